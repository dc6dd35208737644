"""Grading stage 1: full marks for the reference, zero for the starter, and only the broken task's points lost."""
from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from cs451.grading.report import write_report
from cs451.grading.results import format_table, to_gradescope, total_score, write_results
from cs451.grading.loader import load_tests
from cs451 import KIT_ROOT
from cs451.grading.runner import grade


def points_by_task(result):
    out = {}
    for r in result.results:
        out.setdefault(r.test.task, 0.0)
        out[r.test.task] += r.score
    return out


@pytest.fixture
def reference_grade(reference_grade_of):
    return reference_grade_of("sphere")


def test01_tests_are_declared_with_points_visibility_and_tolerance():
    tests = load_tests("sphere")
    assert sum(t.points for t in tests if not t.extension) == 100
    assert {t.task for t in tests} == {f"S{i}" for i in range(1, 10)}
    assert {t.task for t in tests if t.extension} == {"S9"}       # the optional extension, outside the 100
    assert any(t.hidden for t in tests) and any(not t.hidden for t in tests)
    assert all(t.tolerance for t in tests)
    assert len({t.number for t in tests}) == len(tests)


#: each broken task is graded beside the tasks whose tests draw or call what it computes (the matrices feed the
#: shader images and reshape, the mesh the shaders, the shaders each other); that a stubbed task costs no other
#: task anything, over every task of every stage, is the slow contract test (tests/test_stage_contract.py)
@pytest.mark.spawns
@pytest.mark.parametrize("file, old, new, task, consumers", [
    ("camera.py", "s, u, -f", "s, u, f", "S2", ["S5", "S7"]),                      # look_at: forward not negated
    ("mesh.py", "phi = -2.0 * np.pi", "phi = 2.0 * np.pi", "S4", ["S5", "S6"]),    # mesh wound clockwise
    ("shaders.py", "v_color = fixed_function_lighting(p.xyz / p.w, n);", "v_color = fixed_function_lighting(p.xyz / p.w, -n);",
     "S5", ["S6"]),
    ("controls.py", 'if key in ("q", "Q", "escape"):', 'if key == "q":', "S8", ["S7"]),
    # Phong without renormalising the interpolated normal (handout §S6): the coarse, close-up sphere tells
    ("shaders.py", "fixed_function_lighting(v_position, normalize(v_normal))", "fixed_function_lighting(v_position, v_normal)",
     "S6", ["S5"]),
    ("camera.py", "f = 1.0 / np.tan(np.radians(fovy) / 2.0)", "f = 1.0 / np.tan(np.radians(fovy))", "S1", ["S5", "S7"]),
    # the modelview product taken on the left: the first call becomes the first applied (handout §S3)
    ("transforms.py", "stack[-1] = stack[-1] @ operations[name](*args)", "stack[-1] = operations[name](*args) @ stack[-1]",
     "S3", ["S5", "S6"]),
])
def test04_one_broken_function_loses_only_its_task(make_submission, reference_grade, file, old, new, task, consumers):
    result = grade("sphere", make_submission("sphere", file, old, new), show_progress=False, tasks=[task, *consumers])
    got, full = points_by_task(result), points_by_task(reference_grade)
    assert set(got) == {task, *consumers}
    assert got[task] < full[task], f"{task} should lose points"
    assert {k: v for k, v in got.items() if k != task} == {k: full[k] for k in consumers}


@pytest.mark.spawns
def test05_a_submission_that_does_not_import_gets_zero_and_the_reason(make_submission):
    root = make_submission("sphere", "camera.py", "def perspective(", "def perspective(:")
    result = grade("sphere", root, show_progress=False)
    assert result.score == 0
    assert "syntax error" in result.results[0].verdict.message and "camera.py" in result.results[0].verdict.message


