"""One handout, two readers: the instructor's kit and the student's repository.

A handout (``assignments/<stage>/README.md``) is written once, for the kit. Where the
student's repository differs (it holds the package at its root, has no starter to
copy and no benchmarks), the text says so in two marked blocks::

    <!-- kit -->
    what the kit's reader sees (hidden from the student's copy)
    <!-- /kit -->
    <!-- release
    what the student's copy shows instead (an HTML comment in the kit, so hidden there)
    -->

and a few words change by rule: ``starter/<stage>/`` becomes ``<stage>/``, and
``--impl my-submission`` and ``--submission my-submission`` go (in a student copy
both default to the student's package). :func:`for_release` makes the student's
copy, and refuses one that would still name what a student copy does not have.
"""
from __future__ import annotations

import re

from ..errors import KitError

KIT_BLOCK = re.compile(r"<!-- kit -->\n?(.*?)<!-- /kit -->\n?", re.S)
RELEASE_BLOCK = re.compile(r"<!-- release\n(.*?)-->\n?", re.S)
#: What no student copy may tell its reader to use: it is not there.
KIT_ONLY = ("my-submission", "starter/", "cs451 bench", "--submission reference", "--impl reference")


def check_markers(text: str, where: str) -> None:
    """Every kit block closes, and nothing but a release block opens an HTML comment that holds commands."""
    opens, closes = text.count("<!-- kit -->"), text.count("<!-- /kit -->")
    if opens != closes:
        raise KitError(f"{where}: {opens} '<!-- kit -->' but {closes} '<!-- /kit -->'")
    for block in KIT_BLOCK.findall(text):
        if "<!-- kit -->" in block or "<!-- release" in block:
            raise KitError(f"{where}: a kit block holds another block")


def for_kit(text: str) -> str:
    """What the kit's reader sees: release blocks (HTML comments) blanked, line for line."""
    return RELEASE_BLOCK.sub(lambda m: "\n" * m.group(0).count("\n"), text)


def for_release(text: str, stage: str, where: str = "handout") -> str:
    """The student's copy of a kit handout (or README) for ``stage``."""
    check_markers(text, where)
    out = KIT_BLOCK.sub("", text)
    out = RELEASE_BLOCK.sub(lambda m: m.group(1), out)
    out = out.replace(f"starter/{stage}/", f"{stage}/")
    for words in (" --impl my-submission", " --submission my-submission"):
        out = out.replace(words, "")
    left = [k for k in KIT_ONLY if k in out]
    if left:
        line = next(l for l in out.splitlines() if any(k in l for k in left))
        raise KitError(f"{where}: the student's copy would still say {left[0]!r} (in: {line.strip()[:120]}); "
                       f"put it in a <!-- kit --> block with a <!-- release ... --> alternative")
    return out
