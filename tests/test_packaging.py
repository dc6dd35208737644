"""The Gradescope zip and the students' repository, run as the platforms run them.

The zip is unpacked into Gradescope's layout (``autograder/source``, ``submission``,
``results``), its own ``setup.sh`` moves the kit to ``opt/cs451-kit`` (as it does to
``/opt`` on Gradescope), and its own ``run_autograder`` grades the upload. The student
repository is checked for what it must not hold (the reference, hidden tests, truths)
and graded with the commands its GitHub workflow runs.
"""
from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from cs451 import KIT_ROOT
from cs451.grading.loader import load_tests
from cs451.grading.results import total_score
from cs451.packaging.release import build_release

from conftest import clean_env, world_readable_dir
from hidden_host import hiding_host

STAGE = "sphere"
TESTS = load_tests(STAGE)
HIDDEN = [t for t in TESTS if t.hidden]
PUBLIC_POINTS = sum(t.points for t in TESTS if not t.hidden and not t.extension)   # the grade's: no extension
HIDDEN_NOTE = f"{len(HIDDEN)} hidden tests ({sum(t.points for t in HIDDEN):g} points)"   # as the report counts them


def run_autograder(layout: tuple[Path, dict], files: Path | None, *args: str) -> dict:
    """Put an upload in submission/, run the zip's run_autograder as Gradescope does, return results.json."""
    root, env = layout
    for sub in ("submission", "results"):
        shutil.rmtree(root / sub, ignore_errors=True)
        (root / sub).mkdir()
    if files is not None:  # as uploaded: links, FIFOs and modes kept
        subprocess.run(["cp", "-a", f"{files}/.", str(root / "submission")], check=True)
    command = [str(root / "source" / "run_autograder"), *args]
    if env.get("CS451_SANDBOX") == "uid":   # as on a server, where no other copy of the kit is readable
        command = hiding_host(command, [root.parent])
    done = subprocess.run(command, env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    return json.loads((root / "results" / "results.json").read_text())


def test01_setup_moves_the_kit_out_of_reach_and_leaves_source_empty(gradescope):
    root, env = gradescope
    kit = Path(env["CS451_HOME"])
    assert sorted(p.name for p in (root / "source").iterdir()) == ["run_autograder", "setup.sh"]
    assert (root / "source").stat().st_mode & 0o077 == 0
    assert kit.stat().st_mode & 0o777 == 0o711
    for private in ("reference", "autograder", "cs451", ".cs451-cache", "autograder.json"):
        assert (kit / private).exists() and (kit / private).stat().st_mode & 0o007 == 0, private
    assert (kit / "reference" / STAGE / "__init__.py").exists() and (kit / "autograder" / STAGE / "hidden.py").exists()
    kept = [p for p in kit.rglob("*") if ".venv" not in p.relative_to(kit).parts]
    names = {p.relative_to(kit).as_posix() for p in kept}
    assert not [n for n in names if n.startswith(("starter/", "tests/", "bench/"))]
    readable = [p.relative_to(kit).as_posix() for p in kept if p.stat().st_mode & 0o007]
    assert not readable, f"left readable to the worker (bytecode of the warm-up included): {readable[:5]}"
    setup = (kit / "setup.sh").read_text()
    assert "libegl-mesa0" in setup and "bubblewrap" in setup and f"autograder warm {STAGE}" in setup


@pytest.mark.spawns
def test02_reference_upload_gets_full_marks_with_gradescope_fields(gradescope):
    results = run_autograder(gradescope, KIT_ROOT / "reference")  # an upload holding the sphere/ folder
    assert total_score(results) == pytest.approx(100)
    assert results["output_format"] == "html" and HIDDEN_NOTE in results["output"]
    assert "bubblewrap" in results["output"] or "throwaway user" in results["output"]
    hidden = [t for t in results["tests"] if t["visibility"] == "after_published"]
    assert len(hidden) == len(HIDDEN) and all(t["status"] == "passed" for t in results["tests"])
    assert {"score", "max_score", "name", "number", "output", "tags"} <= set(results["tests"][0])


@pytest.mark.spawns
def test03_starter_files_uploaded_loose_get_zero_with_hints(gradescope):
    loose = world_readable_dir("cs451-upload-")
    for f in (KIT_ROOT / "starter" / STAGE).glob("*.py"):
        shutil.copy(f, loose / f.name)  # a student who dragged the files, not the folder
    results = run_autograder(gradescope, loose)
    shutil.rmtree(loose)
    assert total_score(results) == 0 and len(results["tests"]) == len(TESTS)
    assert all("not implemented yet" in t["output"] for t in results["tests"])


@pytest.mark.spawns
def test04_a_whole_repository_upload_is_found_and_an_empty_one_is_explained(gradescope):
    repo = world_readable_dir("cs451-upload-")
    shutil.copytree(KIT_ROOT / "reference" / STAGE, repo / "my-repo" / "starter" / STAGE)
    results = run_autograder(gradescope, repo)
    shutil.rmtree(repo)
    assert total_score(results) == pytest.approx(100)
    empty = run_autograder(gradescope, None)
    assert empty["score"] == 0 and empty["output"].startswith("Your submission could not be graded")
    assert f"no '{STAGE}' package" in empty["output"] and "/autograder/submission" in empty["output"].replace(
        str(gradescope[0]), "/autograder")


@pytest.mark.spawns
@pytest.mark.skipif(os.geteuid() != 0, reason="Gradescope runs as root; its sandbox user needs it")
def test04b_a_submission_cannot_write_the_results(gradescope):
    upload = world_readable_dir("cs451-upload-")
    shutil.copytree(KIT_ROOT / "reference" / STAGE, upload / STAGE)
    camera = upload / STAGE / "camera.py"
    forged = gradescope[0] / "results" / "results.json"
    camera.write_text(camera.read_text().replace(
        "    f = 1.0 / np.tan(", f"    open({str(forged)!r}, 'w').write('{{\"score\": 1000}}')\n"
                                 "    f = 1.0 / np.tan(", 1))
    results = run_autograder(gradescope, upload)
    shutil.rmtree(upload)
    s1 = [t for t in results["tests"] if t["tags"] == ["S1"]]
    assert all(t["score"] == 0 and ("Permission denied" in t["output"] or "No such file" in t["output"]) for t in s1)
    assert len(results["tests"]) == len(TESTS) and total_score(results) == pytest.approx(sum(t["score"] for t in results["tests"]))
    assert all(t["status"] == "passed" for t in results["tests"] if t["tags"][0] in ("S2", "S3", "S4", "S5", "S6", "S8"))


@pytest.fixture(scope="module")
def release(request) -> Path:
    out = world_readable_dir("cs451-release-") / "repo"
    request.addfinalizer(lambda: shutil.rmtree(out.parent, ignore_errors=True))
    return build_release(STAGE, out)


def test05_student_repository_holds_no_solution_no_hidden_test_and_no_truth(release):
    files = {p.relative_to(release).as_posix() for p in release.rglob("*") if p.is_file()}
    assert not [f for f in files if f.startswith("reference/") or f.endswith(("hidden.py", "truth.py", "public.py"))]
    spec = {f for f in files if f.startswith(f"autograder/{STAGE}/") and "/answers/" not in f}
    assert spec == {f"autograder/{STAGE}/{n}" for n in ("__init__.py", "checks.py", "public.json", "hidden.json")}
    assert f"{STAGE}/camera.py" in files and ".github/workflows/classroom.yml" in files
    assert (release / STAGE / "camera.py").read_text() == (KIT_ROOT / "starter" / STAGE / "camera.py").read_text()
    assert json.loads((release / "autograder" / STAGE / "hidden.json").read_text())["count"] == len(HIDDEN)
    answers = list((release / "autograder" / STAGE / "answers").glob("*.npz"))
    assert answers and all(a.name.startswith(("render-", "parts-", "reshape_parts-", "truth-")) for a in answers)
    manifest = json.loads((release / "autograder" / STAGE / "public.json").read_text())
    assert len(manifest["tests"]) == len(TESTS) - len(HIDDEN) and all(t["check"]["module"].endswith(".checks") for t in manifest["tests"])
    setup = (release / "setup.sh").read_text()
    assert "main job" not in setup and "cs451 render" not in setup and "-e .   # the kit's engine" in setup and "[dev" not in setup


def workflow_commands(workflow: Path) -> list[str]:
    """The shell commands the workflow runs after setup, in order (run: and command: lines)."""
    return re.findall(r"^\s+(?:run|command): (.+)$", workflow.read_text(), flags=re.M)


def run_workflow(release: Path) -> list[int]:
    """The workflow's commands as written (its ./setup.sh first, which makes .venv), each in a clean environment as a
    fresh runner's shell has: nothing of this machine's, no virtual environment activated."""
    codes = []
    env = clean_env(release.parent / "home")
    for command in workflow_commands(release / ".github" / "workflows" / "classroom.yml"):
        done = subprocess.run(command, shell=True, cwd=release, env=env, capture_output=True, text=True, timeout=1800)
        assert command != "./setup.sh" or done.returncode == 0, done.stderr[-3000:]
        codes.append(done.returncode)
    return codes


@pytest.mark.spawns
def test06_the_workflow_grades_the_starter_zero_and_a_solution_full(release):
    text = (release / ".github" / "workflows" / "classroom.yml").read_text()
    assert "python -m" not in text and workflow_commands(release / ".github" / "workflows" / "classroom.yml")[1] \
        .startswith(f".venv/bin/cs451 grade {STAGE} ")   # the console script the student types, not python -m
    codes = run_workflow(release)
    assert codes[:2] == [0, 0] and all(c == 1 for c in codes[2:]) and len(codes) == 2 + 8  # set-up, grading, one per task
    results = json.loads((release / "results.json").read_text())
    assert results["score"] == 0 and not [t for t in results["tests"] if t["visibility"] != "visible"]
    for f in (KIT_ROOT / "reference" / STAGE).glob("*.py"):
        shutil.copy(f, release / STAGE / f.name)
    codes = run_workflow(release)
    assert codes == [0] * 10
    results = json.loads((release / "results.json").read_text())
    assert results["score"] == pytest.approx(PUBLIC_POINTS)  # from the packaged answers
    report = (release / "report" / "report.html").read_text()
    assert f"{HIDDEN_NOTE}, run after the deadline" in report


def test07_workflow_points_add_up_to_the_public_tests(release):
    text = (release / ".github" / "workflows" / "classroom.yml").read_text()
    assert sum(float(p) for p in re.findall(r"max-score: ([\d.]+)", text)) == PUBLIC_POINTS
    assert text.count("_RESULTS:") == 8


@pytest.mark.spawns
@pytest.mark.skipif(shutil.which("git") is None, reason="needs git")
def test08_git_keeps_every_file_of_the_release_and_ignores_only_what_its_commands_write(tmp_path):
    """A student commits the release as it is (`git add -A`): every file it ships is kept (the handout's figures
    above all), and what set-up and the README's and handout's commands write is not."""
    out = build_release(STAGE, tmp_path / "repo")
    shipped = sorted(p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file())
    assert [f for f in shipped if f.startswith("assignments/") and f.endswith(".png")], "no figures to keep"
    subprocess.run(["git", "init", "-q"], cwd=out, check=True)

    def ignored(paths: list[str]) -> set[str]:
        done = subprocess.run(["git", "check-ignore", "--no-index", "--stdin"], cwd=out, input="\n".join(paths),
                              capture_output=True, text=True)
        assert done.returncode in (0, 1), done.stderr
        return set(done.stdout.split())
    assert ignored(shipped) == set()
    written = ["mine.png", "S5.1-mine.png", "S5.1-compare.png", "compare.png", "orrery.png", "report/report.html",
               "results.json", "demo/sphere-gouraud.png", ".venv/bin/python", f"{STAGE}/__pycache__/camera.cpython-311.pyc",
               "cs451/__pycache__/cli.cpython-311.pyc", "cs451_kit.egg-info/PKG-INFO", ".cs451-cache/answers.npz"]
    assert ignored(written) == set(written)
    kept = ["assignments/01-sphere/figures/S9.9.png", "assignments/01-sphere/diagrams/new.png", f"{STAGE}/texture.png",
            "my-scene.json"]
    assert ignored(kept) == set()


def test09_an_earlier_stage_reference_ships_only_when_asked(tmp_path):
    from cs451.errors import KitError
    from cs451.stages import get_stage
    out = build_release("radiosity", tmp_path / "repo", include_reference=("hemicube",))
    shipped = {p.relative_to(out / "reference").parts[0] for p in (out / "reference").rglob("*.py")}
    assert shipped == set(get_stage("radiosity").builds_on) == {"hemicube"}
    with pytest.raises(KitError, match="builds on"):
        build_release("radiosity", tmp_path / "other", include_reference=("radiosity",))


def test10_a_release_that_draws_with_an_earlier_stage_says_how_to_copy_the_student_s_own_in(tmp_path, capsys):
    """Stage 4 draws with a stage-3 hemicube: without --include-reference hemicube its release holds none, so
    `cs451 release` warns and the release's README gives the command that copies the student's own package in
    (tests/test_release_commands.py runs that command, then every render)."""
    from cs451.cli import main
    command = "cp -r ../your-hemicube-repository/hemicube ."
    assert main(["release", "radiosity", "-o", str(tmp_path / "own")]) == 0
    said = capsys.readouterr().err
    assert "warning: stage radiosity draws with a stage-3 (hemicube) implementation and this release ships none" in said
    assert command in said and "--include-reference hemicube" in said
    readme = (tmp_path / "own" / "README.md").read_text()
    assert f"```sh\n{command}\n```" in readme and readme.index(command) < readme.index("cs451 render cornell-box")
    assert main(["release", "radiosity", "-o", str(tmp_path / "with"), "--include-reference", "hemicube"]) == 0
    said = capsys.readouterr().err
    assert "ships none" not in said and "the reference solution of hemicube" in said
    assert "your-hemicube-repository" not in (tmp_path / "with" / "README.md").read_text()
    assert main(["release", "sphere", "-o", str(tmp_path / "sphere")]) == 0
    assert "warning" not in capsys.readouterr().err
    assert "Before you render" not in (tmp_path / "sphere" / "README.md").read_text()
