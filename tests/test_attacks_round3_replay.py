"""Issue 34, item 1: a submission that replays the public answers a release ships scores nothing where it is graded.

The *replayer* is built at run time from what ``cs451 release STAGE`` writes: it copies the release's
``public.json`` and ``answers/`` into its own package, and when the worker imports it, it looks the
request up there (probe and parameters), writes the stored arrays as its answer and exits, implementing
nothing. Before the fix it scored most public points in every layout. Now every grading done with the
instructor's kit (``cs451 grade`` with the hidden tests, a roster, the Gradescope zip) grades the public
tests on fresh cases made from the kit's private secret (``autograder/<stage>/variants.py``), so the
replayer finds no case; a student's own self-check (the release, or ``--public-only``) keeps the shipped
cases. The reference keeps full marks on the fresh cases, and a solution with one planted bug loses the
same tasks there as in its self-check.
"""
from __future__ import annotations

import csv
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from cs451 import KIT_ROOT
from cs451.grading import sandbox
from cs451.grading.loader import load_tests
from cs451.grading.roster import grade_roster
from cs451.grading.runner import grade
from cs451.packaging.release import build_release
from cs451.stages import stage_names

from conftest import world_readable_dir
from test_packaging import run_autograder

pytestmark = pytest.mark.skipif(not sandbox.is_root(), reason="graded as a root grader grades them")

REPLAY = '''"""Implements nothing: answers each request with the stored answer of the shipped public case it matches."""
import json as _json
import os as _os

import numpy as _np

_HERE = _os.path.dirname(_os.path.abspath(__file__))


def _truth_as_output(check, truth):
    """The truth's arrays under the names the check reads (close_to's key), and under their own names."""
    out = dict(truth)
    kw = check.get("kwargs", {})
    if check["name"] == "close_to":
        out[kw["key"]] = truth[kw.get("truth_key", "value")]
    return out


def _replay():
    try:
        request = _json.load(open("request.json"))
    except OSError:
        return
    if request["probe"] == "__interface__":
        return
    from cs451.grading.expected import answer_key, truth_key
    from cs451.grading.spec import Ref
    inputs = dict.fromkeys(_np.load("inputs.npz").files) if _os.path.exists("inputs.npz") else None
    manifest = _json.load(open(_os.path.join(_HERE, "replay", "public.json")))
    answers = _os.path.join(_HERE, "replay", "answers")
    for test in manifest["tests"]:
        if test["probe"] != request["probe"] or test["params"] != request["params"]:
            continue
        out = {}
        stored = _os.path.join(answers, answer_key(test["probe"], test["params"], inputs))
        if test["expected"] == "reference" and _os.path.exists(stored):
            out.update(_np.load(stored))
        if test["truth"]:
            truth = dict(_np.load(_os.path.join(answers, truth_key(Ref.from_json(test["truth"]), test["params"]))))
            out = {**_truth_as_output(test["check"], truth), **out}
        _np.savez("output.npz", **out)
        open("status.json", "w").write(_json.dumps({"ok": True, "error": ""}))
        print("REPLAYED", test["name"])
        _os._exit(0)
    print("NO STORED CASE for", request["probe"])


_replay()
'''


def replayer(stage: str, release: Path, root: Path) -> Path:
    """A folder holding ``<stage>/``: the release's starter (every task a stub) with the replay at import."""
    pkg = root / stage
    shutil.copytree(release / stage, pkg, ignore=shutil.ignore_patterns("__pycache__"))
    (pkg / "replay").mkdir()
    shutil.copy(release / "autograder" / stage / "public.json", pkg / "replay" / "public.json")
    shutil.copytree(release / "autograder" / stage / "answers", pkg / "replay" / "answers")
    init = pkg / "__init__.py"
    init.write_text(REPLAY + "\n" + init.read_text())
    for path in [root, *root.rglob("*")]:
        os.chmod(path, 0o755 if path.is_dir() else 0o644)
    return root


def public_points(results: dict) -> float:
    """The points of the visible (public) tests in a results.json."""
    return round(sum(t["score"] for t in results["tests"] if t["visibility"] == "visible"), 4)


def grade_in_release(release: Path, stage: str, submission: Path, out: Path) -> dict:
    """A student's self-check in the release: its own engine, its shipped public cases (no set-up needed here)."""
    env = {**os.environ, "PYTHONPATH": str(release)}
    env.pop("CS451_HOME", None)
    done = subprocess.run([sys.executable, "-m", "cs451", "grade", stage, "--submission", str(submission),
                           "--public-only", "--results", str(out)], cwd=release, env=env, capture_output=True,
                          text=True, timeout=600)
    assert out.exists(), done.stderr[-3000:]
    return json.loads(out.read_text())


def grade_in_kit(stage: str, submission: Path) -> dict:
    from cs451.grading.results import to_gradescope
    return to_gradescope(grade(stage, submission, show_progress=False))