@pytest.mark.spawns
def test06_wrong_shape_and_nan_are_scored_with_a_message(make_submission):
    root = make_submission("sphere", "camera.py", "    return rotation @ translation", "    return (rotation @ translation)[:3]")
    result = grade("sphere", root, show_progress=False, tasks=["S2"])
    s2 = [r for r in result.results if r.test.task == "S2"]
    assert s2 and all(r.score == 0 and "shape (3, 4), expected (4, 4)" in r.verdict.message for r in s2)
    root = make_submission("sphere", "camera.py", "f = 1.0 / np.tan(np.radians(fovy) / 2.0)", "f = np.nan", name="nan")
    result = grade("sphere", root, show_progress=False, tasks=["S1"])
    assert result.results and all("NaN" in r.verdict.message for r in result.results if r.test.task == "S1")


def test07_results_json_follows_gradescope_and_report_shows_images(reference_grade, tmp_path):
    data = json.loads(write_results(tmp_path / "results.json", reference_grade).read_text())
    assert "score" not in data and total_score(data) == 100 and len(data["tests"]) == len(reference_grade.results)
    for t in data["tests"]:
        assert set(t) >= {"score", "max_score", "name", "number", "output", "visibility", "status"}
        assert t["visibility"] in ("visible", "after_published")
    html = write_report(tmp_path, reference_grade).read_text()
    assert html.count("data:image/png;base64") >= 4 * sum(bool(r.verdict.images) for r in reference_grade.results)
    student = write_report(tmp_path / "student", reference_grade, show_hidden=False).read_text()
    assert "hidden tests" in student and "[hidden]" not in student
    assert "S5.1" in format_table(reference_grade)
    assert to_gradescope(reference_grade)["tests"][0]["status"] == "passed"


@pytest.mark.spawns
def test08_only_the_word_reference_is_trusted_and_grading_leaves_the_kit_as_it_was(kit_root):
    """A path that leads to the reference is a submission like any other: sandboxed, not a self-test."""
    watched = [kit_root, kit_root / "reference", kit_root / "autograder", kit_root / ".cs451-cache"]
    modes = {p: p.stat().st_mode for p in watched if p.exists()}
    trusted = grade("sphere", "reference", show_progress=False, tasks=["S1"])
    by_path = grade("sphere", kit_root / "reference", show_progress=False, tasks=["S1"])
    assert "trusted" in trusted.isolation and "trusted" not in by_path.isolation
    assert trusted.score == by_path.score == trusted.max_score == 10
    assert modes == {p: p.stat().st_mode for p in modes}


def test09_messages_write_shapes_as_python_does_and_plurals_agree():
    import numpy as np

    from cs451.errors import KitError
    from cs451.grading.checks import ShapeError, close_to, output
    from cs451.stages.base import as_array
    with pytest.raises(KitError, match=r"returned shape \(8,\), expected \(7,\)$"):
        as_array(np.zeros(8), (7,), "S0 f()")
    with pytest.raises(ShapeError, match=r"has shape \(2, 3\), expected \(n, 4\)$"):
        output({"x": np.zeros((2, 3))}, "x", (None, 4))
    views = {"value": np.stack([np.eye(4)] * 5)}
    plural = dict(key="views", what="the five view matrices", plural=True)
    assert close_to({"views": views["value"]}, views, {}, **plural).message == "the five view matrices match"
    assert close_to({"views": 2 * views["value"]}, views, {}, **plural).message.startswith("the five view matrices are wrong")
    assert close_to({"m": np.eye(4)}, {"value": np.eye(4)}, {}, "m", what="the matrix").message == "the matrix matches"


def test10_shader_errors_name_the_shader_and_count_the_students_own_lines():
    from cs451.errors import KitError
    from cs451.gl import create_context
    from cs451.impl import load_impl, resolve_impl
    from cs451.stages.sphere import SphereRenderer

    vertex, fragment = load_impl(resolve_impl("reference", "sphere"), "sphere").phong_shaders()
    ctx = create_context()

    def line_of(source: str, text: str) -> int:
        return next(i for i, line in enumerate(source.split("\n"), 1) if text in line)

    broken = vertex.replace("gl_Position = u_projection * p;", "gl_Position = u_projection * p")
    with pytest.raises(KitError, match=rf"^S6: the vertex shader does not compile: line {line_of(vertex, 'gl_Position') + 1}, "):
        SphereRenderer(ctx, (broken, fragment), [], "S6")
    broken = fragment.replace("normalize(v_normal)", "normalise(v_normal)")
    with pytest.raises(KitError, match=rf"^S6: the fragment shader does not compile: line {line_of(fragment, 'normalize(v_normal)')}, "):
        SphereRenderer(ctx, (vertex, broken), [], "S6")
    with pytest.raises(KitError, match=r"^S6: the vertex shader does not compile: line 1, column 1: preprocessor error"):
        SphereRenderer(ctx, ("#version 330\n" + vertex, fragment), [], "S6")
    with pytest.raises(KitError, match=r"^S6: the vertex and fragment shaders do not link"):
        SphereRenderer(ctx, (vertex, fragment.replace("void main()", "void mane()")), [], "S6")


