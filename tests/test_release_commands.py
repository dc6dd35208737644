"""Every command a student is told to run works in the student's repository, as written.

Each stage's release (`cs451 release STAGE`) is built in a temporary folder and set up as its README
says: its own ``./setup.sh`` makes ``.venv`` (the kit's engine, installed from this machine's
registries). The commands of its README and handout (lines of ``sh`` code blocks, and inline
``cs451 …`` or ``cp …`` commands with arguments) then run there in order through the release's own
console script (``.venv/bin/cs451``, never ``python -m cs451``), each in a clean environment (only
``HOME`` and a PATH of the release's ``.venv/bin`` and the system's folders, as after ``source
.venv/bin/activate`` in a fresh shell): first with the untouched starter, then with the reference
solution copied into the student's package. With the starter a command may only stop with exit status
2 and "not implemented yet" (``cs451 grade`` with 1 too: a grade under full marks); with the solution
every command exits 0, writes the files it names, and every ``cs451 grade`` gives every public point. Every handout figure's "compare with the figure"
recipe is run for every figure of the stage. A stage that draws with an earlier stage's package gets
the student's finished one from where its README's ``cp`` command takes it. The fast suite checks every
stage's commands and paths without running them; the slow and seat runs (CI: ``-m seat``) run every
stage's, stage 1's included (each costs minutes: CI runs them once, not again in every fast suite).
"""
from __future__ import annotations

import json
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from cs451 import KIT_ROOT
from cs451.packaging.release import build_release, earlier_source
from cs451.stages import stage_names
from cs451.stages import get_stage

from conftest import set_up_release, world_readable_dir
from seats.measured import FOLDER, record

SKIPPED = ("./setup.sh", "source .venv/bin/activate")   # set-up: set_up_release runs it, and the PATH it gives
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
    for earlier in get_stage(stage).builds_on:   # the student's finished earlier stage, in its own repository
        source = (release / earlier_source(earlier)).resolve() / earlier
        shutil.copytree(KIT_ROOT / "reference" / earlier, source, ignore=shutil.ignore_patterns("__pycache__"))
    return release


def outputs_named(command: str) -> list[str]:
    words = shlex.split(command)
    return [words[i + 1] for i, w in enumerate(words[:-1]) if w in ("-o", "--output", "--report")]


def run(command: str, release: Path, env: dict) -> subprocess.CompletedProcess:
    """One command as the student types it, in their shell's clean environment."""
    return subprocess.run(command, shell=True, cwd=release, env=env, capture_output=True, text=True, timeout=1200)


def full_marks(said: str) -> bool:
    """The grade's table ends with ``total: X / Y``; every public point is X == Y > 0."""
    total = re.search(r"^total: ([\d.]+) / ([\d.]+)", said, flags=re.M)
    return total is not None and float(total.group(1)) == float(total.group(2)) > 0


def run_all(release: Path, env: dict, solved: bool) -> list[str]:
    problems = []
    stage = json.loads((release / "cs451-release.json").read_text())["stage"]
    for command in commands_in(student_texts(release, stage)):
        done = run(command, release, env)
        said = done.stdout + done.stderr
        if "Traceback" in said:
            problems.append(f"{command}: a traceback: {said[-800:]}")
        elif solved and done.returncode != 0:
            problems.append(f"{command}: exit {done.returncode}: {said[-600:]}")
        elif not solved and done.returncode not in ((0, 1, 2) if command.startswith("cs451 grade") else (0, 2)):
            problems.append(f"{command}: exit {done.returncode} with the starter: {said[-600:]}")
        elif not solved and done.returncode == 2 and "not implemented yet" not in said:
            problems.append(f"{command}: exit 2 with the starter, but not for an unwritten function: {said[-600:]}")
        elif solved and command.startswith(f"cs451 grade {stage}") and not full_marks(done.stdout):
            problems.append(f"{command}: not every public point for the solution: {said[-1500:]}")
        elif done.returncode in (0, 1):     # 1: the starter's grade, its report written all the same
            missing = [o for o in outputs_named(command) if not (release / o).exists()]
            if missing:
                problems.append(f"{command}: wrote no {missing}")
    return problems


