"""The Gradescope zip and the students' repository, run as the platforms run them.

The zip is unpacked into a layout like Gradescope's (``autograder/source``,
``submission``, ``results``) and its own ``run_autograder`` grades the upload.
The student repository is checked for what it must not hold (the reference,
hidden tests) and graded with the commands its GitHub workflow runs.
"""
from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

from cs451 import KIT_ROOT
from cs451.packaging.gradescope import build_gradescope, simulated_env, unpack_like_gradescope
from cs451.packaging.release import build_release

STAGE = "sphere"


def world_readable_dir(prefix: str) -> Path:
    """A scratch folder the grader's unprivileged worker can enter (pytest's tmp_path is private to root)."""
    path = Path(tempfile.mkdtemp(prefix=prefix))
    os.chmod(path, 0o755)
    return path


@pytest.fixture(scope="module")
def gradescope(request) -> Path:
    """An unpacked autograder in a Gradescope-like layout, its reference answers warmed as setup.sh does."""
    top = world_readable_dir("cs451-gs-")
    request.addfinalizer(lambda: shutil.rmtree(top, ignore_errors=True))
    root = unpack_like_gradescope(build_gradescope(STAGE, top / "autograder.zip"), top)
    subprocess.run([sys.executable, "-m", "cs451", "autograder", "warm", STAGE], cwd=root / "source",
                   check=True, capture_output=True)
    return root


