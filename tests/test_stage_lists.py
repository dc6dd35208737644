"""Every list of the stages a reader meets, checked against the registry (``cs451.stages``): the tables of the README,
the overview deck and the docs, and what the command's help names. The tests' own per-stage lists are derived from
the registry where they are defined (test_slides, test_demo_screen, test_demo_warm, test_slide_records), so they
cannot fall behind; these are the lists a person writes, so a test must say when one does.

A list is read with a pattern that finds the stages it names (and their numbers, where it gives them); every
registered stage must be there, under its own number. ``test_a_stage_left_out_is_named`` runs the same check with
one stage more than the registry has, and expects each list to name it as missing: the check can fail.
"""
from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from cs451 import KIT_ROOT
from cs451.stages import get_stage, stage_names

#: (file, what the list is, the pattern of one entry: group "name", and group "number" where the list numbers them)
LISTS = (
    ("README.md", "the table of stages", r"^\| (?P<number>\d+) `(?P<name>\w+)` \|"),
    ("slides/00-overview.md", "the overview deck's table of stages", r"^\| (?P<number>\d+) `(?P<name>\w+)` \|"),
    ("docs/lecturers.md", "the demos' table", r"^\| `(?P<name>\w+)` \| "),
    ("docs/lecturers.md", "the decks' table", r"^\| (?P<name>\w+) \| \d+ \| "),
    ("docs/stages.md", "a section per stage", r"^## Stage (?P<number>\d+): .*\(`(?P<name>\w+)`\)"),
    ("docs/testing.md", "the tests' folders", r"^\| `tests/(?P<name>\w+)/` \|"),
)


def missing(stages: dict[str, int], path: str, pattern: str) -> list[str]:
    """The stages (name → number) a list does not name, or names under another number."""
    regex = re.compile(pattern, re.M)
    found = [m.groupdict() for m in regex.finditer((KIT_ROOT / path).read_text())]
    out = []
    for name, number in stages.items():
        if "name" not in regex.groupindex:                   # a list by number only
            if not any(int(f["number"]) == number for f in found):
                out.append(name)
            continue
        entries = [f for f in found if f["name"] == name]
        if not entries:
            out.append(name)
        elif "number" in regex.groupindex and any(int(f["number"]) != number for f in entries):
            out.append(f"{name} (numbered {entries[0]['number']}, not {number})")
    return out


def registered() -> dict[str, int]:
    return {name: get_stage(name).number for name in stage_names()}


@pytest.mark.parametrize("path, what, pattern", LISTS, ids=[f"{p}: {w}" for p, w, _ in LISTS])
def test_every_list_of_the_stages_names_every_stage(path, what, pattern):
    assert not missing(registered(), path, pattern), f"{path}, {what}: no entry for {missing(registered(), path, pattern)}"


@pytest.mark.parametrize("path, what, pattern", LISTS, ids=[f"{p}: {w}" for p, w, _ in LISTS])
def test_a_stage_left_out_is_named(path, what, pattern):
    """One stage more than the registry holds, numbered after the last: every list misses it (the check can fail;
    tests/test_architecture.py shows it failing on the toy stage before the recipe's lines are added)."""
    stages = registered()
    assert missing({**stages, "unlisted": max(stages.values()) + 1}, path, pattern) == ["unlisted"]


@pytest.mark.spawns
def test_the_command_s_help_names_every_stage_and_every_benchmark():
    from cs451.bench import benches
    said = {command: subprocess.run([str(Path(sys.executable).with_name("cs451")), *command.split(), "--help"],
                                    capture_output=True, text=True, timeout=120).stdout
            for command in ("demo", "bench", "slides build", "render")}
    for stage in stage_names():
        assert stage in said["demo"] and stage in said["slides build"], stage
    for name in benches():
        assert re.search(rf"^\s+{name}\s", said["bench"], re.M), f"cs451 bench --help does not list {name}"