def grade_in_roster(stage: str, submission: Path) -> dict:
    top = world_readable_dir("cs451-class-")
    try:
        shutil.copytree(submission, top / "class" / "mallory")
        grade_roster(stage=stage, roster=top / "class", output=top / "grades", show_progress=False)
        rows = {r["student"]: r for r in csv.DictReader(open(top / "grades" / "gradebook.csv"))}
        assert rows["mallory"]["max_score"], rows
        return json.loads((top / "grades" / "mallory" / "results.json").read_text())
    finally:
        shutil.rmtree(top, ignore_errors=True)


@pytest.fixture(scope="module")
def workspace():
    root = world_readable_dir("cs451-replay-")
    yield root
    shutil.rmtree(root, ignore_errors=True)


def release_of(workspace: Path, stage: str) -> Path:
    path = workspace / f"release-{stage}"
    return path if path.exists() else build_release(stage, path)


def public_tasks_losing(results: dict) -> set[str]:
    """The tasks whose visible tests lost points."""
    return {t["tags"][0] for t in results["tests"] if t["visibility"] == "visible" and t["score"] < t["max_score"]}


def assert_fresh(results: dict) -> None:
    visible = [t for t in results["tests"] if t["visibility"] == "visible"]
    assert visible and all("graded on a fresh case of this kind: " in t["name"] for t in visible), \
        [t["name"] for t in visible if "fresh case" not in t["name"]][:3]


# --- the fresh cases themselves ------------------------------------------------------------------------

@pytest.mark.parametrize("stage", stage_names())
def test01_every_public_test_has_a_fresh_case_of_its_kind(stage):
    """Every public test names a variant; each fresh case differs from the shipped one, is the same for the same
    secret, changes with the secret, and keeps the test's task, points, probe and kind of check."""
    shipped = load_tests(stage, include_hidden=False)
    assert all(t.vary is not None and t.vary.module == f"autograder.{stage}.variants" for t in shipped), \
        [t.number for t in shipped if t.vary is None]
    one, again = load_tests(stage, include_hidden=False, secret="a" * 64), load_tests(stage, include_hidden=False,
                                                                                        secret="a" * 64)
    other = load_tests(stage, include_hidden=False, secret="b" * 64)
    assert [t.params for t in one] == [t.params for t in again]
    for s, f, g in zip(shipped, one, other):
        assert (f.number, f.task, f.points, f.probe, f.given, f.expected, f.edge_case) == \
            (s.number, s.task, s.points, s.probe, s.given, s.expected, s.edge_case)
        assert f.params != s.params and g.params != s.params, s.number
        assert f.check.name == s.check.name and f.name.startswith(s.name + "; graded on a fresh case of this kind: ")
    assert sum(f.params != g.params for f, g in zip(one, other)) >= 0.9 * len(shipped)
    hidden = [t for t in load_tests(stage, secret="a" * 64) if t.hidden]
    assert [t.params for t in hidden] == [t.params for t in load_tests(stage) if t.hidden]


def test02_the_kit_s_secret_is_private_and_stable(tmp_path):
    from cs451.grading.loader import variant_secret
    first = variant_secret(tmp_path / "cache")
    path = tmp_path / "cache" / "variant-secret"
    assert len(first) == 64 and variant_secret(tmp_path / "cache") == first
    assert path.stat().st_mode & 0o777 == 0o600 and (tmp_path / "cache").stat().st_mode & 0o077 == 0
    assert variant_secret(tmp_path / "other") != first


def test03_the_edge_cases_stay_edge_cases():
    """The cases whose purpose is a number keep it: height 0, max_edge 0, a repeated corner, zero-area triangles,
    a light under the floor, presses at the limits, a rolled camera."""
    def fresh(stage: str, number: str):
        shipped = {t.number: t for t in load_tests(stage, include_hidden=False)}[number]
        return shipped, {t.number: t for t in load_tests(stage, include_hidden=False, secret="c" * 64)}[number]
    _, minimised = fresh("sphere", "S7.3")
    assert minimised.params["height"] == 0 and minimised.params["width"] > 0
    shipped, limits = fresh("sphere", "S8.2")
    assert [s["slices"] for _, s in limits.params["presses"]][1::2] == [256, 4]
    _, keep = fresh("radiosity", "R1.3")
    assert keep.params["max_edge"] == 0 and keep.edge_case
    import numpy as np
    _, corner = fresh("hemicube", "H6.2")
    assert np.array_equal(corner.params["polygon"][2], corner.params["polygon"][3])
    _, zero = fresh("whitted", "W3.2")
    v0, v1, v2 = (np.asarray(zero.params[k]) for k in ("v0", "v1", "v2"))
    assert np.allclose(np.linalg.norm(np.cross(v1 - v0, v2 - v0), axis=1), 0.0) and zero.edge_case
    _, behind = fresh("whitted", "W11.3")
    assert behind.params["scene"]["lights"][0]["position"][1] < 0
    _, rolled = fresh("whitted", "W1.2")
    assert rolled.params["camera"]["up"] != [0, 1, 0] and rolled.params["height"] > rolled.params["width"]


