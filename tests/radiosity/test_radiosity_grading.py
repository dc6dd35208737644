"""Stage 4 from the outside: grading (reference 100, starter 0, a broken task loses its points), the CLI, the demo."""
from __future__ import annotations

import shutil
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

from cs451 import KIT_ROOT
from cs451.grading.runner import grade, load_tests
from cs451.impl import load_impl, resolve_impl

REF = load_impl(resolve_impl("reference", "radiosity"), "radiosity")


def points_by_task(result) -> dict[str, float]:
    out: dict[str, float] = {}
    for r in result.results:
        out[r.test.task] = out.get(r.test.task, 0.0) + r.score
    return out


def test01_tests_are_declared_with_points_visibility_and_tolerance():
    tests = load_tests("radiosity")
    assert sum(t.points for t in tests if not t.extension) == 100
    assert {t.task for t in tests} == {f"R{i}" for i in range(1, 8)}
    assert {t.task for t in tests if t.extension} == {"R7"}     # the optional extension, outside the 100
    assert any(t.hidden for t in tests) and any(not t.hidden for t in tests)
    assert all(t.tolerance for t in tests) and len({t.number for t in tests}) == len(tests)


@pytest.fixture
def reference_grade(reference_grade_of):
    return reference_grade_of("radiosity")


@pytest.mark.spawns
@pytest.mark.slow
@pytest.mark.parametrize("file,old,new,lost", [
    ("patches.py", "cells = np.stack([grid[:-1, :-1], grid[:-1, 1:], grid[1:, 1:], grid[1:, :-1]], axis=2)",
     "cells = np.stack([grid[:-1, :-1], grid[1:, :-1], grid[1:, 1:], grid[:-1, 1:]], axis=2)", {"R1"}),
    ("shooting.py", "return (unshot * areas[:, None]).sum(axis=0) / total / (1.0 - rho_avg)",
     "return (unshot * areas[:, None]).sum(axis=0) / total", {"R4"}),
    ("display.py", "return positions, sums / counts[:, None], inverse.astype(np.int64)",
     "return positions, sums / 4.0, inverse.astype(np.int64)", {"R5"}),
    ("shooting.py", "received = np.outer(row * (areas[i] / areas), delta)", "received = np.outer(row, delta)",
     {"R2", "R3"}),
    ("solve_again.py", "return progressive_refinement(remembered,", "return progressive_refinement(row,", {"R6"}),
    ("solve_again.py", "            known[i] = row(i)\n        return known[i]", "            return row(i)\n        return known[i]",
     {"R6"}),
])
def test04_one_broken_function_loses_its_task_and_what_calls_it(make_submission, file, old, new, lost):
    """The image tests show the reference's R3 and R4 values (R5 alone is judged); only R3 runs the student's R2,
    and its failing tests say so."""
    result = grade("radiosity", make_submission("radiosity", file, old, new), show_progress=False)
    full = {t: sum(x.points for x in load_tests("radiosity") if x.task == t) for t in ("R1", "R2", "R3", "R4", "R5", "R6")}
    got = points_by_task(result)
    for task, points in full.items():
        if task in lost:
            assert got[task] < points, f"breaking {file} should cost {task} points"
        else:
            assert got[task] == points, f"breaking {file} cost {task} {points - got[task]} points"
    if lost == {"R2", "R3"}:
        failing_r3 = [r for r in result.results if r.test.task == "R3" and r.score < r.test.points]
        assert all("relies on your own R2 shoot(), and R2 shoot() loses points in its own tests" in r.verdict.message for r in failing_r3)


def test05_demo_writes_frames_and_an_animation(tmp_path):
    """The frames after 0, 1, 2 and 4 shots; what the keys do is tests/radiosity/test_demo_radiosity.py's."""
    from cs451.stages.radiosity.demo import demo
    paths = demo(REF, tmp_path, window=False, frames=4, scene="furnace", size=(48, 48))
    assert paths[0].name == "radiosity.gif" and len(paths) == 1 + 4
    with Image.open(paths[0]) as gif:
        assert gif.n_frames == 4
    first, second = (np.asarray(Image.open(p), dtype=float) for p in paths[1:3])
    bar = max(10, 48 // 24)
    assert first.shape == second.shape and first.shape[0] > 48 + bar and first.shape[1:] == (48, 3)
    assert first[48 + bar:].std() > 10                           # the caption says what the frame shows
    assert not np.array_equal(first, second)                      # a shot later


@pytest.mark.spawns
@pytest.mark.skipif(shutil.which("xvfb-run") is None, reason="needs Xvfb (xvfb-run) for a window without a display")
def test05b_demo_window_shows_frames_under_xvfb(tmp_path):
    done = subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 1024x768x24", sys.executable, "-m", "cs451", "demo",
                           "radiosity", "--window", "--frames", "3", "-o", str(tmp_path)],
                          cwd=KIT_ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert not list(tmp_path.iterdir()), "a window demo writes no files"


@pytest.mark.spawns
@pytest.mark.slow
def test06_cli_renders_the_cornell_box(tmp_path):
    out = tmp_path / "r.png"
    done = subprocess.run([sys.executable, "-m", "cs451", "render", "cornell-box", "--stage", "radiosity", "-o", str(out)],
                          cwd=KIT_ROOT, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    image = np.asarray(Image.open(out), dtype=float)
    assert image.shape == (256, 256, 3)
    left, right = image[100:150, 5:30].mean(axis=(0, 1)), image[100:150, 226:251].mean(axis=(0, 1))
    assert left[0] > 2 * left[1] and right[1] > 1.3 * right[0], "the red wall is on the left, the green on the right"
    assert "converged" in done.stderr and "rows computed" in done.stderr


@pytest.mark.spawns
@pytest.mark.slow
def test07_bench_writes_its_table_json_and_plot(tmp_path):
    done = subprocess.run([sys.executable, "-m", "cs451", "bench", "radiosity", "--quick", "-o", str(tmp_path)],
                          cwd=KIT_ROOT, capture_output=True, text=True, timeout=1200)
    assert done.returncode == 0, done.stderr
    import json
    report = json.loads((tmp_path / "radiosity.json").read_text())
    assert (tmp_path / "radiosity.png").stat().st_size > 10_000
    methods = set(report["cases"][0]["methods"])
    assert {"direct", "jacobi", "gauss-seidel", "progressive", "progressive+ambient", "progressive+overshoot",
            "progressive+overshoot+ambient", "maximum (1988)", "maximum (1988)+overshoot"} <= methods
    for case in report["cases"]:                       # the notes' sweeps and the paper's order shoot about as often
        m = case["methods"]
        assert 0.5 < m["progressive"]["shots"] / m["maximum (1988)"]["shots"] < 2.0
    for case in report["cases"]:                       # every method gets within 0.1% of the direct solve
        assert all(m["seconds_to_0.001"] is not None for m in case["methods"].values()), case["scene"]
    for case in report["solve_again"]["cases"]:          # R6: a change of colours or lights renders no hemicube
        assert case["reused_hemicubes"] == 0 < case["fresh_hemicubes"] and case["max_difference"] < 1e-4
    exact = [f for f in report["furnace"] if f["form_factors"].startswith("exact")]
    assert all(abs(f["mean_error"]) <= 1e-4 for f in exact)
    assert all(0 < case["formfactor_noise"] < 0.1 for case in report["cases"])
    for case in report["substructured"]:               # a row per patch at most, fewer than the elements
        for m in case["methods"].values():
            assert 0 < m["rows"] <= case["patches"] < case["elements"] and m["final_error"] < 0.1
