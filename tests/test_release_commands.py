"""Every command a student is told to run works in the student's repository, as written.

Each stage's release (`cs451 release STAGE`) is built in a temporary folder; the commands of its
README and handout (lines of ``sh`` code blocks, and inline ``cs451 …`` or ``cp …`` commands with
arguments) are run there in order, first with the untouched starter and then with the reference
solution copied into the student's package. With the starter a command may only stop with exit
status 2 and "not implemented yet"; with the solution every command exits 0 and writes the files it
names. A command added to a handout without working fails here. The fast suite runs them for stage 1
and checks every stage's commands and paths without running them; the slow one runs them all, and
runs a release's own ``setup.sh`` in a fresh virtual environment.
"""
from __future__ import annotations

import json
import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from cs451 import KIT_ROOT
from cs451.packaging.release import build_release
from cs451.stages import stage_names
from cs451.stages import get_stage

from conftest import world_readable_dir

SKIPPED = ("./setup.sh", "source .venv/bin/activate")   # set-up: the slow test runs it for real
COMMAND_WORDS = ("cs451 ", "cp ", "mkdir ")


def commands_in(markdown: str) -> list[str]:
    """The commands a text tells its reader to run, in order."""
    found, fence = [], None
    for line in markdown.splitlines():
        opening = re.match(r"^\s*(```+)\s*(\w*)", line)
        if fence is None and opening:
            fence = opening.group(2) or "text"
            continue
        if fence is not None and line.strip().startswith("```"):
            fence = None
            continue
        if fence in ("sh", "bash", "console"):
            command = line.split(" #")[0].strip()
            if command and not command.startswith("#"):
                found.append(command)
        elif fence is None:
            for span in re.findall(r"`([^`]+)`", line):
                words = span.split()
                if span.startswith(COMMAND_WORDS) and len(words) > (2 if words[0] == "cs451" else 1):
                    found.append(span)
    return [c for c in found if not c.startswith(SKIPPED)]


def student_texts(release: Path, stage: str) -> str:
    return (release / "README.md").read_text() + "\n" + \
        (release / "assignments" / get_stage(stage).handout / "README.md").read_text()


def make_release(stage: str, top: Path) -> Path:
    release = build_release(stage, top / "repo")
    for earlier in get_stage(stage).builds_on:   # the student's own earlier stage, copied in as the handout says
        shutil.copytree(KIT_ROOT / "reference" / earlier, release / earlier, ignore=shutil.ignore_patterns("__pycache__"))
    return release


def cs451_on_path(top: Path) -> dict[str, str]:
    """``cs451`` as the release's own command: this Python, run in the release (its engine comes first)."""
    bin_dir = top / "bin"
    bin_dir.mkdir(exist_ok=True)
    shim = bin_dir / "cs451"
    shim.write_text(f'#!/bin/sh\nexec {shlex.quote(sys.executable)} -m cs451 "$@"\n')
    shim.chmod(0o755)
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    return {**env, "PATH": f"{bin_dir}:{os.environ['PATH']}"}


def outputs_named(command: str) -> list[str]:
    words = shlex.split(command)
    return [words[i + 1] for i, w in enumerate(words[:-1]) if w in ("-o", "--output", "--report")]


def run_all(release: Path, env: dict, solved: bool) -> list[str]:
    problems = []
    stage = json.loads((release / "cs451-release.json").read_text())["stage"]
    for command in commands_in(student_texts(release, stage)):
        done = subprocess.run(command, shell=True, cwd=release, env=env, capture_output=True, text=True, timeout=900)
        said = done.stdout + done.stderr
        if "Traceback" in said:
            problems.append(f"{command}: a traceback: {said[-800:]}")
        elif solved and done.returncode != 0:
            problems.append(f"{command}: exit {done.returncode}: {said[-600:]}")
        elif not solved and done.returncode not in (0, 2):
            problems.append(f"{command}: exit {done.returncode} with the starter: {said[-600:]}")
        elif not solved and done.returncode == 2 and "not implemented yet" not in said:
            problems.append(f"{command}: exit 2 with the starter, but not for an unwritten function: {said[-600:]}")
        elif done.returncode == 0:
            missing = [o for o in outputs_named(command) if not (release / o).exists()]
            if missing:
                problems.append(f"{command}: wrote no {missing}")
    return problems