# --- the replay, before (the self-check) and after (every server path) -----------------------------------

@pytest.mark.spawns
def test04_the_replay_scores_in_the_self_check_and_nothing_in_the_kit(workspace):
    """Sphere in the fast suite: the replay earns most public points in the student's own self-check (the shipped
    cases: that is not a grade) and none where the kit grades, whose tests each name their fresh case."""
    release = release_of(workspace, "sphere")
    assert not [p for p in release.rglob("variants.py")]
    submission = replayer("sphere", release, workspace / "replay-sphere")
    own = grade_in_release(release, "sphere", submission, workspace / "self-check.json")
    assert public_points(own) >= 50, public_points(own)
    kit = grade_in_kit("sphere", submission)
    assert public_points(kit) == 0 and "NO STORED CASE" in json.dumps(kit), public_points(kit)
    assert_fresh(kit)


@pytest.mark.spawns
@pytest.mark.slow
def test04b_in_a_roster_the_replay_scores_nothing_beside_an_honest_classmate_s_full_marks(workspace):
    submission = replayer("sphere", release_of(workspace, "sphere"), workspace / "replay-roster")
    top = world_readable_dir("cs451-class-")
    try:
        shutil.copytree(submission, top / "class" / "mallory")
        shutil.copytree(KIT_ROOT / "reference" / "sphere", top / "class" / "alice" / "sphere",
                        ignore=shutil.ignore_patterns("__pycache__"))
        grade_roster(stage="sphere", roster=top / "class", output=top / "grades", show_progress=False)
        rows = {r["student"]: r for r in csv.DictReader(open(top / "grades" / "gradebook.csv"))}
        assert float(rows["alice"]["score"]) == 100, rows["alice"]
        mallory = json.loads((top / "grades" / "mallory" / "results.json").read_text())
        assert public_points(mallory) == 0
        assert_fresh(mallory)
    finally:
        shutil.rmtree(top, ignore_errors=True)


@pytest.mark.spawns
@pytest.mark.parametrize("mode", ["bubblewrap", pytest.param("uid", marks=pytest.mark.slow)])
def test05_the_replay_scores_nothing_through_the_gradescope_zip(mode, workspace, gradescope):
    """The zip's own setup.sh made a secret of its own (private to root) and warmed the fresh cases' answers: the
    replay finds none of its cases there."""
    root, env = gradescope
    secret = Path(env["CS451_HOME"]) / ".cs451-cache" / "variant-secret"
    assert secret.stat().st_mode & 0o777 == 0o600 and secret.stat().st_uid == 0
    assert secret.read_text() != (KIT_ROOT / ".cs451-cache" / "variant-secret").read_text()
    submission = replayer("sphere", release_of(workspace, "sphere"), workspace / f"replay-gs-{mode}")
    layout = (root, {**env, "CS451_SANDBOX": mode})
    replayed = run_autograder(layout, submission)
    assert public_points(replayed) == 0 and len(replayed["tests"]) == len(load_tests("sphere"))
    assert_fresh(replayed)   # (test_packaging.py's test02 grades the reference there: 100, on the same fresh cases)


SLOW_STAGES = [pytest.param(s, marks=pytest.mark.slow) for s in ("whitted", "hemicube", "radiosity")]


@pytest.mark.spawns
@pytest.mark.parametrize("stage", SLOW_STAGES)
def test06_every_stage_s_replay_scores_nothing_where_the_kit_grades(stage, workspace):
    release = release_of(workspace, stage)
    submission = replayer(stage, release, workspace / f"replay-{stage}")
    own = grade_in_release(release, stage, submission, workspace / f"self-check-{stage}.json")
    assert public_points(own) >= 40, public_points(own)
    for path in (grade_in_kit(stage, submission), grade_in_roster(stage, submission)):
        assert public_points(path) == 0
        assert_fresh(path)


@pytest.mark.spawns
@pytest.mark.parametrize("stage", SLOW_STAGES)
def test07_every_stage_s_replay_scores_nothing_through_its_own_gradescope_zip(stage, workspace):
    from cs451.packaging.gradescope import build_gradescope, setup_like_gradescope
    top = world_readable_dir("cs451-gs-")
    try:
        layout = setup_like_gradescope(build_gradescope(stage, top / "autograder.zip"), top, sys.prefix)
        submission = replayer(stage, release_of(workspace, stage), workspace / f"replay-gs-{stage}")
        for mode in ("bubblewrap", "uid"):
            replayed = run_autograder((layout[0], {**layout[1], "CS451_SANDBOX": mode}), submission)
            assert public_points(replayed) == 0, (mode, public_points(replayed))
        reference = run_autograder(layout, KIT_ROOT / "reference")
        assert sum(t["score"] for t in reference["tests"]) == pytest.approx(100)
        assert_fresh(reference)
    finally:
        shutil.rmtree(top, ignore_errors=True)


