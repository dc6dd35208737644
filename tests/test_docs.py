"""The README stays a front door (what the kit is, the two commands, where to go next) and every link in it and
in ``docs/`` leads somewhere: a moved section leaves no dead link behind."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

from cs451 import KIT_ROOT

README_MAX_LINES = 120
LINK = re.compile(r"\]\(([^)\s]+)\)")
PAGES = [KIT_ROOT / "README.md", KIT_ROOT / "slides" / "README.md", *sorted((KIT_ROOT / "docs").glob("*.md"))]


def prose(page: Path) -> str:
    """A page without its code (fenced blocks and inline spans), where ``](…)`` is an example, not a link."""
    text = re.sub(r"^(`{3,}).*?^\1", "", page.read_text(), flags=re.M | re.S)
    return re.sub(r"`[^`\n]*`", "", text)


def anchors(page: Path) -> set[str]:
    """GitHub's anchors of a page's headings: lower case, punctuation dropped, spaces as hyphens."""
    heads = re.findall(r"^#+ (.+)$", page.read_text(), re.M)
    return {re.sub(r"[^\w\- ]", "", h.strip().lower()).replace(" ", "-") for h in heads}


def test_the_readme_is_short_enough_to_read_first():
    lines = (KIT_ROOT / "README.md").read_text().splitlines()
    assert len(lines) <= README_MAX_LINES, f"README.md has {len(lines)} lines; move detail to docs/"


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(KIT_ROOT)))
def test_every_relative_link_leads_to_a_file_and_heading_that_exist(page):
    dead = []
    for target in LINK.findall(prose(page)):
        if target.startswith(("http://", "https://", "mailto:")):
            continue
        path, _, anchor = target.partition("#")
        file = (page.parent / path).resolve() if path else page
        if not file.exists():
            dead.append(f"{target}: no such file")
        elif anchor and file.suffix == ".md" and anchor not in anchors(file):
            dead.append(f"{target}: no heading #{anchor} in {file.name}")
    assert not dead, f"{page.relative_to(KIT_ROOT)}: " + "; ".join(dead)