def figure_recipes(release: Path, stage: str) -> list[str]:
    """The handout's "compare with the figure" command line, for every figure the release ships (the handout gives
    it for one figure and says to put another's number in both places); none for a stage without image tests."""
    handout = release / "assignments" / get_stage(stage).handout
    recipe = [c for c in commands_in(student_texts(release, stage)) if "--figure" in c]
    figures = sorted(p.stem for p in (handout / "figures").glob("*.png"))
    if not figures and not recipe:
        return []                    # stage 5: no image test, so no figure to compare with
    assert len(recipe) == 1 and figures, f"{handout}: one figure recipe and its figures, got {recipe} {figures}"
    example = re.search(r"--figure (\S+)", recipe[0]).group(1)
    assert example in figures
    return [recipe[0].replace(example, number) for number in figures]


def figure_problems(release: Path, stage: str, env: dict, solved: bool) -> list[str]:
    problems = []
    for command in figure_recipes(release, stage):
        done = run(command, release, env)
        said = done.stdout + done.stderr
        if solved and (done.returncode != 0 or " matches " not in done.stdout):
            problems.append(f"{command}: exit {done.returncode} with the solution: {said[-800:]}")
        elif not solved and (done.returncode != 2 or "not implemented yet" not in said or "Traceback" in said):
            problems.append(f"{command}: exit {done.returncode} with the starter, not a clear 'not implemented yet': "
                            f"{said[-800:]}")
    return problems


def solve(release: Path, stage: str) -> None:
    shutil.rmtree(release / stage)
    shutil.copytree(KIT_ROOT / "reference" / stage, release / stage, ignore=shutil.ignore_patterns("__pycache__"))


STAGES = stage_names()


@pytest.mark.spawns
@pytest.mark.parametrize("stage", STAGES)
def test01_every_command_and_path_a_student_reads_exists_there(stage, tmp_path):
    release = make_release(stage, tmp_path)
    text = student_texts(release, stage)
    commands = commands_in(text)
    assert any(c.startswith(f"cs451 grade {stage}") for c in commands) and any(c.startswith("cs451 render") for c in commands)
    for kit_only in ("my-submission", "starter/", "cs451 bench", "--impl reference"):
        assert kit_only not in text, kit_only
    for command in commands:
        for part in command.split("&&"):
            words = shlex.split(part)
            if words[0] in ("cp", "mkdir"):     # the student's own copies (an earlier stage's package, a scene)
                assert subprocess.run(part, shell=True, cwd=release).returncode == 0, part
            if words[0] != "cs451" or "--help" in words:
                continue
            parsed = subprocess.run([sys.executable, "-c", "import sys; from cs451.cli import build_parser; "
                                     "build_parser().parse_args(sys.argv[1:])", *words[1:]],
                                    cwd=release, capture_output=True, text=True)   # the release's own parser
            assert parsed.returncode == 0, f"{part}: {parsed.stderr.strip()}"
    tops = ("cs451/", "autograder/", "assignments/", "reference/", ".github/", f"{stage}/",
            *(f"{s}/" for s in get_stage(stage).builds_on))
    paths = {t.strip("`'\"(),.") for t in re.findall(r"`([^`\s]+/[^`\s]*)`", text)}
    missing = [p for p in paths if p.startswith(tops) and "*" not in p and not (release / p.split("#")[0]).exists()]
    assert not missing, f"paths the student's copy names but does not hold: {missing}"


#: The students' home folder, shared by every release's set-up and kept between runs: pip's cache of downloaded
#: wheels lives there, so five releases (and the next CI run) download them once. Each release still makes its own
#: .venv and installs every package into it, as a student's set-up does.
RELEASE_HOME = FOLDER / "release-home"


def _run_stage(stage: str, top: Path) -> None:
    release = make_release(stage, top)
    env = set_up_release(release, RELEASE_HOME)
    assert run_all(release, env, solved=False) == []
    assert figure_problems(release, stage, env, solved=False) == []
    solve(release, stage)
    assert run_all(release, env, solved=True) == []
    assert figure_problems(release, stage, env, solved=True) == []
    graded = run(f"cs451 grade {stage} --results results.json", release, env)
    results = json.loads((release / "results.json").read_text())
    points = sum(t["max_score"] for t in results["tests"])
    assert graded.returncode == 0 and results["score"] == points > 0, graded.stdout[-3000:] + graded.stderr[-2000:]
    record("releases", {stage: {"finished_student": f"{results['score']:g}/{points:g} public points, exit 0"}})


@pytest.mark.spawns
@pytest.mark.slow
@pytest.mark.seat
@pytest.mark.parametrize("stage", STAGES)
def test03_every_stage_s_commands_work_with_the_starter_and_with_a_solution(stage):
    top = world_readable_dir("cs451-release-run-")
    try:
        _run_stage(stage, top)
    finally:
        shutil.rmtree(top, ignore_errors=True)