# --- honest work: full marks, and a planted bug costs the same tasks everywhere ---------------------------

#: One planted bug per stage: (file, text, replacement).
PLANTED = {
    "sphere": ("camera.py", "f = 1.0 / np.tan(np.radians(fovy) / 2.0)", "f = 1.0 / np.tan(np.radians(fovy))"),
    "whitted": ("optics.py", "return d - 2.0 * np.einsum", "return d - 1.0 * np.einsum"),
    "hemicube": ("views.py", "_frustum(-near, near, 0.0, near, near, far)", "_frustum(-near, near, -near, near, near, far)"),
    "radiosity": ("shooting.py", "row * (areas[i] / areas)", "row * (areas / areas[i])"),
}


def _results(result) -> dict:
    from cs451.grading.results import to_gradescope
    return to_gradescope(result)


@pytest.mark.spawns
@pytest.mark.parametrize("stage", ["sphere", *SLOW_STAGES])
def test08_a_planted_bug_loses_the_same_tasks_on_the_fresh_cases(stage, make_submission):
    """The self-check (shipped cases) and the kit's grading (fresh cases) find the same tasks at fault; the fresh
    cases' messages describe the case and give no shipped case's answer."""
    file, old, new = PLANTED[stage]
    submission = make_submission(stage, file, old, new)
    local = _results(grade(stage, submission, include_hidden=False, show_progress=False))
    server = _results(grade(stage, submission, show_progress=False))
    assert public_tasks_losing(local) and public_tasks_losing(local) == public_tasks_losing(server), \
        (public_tasks_losing(local), public_tasks_losing(server))
    assert_fresh(server)
    if stage == "sphere":
        from cs451.grading.expected import TruthValues
        truths = TruthValues(stage)
        shipped = [t for t in load_tests(stage, include_hidden=False) if t.task == "S1"]
        answers = {f"{v:.6g}" for t in shipped for a in truths.get(t).values() for v in a.ravel() if v not in (0, 1, -1)}
        said = " ".join(t["output"] for t in server["tests"] if t["tags"] == ["S1"] and t["visibility"] == "visible")
        assert "expected" in said and not [a for a in answers if f"expected {a}" in said], said


@pytest.mark.slow
def test09_the_vetted_hemicube_cases_stay_as_close_to_their_closed_forms_as_the_shipped_ones():
    """H5's fresh closed-form cases come from lists measured with the reference's hemicube: each stays within the
    shipped case's own distance from its closed form, so a correct solution passes every one."""
    from cs451.formfactors import HemicubeFormFactors
    from cs451.impl import load_impl, resolve_impl
    from cs451.stages.hemicube import _quads, calls
    from autograder.hemicube import truth, variants
    impl = load_impl(resolve_impl("reference", "hemicube"), "hemicube")

    def error(quads, receivers, want, rotate):
        ff = HemicubeFormFactors(_quads(quads), calls(impl), resolution=128, rotate=rotate, proximity="none", seed=0)
        return abs(float(ff.rows([0])[0][receivers].sum()) - want) / want
    shipped = error(truth.opposed_squares(0.2, 1.0), [1], truth.howell_c11(0.2, 0.2, 1.0), True)
    far = [(a, d) for a, d in variants.SMALL_SQUARES
           if error(truth.opposed_squares(a, d), [1], truth.howell_c11(a, a, d), True) > max(shipped, 0.015)]
    assert not far, far
    sides = list(range(1, 257))
    shipped = error(truth.small_patch_under_disk(0.01, 1.0, 1.0, 256), sides, truth.polygon_disk(1.0, 1.0, 256), False)
    far = [(r, h) for r, h in variants.DISKS
           if error(truth.small_patch_under_disk(0.01, r, h, 256), sides, truth.polygon_disk(r, h, 256), False)
           > max(shipped, 0.001)]
    assert not far, far


@pytest.mark.spawns
def test10_graders_starting_together_share_one_whole_secret(tmp_path):
    """A roster's graders may all ask for the secret at once: each gets the same one, never a half-written file."""
    from concurrent.futures import ProcessPoolExecutor
    from cs451.grading.loader import variant_secret
    with ProcessPoolExecutor(4) as pool:
        got = list(pool.map(variant_secret, [tmp_path / "cache"] * 16))
    assert len(set(got)) == 1 and len(got[0]) == 64
    assert sorted(p.name for p in (tmp_path / "cache").iterdir()) == ["variant-secret"]
