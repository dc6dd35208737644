"""Which copy of the kit this is: the instructor's kit, or a student's repository made by ``cs451 release``.

The two run the same engine; what differs is where the student's package is and
which commands make sense. A student copy says so in ``cs451-release.json`` at its
root (written by ``cs451 release``), naming its stage.
"""
from __future__ import annotations

import json
from functools import lru_cache

from . import KIT_ROOT

MARKER = "cs451-release.json"


@lru_cache(maxsize=1)
def student_stage() -> str | None:
    """The stage of this student copy, or None in the instructor's kit."""
    path = KIT_ROOT / MARKER
    if not path.is_file():
        return None
    try:
        return str(json.loads(path.read_text())["stage"])
    except (ValueError, KeyError, TypeError, OSError):
        return None


def default_impl() -> str:
    """What ``--impl`` and ``--submission`` mean when not given: the student's own package in a student copy
    (the repository's root holds it), the kit's reference for ``render`` and ``demo`` in the instructor's kit."""
    return str(KIT_ROOT) if student_stage() else "reference"


def default_submission() -> str:
    """What ``cs451 grade`` grades when not told: the student's package in a student copy, the starter in the kit."""
    return str(KIT_ROOT) if student_stage() else "starter"