def solve(release: Path, stage: str) -> None:
    shutil.rmtree(release / stage)
    shutil.copytree(KIT_ROOT / "reference" / stage, release / stage, ignore=shutil.ignore_patterns("__pycache__"))


STAGES = stage_names()


@pytest.mark.parametrize("stage", STAGES)
def test01_every_command_and_path_a_student_reads_exists_there(stage, tmp_path):
    release = make_release(stage, tmp_path)
    text = student_texts(release, stage)
    commands = commands_in(text)
    assert any(c.startswith(f"cs451 grade {stage}") for c in commands) and any(c.startswith("cs451 render") for c in commands)
    for kit_only in ("my-submission", "starter/", "cs451 bench", "--impl reference"):
        assert kit_only not in text, kit_only
    env = cs451_on_path(tmp_path)
    for command in commands:
        words = shlex.split(command)
        if words[0] != "cs451" or "--help" in words:
            continue
        parsed = subprocess.run([sys.executable, "-c", "import sys; from cs451.cli import build_parser; "
                                 "build_parser().parse_args(sys.argv[1:])", *words[1:]],
                                cwd=release, env=env, capture_output=True, text=True)
        assert parsed.returncode == 0, f"{command}: {parsed.stderr.strip()}"
    tops = ("cs451/", "autograder/", "assignments/", "reference/", ".github/", f"{stage}/",
            *(f"{s}/" for s in get_stage(stage).builds_on))
    paths = {t.strip("`'\"(),.") for t in re.findall(r"`([^`\s]+/[^`\s]*)`", text)}
    missing = [p for p in paths if p.startswith(tops) and "*" not in p and not (release / p.split("#")[0]).exists()]
    assert not missing, f"paths the student's copy names but does not hold: {missing}"


def _run_stage(stage: str, top: Path) -> None:
    release = make_release(stage, top)
    env = cs451_on_path(top)
    assert run_all(release, env, solved=False) == []
    solve(release, stage)
    assert run_all(release, env, solved=True) == []
    graded = subprocess.run(["cs451", "grade", stage, "--results", "results.json"], cwd=release, env=env,
                            capture_output=True, text=True, timeout=900)
    results = json.loads((release / "results.json").read_text())
    assert graded.returncode == 0 and results["score"] == sum(t["max_score"] for t in results["tests"]) > 0


def test02_stage_1_commands_work_with_the_starter_and_with_a_solution():
    top = world_readable_dir("cs451-release-run-")
    try:
        _run_stage("sphere", top)
    finally:
        shutil.rmtree(top, ignore_errors=True)


@pytest.mark.slow
@pytest.mark.parametrize("stage", STAGES[1:])
def test03_every_stage_s_commands_work_with_the_starter_and_with_a_solution(stage):
    top = world_readable_dir("cs451-release-run-")
    try:
        _run_stage(stage, top)
    finally:
        shutil.rmtree(top, ignore_errors=True)


@pytest.mark.slow
def test04_the_release_s_own_setup_makes_a_working_environment():
    """The student's first command, for real: setup.sh makes .venv, and its cs451 renders and grades."""
    top = world_readable_dir("cs451-release-setup-")
    try:
        release = make_release("sphere", top)
        done = subprocess.run(["./setup.sh"], cwd=release, capture_output=True, text=True, timeout=1500)
        assert done.returncode == 0, done.stderr[-2000:]
        solve(release, "sphere")
        render = subprocess.run([".venv/bin/cs451", "render", "sphere", "-o", "mine.png"], cwd=release,
                                capture_output=True, text=True, timeout=600)
        assert render.returncode == 0 and (release / "mine.png").exists(), render.stderr
    finally:
        shutil.rmtree(top, ignore_errors=True)