@pytest.mark.spawns
@pytest.mark.parametrize("zero_height_viewport, full", [("(0, 0, width, 0)", True), ("(0, 0, width, 2)", False),
                                                        ("(0, 0, 0, 0)", False)])
def test11_a_zero_height_window_may_keep_viewport_height_0_or_1(make_submission, reference_grade,
                                                                zero_height_viewport, full):
    """Handout §S7: for a window of height 0 the viewport may be (0, 0, w, 0), as the notes' program passes to
    glViewport (legal GL), or (0, 0, w, 1); any other viewport loses S7's points for that window."""
    root = make_submission("sphere", "camera.py", "    height = max(int(height), 1)\n",
                           "    minimised = int(height) == 0\n    height = max(int(height), 1)\n")
    camera = root / "sphere" / "camera.py"
    text = camera.read_text()
    old = "return (0, 0, width, height), perspective("
    assert old in text
    camera.write_text(text.replace(old, f"return ({zero_height_viewport} if minimised else (0, 0, width, height)), "
                                        "perspective(", 1))
    result = grade("sphere", root, show_progress=False, tasks=["S7"])
    got, want = points_by_task(result)["S7"], points_by_task(reference_grade)["S7"]
    assert want == 10
    if full:
        assert got == want, [(r.test.number, r.verdict.message) for r in result.results if r.score < r.test.points]
    else:
        lost = [r for r in result.results if r.score < r.test.points]
        assert got < want and lost and all(r.test.params["height"] == 0 for r in lost)
        assert all(f"expected (0, 0, {w}, 0) or (0, 0, {w}, 1)" in r.verdict.message
                   for r in lost for w in [r.test.params["width"]])   # the public test's width is a fresh case's


@pytest.mark.spawns
@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() != 0, reason="as root the tests run as a throwaway user")
def test12_as_root_a_python_behind_a_private_folder_is_named_with_the_fix():
    """Root grading with its Python environment under a 0700 folder (a repository in /root, say): the sandbox's
    throwaway user cannot reach the interpreter. The refusal names that folder and the fix, which then works; it
    does not tell root to install the bubblewrap it has or to grade as root."""
    import shutil
    import subprocess
    import sys

    from conftest import world_readable_dir
    top = world_readable_dir("cs451-private-")
    private = top / "private"
    private.mkdir(mode=0o700)
    (private / "venv").symlink_to(Path(sys.prefix))   # the kit's environment, reached through the private folder
    try:
        shutil.copytree(KIT_ROOT / "reference" / "sphere", top / "upload" / "sphere",
                        ignore=shutil.ignore_patterns("__pycache__"))
        command = [str(private / "venv" / "bin" / "python"), "-m", "cs451", "grade", "sphere", "--submission",
                   str(top / "upload"), "--tasks", "S1", "--public-only"]
        done = subprocess.run(command, cwd=top, capture_output=True, text=True, timeout=300)
        assert done.returncode == 2, done.stdout + done.stderr
        said = done.stderr
        assert f"cannot reach the Python interpreter {private}/venv/bin/python: {private} lets no other user" in said
        assert f"chmod o+x {private}" in said and "grade as root" not in said and "Install bubblewrap" not in said
        os.chmod(private, 0o711)     # the fix the message gives
        done = subprocess.run(command, cwd=top, capture_output=True, text=True, timeout=300)
        assert done.returncode == 0 and "total: 6 / 6" in done.stdout, done.stdout + done.stderr
    finally:
        shutil.rmtree(top, ignore_errors=True)