def run_autograder(root: Path, files: dict[str, Path] | Path | None) -> dict:
    """Put an upload in submission/, run the zip's run_autograder, return results.json."""
    for sub in ("submission", "results"):
        shutil.rmtree(root / sub, ignore_errors=True)
        (root / sub).mkdir()
    if isinstance(files, Path):
        shutil.copytree(files, root / "submission", dirs_exist_ok=True)
    done = subprocess.run([str(root / "source" / "run_autograder")], env=simulated_env(root, sys.executable), capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr
    return json.loads((root / "results" / "results.json").read_text())


def test01_zip_holds_setup_run_and_reference_but_no_litter(gradescope):
    names = {p.relative_to(gradescope / "source").as_posix() for p in (gradescope / "source").rglob("*")}
    assert {"setup.sh", "run_autograder", "autograder.json", f"reference/{STAGE}/__init__.py",
            f"autograder/{STAGE}/hidden.py"} <= names
    assert not [n for n in names if "__pycache__" in n or n.startswith(("starter/", "tests/", ".venv"))]
    setup = (gradescope / "source" / "setup.sh").read_text()
    assert "libegl-mesa0" in setup and f"autograder warm {STAGE}" in setup


def test02_reference_upload_gets_full_marks_with_gradescope_fields(gradescope):
    results = run_autograder(gradescope, KIT_ROOT / "reference")  # an upload holding the sphere/ folder
    assert results["score"] == pytest.approx(100)
    assert results["output_format"] == "html" and "9 hidden tests (40 points)" in results["output"]
    hidden = [t for t in results["tests"] if t["visibility"] == "after_published"]
    assert len(hidden) == 9 and all(t["status"] == "passed" for t in results["tests"])
    assert {"score", "max_score", "name", "number", "output", "tags"} <= set(results["tests"][0])


def test03_starter_files_uploaded_loose_get_zero_with_hints(gradescope):
    loose = world_readable_dir("cs451-upload-")
    for f in (KIT_ROOT / "starter" / STAGE).glob("*.py"):
        shutil.copy(f, loose / f.name)  # a student who dragged the files, not the folder
    results = run_autograder(gradescope, loose)
    shutil.rmtree(loose)
    assert results["score"] == 0 and len(results["tests"]) == 21
    assert all("not implemented yet" in t["output"] for t in results["tests"])


def test04_a_whole_repository_upload_is_found_and_an_empty_one_is_explained(gradescope):
    repo = world_readable_dir("cs451-upload-")
    shutil.copytree(KIT_ROOT / "reference" / STAGE, repo / "my-repo" / "starter" / STAGE)
    results = run_autograder(gradescope, repo)
    shutil.rmtree(repo)
    assert results["score"] == pytest.approx(100)
    empty = run_autograder(gradescope, None)
    assert empty["score"] == 0 and empty["output"].startswith("Your submission could not be graded")
    assert f"no '{STAGE}' package" in empty["output"]


@pytest.mark.skipif(os.geteuid() != 0, reason="Gradescope runs as root; the worker's drop to 'nobody' needs it")
def test04b_a_submission_cannot_write_the_results(gradescope):
    upload = world_readable_dir("cs451-upload-")
    shutil.copytree(KIT_ROOT / "reference" / STAGE, upload / STAGE)
    camera = upload / STAGE / "camera.py"
    forged = gradescope / "results" / "results.json"
    camera.write_text(camera.read_text().replace(
        "    f = 1.0 / np.tan(", f"    open({str(forged)!r}, 'w').write('{{\"score\": 1000}}')\n"
                                 "    f = 1.0 / np.tan(", 1))
    results = run_autograder(gradescope, upload)
    shutil.rmtree(upload)
    s1 = [t for t in results["tests"] if t["tags"] == ["S1"]]
    assert all(t["score"] == 0 and "Permission denied" in t["output"] for t in s1)
    assert len(results["tests"]) == 21 and results["score"] == pytest.approx(sum(t["score"] for t in results["tests"]))
    assert all(t["status"] == "passed" for t in results["tests"] if t["tags"][0] in ("S2", "S3", "S4", "S5", "S7"))


@pytest.fixture(scope="module")
def release(request) -> Path:
    out = world_readable_dir("cs451-release-") / "repo"
    request.addfinalizer(lambda: shutil.rmtree(out.parent, ignore_errors=True))
    return build_release(STAGE, out)


def test05_student_repository_holds_no_solution_and_no_hidden_test(release):
    files = {p.relative_to(release).as_posix() for p in release.rglob("*") if p.is_file()}
    assert not [f for f in files if f.startswith("reference/") or f.endswith("hidden.py")]  # sphere builds on nothing
    assert f"{STAGE}/camera.py" in files and ".github/workflows/classroom.yml" in files
    assert (release / STAGE / "camera.py").read_text() == (KIT_ROOT / "starter" / STAGE / "camera.py").read_text()
    assert json.loads((release / "autograder" / STAGE / "hidden.json").read_text())["count"] == 9
    answers = list((release / "autograder" / STAGE / "answers").glob("*.npz"))
    assert answers and all(a.name.startswith(("render-", "parts-")) for a in answers)
    setup = (release / "setup.sh").read_text()
    assert "main job" not in setup and "cs451 render" not in setup and "pip install -q -e ." in setup


def workflow_commands(workflow: Path) -> list[str]:
    """The shell commands the workflow runs after setup, in order (run: and command: lines)."""
    commands = re.findall(r"^\s+(?:run|command): (.+)$", workflow.read_text(), flags=re.M)
    return [c for c in commands if c != "./setup.sh"]


def run_workflow(release: Path) -> list[int]:
    codes = []
    for command in workflow_commands(release / ".github" / "workflows" / "classroom.yml"):
        command = command.replace(".venv/bin/python", sys.executable)
        codes.append(subprocess.run(command, shell=True, cwd=release, capture_output=True, timeout=600).returncode)
    return codes


def test06_the_workflow_grades_the_starter_zero_and_a_solution_full(release):
    codes = run_workflow(release)
    assert codes[0] == 0 and all(c == 1 for c in codes[1:]) and len(codes) == 1 + 7  # grading, then one per task
    results = json.loads((release / "results.json").read_text())
    assert results["score"] == 0 and not [t for t in results["tests"] if t["visibility"] != "visible"]
    for f in (KIT_ROOT / "reference" / STAGE).glob("*.py"):
        shutil.copy(f, release / STAGE / f.name)
    codes = run_workflow(release)
    assert codes == [0] * 8
    results = json.loads((release / "results.json").read_text())
    assert results["score"] == pytest.approx(60)  # the public tests' points, from the packaged answers
    report = (release / "report" / "report.html").read_text()
    assert "9 hidden tests (40 points), run after the deadline" in report


def test07_workflow_points_add_up_to_the_public_tests(release):
    text = (release / ".github" / "workflows" / "classroom.yml").read_text()
    assert sum(float(p) for p in re.findall(r"max-score: ([\d.]+)", text)) == 60
    assert text.count("_RESULTS:") == 7


@pytest.mark.parametrize("stage", ["whitted", "hemicube", "radiosity"])
def test08_every_stage_releases_without_its_solution(stage, tmp_path):
    """The packaging is the same for every stage; a later stage ships only the reference it builds on."""
    from cs451.stages import get_stage
    out = build_release(stage, tmp_path / "repo")
    files = {p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file()}
    shipped = {f.split("/")[1] for f in files if f.startswith("reference/")}
    assert shipped == set(get_stage(stage).builds_on) and stage not in shipped
    assert not [f for f in files if f.endswith("hidden.py")]
    assert [f for f in files if f.startswith(f"autograder/{stage}/answers/")]
    assert f"{stage}/__init__.py" in files and ".github/workflows/classroom.yml" in files
