"""The HTML report: what a student sees first, the pictures it shows, and that nothing in it runs as code."""
from __future__ import annotations

import re

import numpy as np

from cs451.grading.checks import target_images
from cs451.grading.report import render_report
from cs451.grading.runner import GradeResult, TestResult as Result
from cs451.grading.spec import Test as Spec, Verdict, check
from cs451.grading.checks import close_to


def _test(name: str, number: str, points: float = 2.0) -> Spec:
    return Spec(name, "W11", points, "render", {}, check(close_to, key="image"), "tol", number=number)


def _result(*rows: tuple[Spec, Verdict]) -> GradeResult:
    return GradeResult("whitted", "sub", [Result(t, t.points * v.fraction, v) for t, v in rows], seconds=1.0)


def _images(shift: float) -> dict[str, np.ndarray]:
    ramp = np.tile(np.linspace(0, 255, 96, dtype=np.uint8)[None, :, None], (72, 1, 3))
    other = np.clip(ramp.astype(int) + int(shift), 0, 255).astype(np.uint8)
    return {"reference": ramp, "submission": other}


def test_failures_come_first_and_passing_tests_are_folded():
    html = render_report(_result((_test("good", "W11.1"), Verdict(1.0, "ok", _images(0))),
                                 (_test("bad", "W11.2"), Verdict(0.0, "image differs", _images(60)))))
    body = html.split("</table>", 1)[1]
    assert body.index('id="tW11.2"') < body.index("<details>") < body.index('id="tW11.1"')


def test_a_flip_map_and_score_stand_beside_the_renders():
    html = render_report(_result((_test("bad", "W11.2"), Verdict(0.0, "image differs", _images(60)))))
    means = [float(m) for m in re.findall(r"FLIP, the perceptual error.*?mean ([\d.]+)", html)]
    assert len(means) == 1 and 0.05 < means[0] < 1, means
    same = render_report(_result((_test("good", "W11.1"), Verdict(1.0, "ok", _images(0)))))
    assert re.search(r"mean 0\.000", same)


def test_small_images_are_scaled_by_whole_pixels_and_enlarge_on_a_click():
    html = render_report(_result((_test("bad", "W11.2"), Verdict(0.0, "x", _images(60)))))
    widths = {int(w) for w in re.findall(r'<img [^>]*width="(\d+)"', html)}
    assert widths == {288}                     # 96 × 3: the smallest whole factor reaching 256
    assert "image-rendering:pixelated" in html and 'data-zoom="864"' in html


def test_a_submission_that_drew_nothing_still_shows_the_target():
    expected = {"image": np.full((6, 8, 3), 0.5)}
    images = target_images(expected, {"scene": {"image": {"srgb": True}}})
    assert set(images) == {"reference"} and images["reference"].dtype == np.uint8
    assert images["reference"][0, 0, 0] == round(255 * (1.055 * 0.5 ** (1 / 2.4) - 0.055))
    assert target_images({"F": np.zeros((3, 3))}, {}) == {}
    html = render_report(_result((_test("crashed", "W11.3"), Verdict(0.0, "it crashed", images))))
    assert html.count("data:image/png;base64") == 1 and "reference (as" in html


def test_what_a_submission_writes_is_shown_as_text_never_run():
    hostile = "<script>alert(1)</script><img src=x onerror=alert(2)>"
    html = render_report(_result((_test(hostile, "W11.4"), Verdict(0.0, hostile))))
    assert "<script>alert(1)" not in html and "<img src=x" not in html
    assert "&lt;script&gt;alert(1)&lt;/script&gt;" in html


def test_an_optional_extension_is_reported_on_its_own_line_and_never_moves_the_grade():
    """W12 (optional) passed, W11 failed: the grade is W11's alone in the table, the report, results.json's sum and
    the gradebook row; the extension's points are shown beside it and travel in results.json's extra_data."""
    from dataclasses import replace

    from cs451.grading.results import format_table, to_gradescope, total_score
    from cs451.grading.roster import _row
    main = _test("main", "W11.1", 4.0)
    extra = replace(Spec("lens", "W12", 5.0, "thin_lens", {}, check(close_to, key="origins"), "tol", number="W12.1"),
                    extension=True)
    result = _result((main, Verdict(0.0, "image differs")), (extra, Verdict(1.0, "ok")))
    assert (result.score, result.max_score, result.extension_score, result.extension_max) == (0, 4, 5, 5)
    table = format_table(result)
    assert "total: 0 / 4" in table and "optional extension W12: 5 / 5 (not part of the grade)" in table
    assert "Optional extension W12: 5 / 5 (not part of the grade)." in render_report(result)
    data = to_gradescope(result)
    lens = next(t for t in data["tests"] if t["number"] == "W12.1")
    assert (lens["score"], lens["max_score"], lens["extra_data"]) == (0.0, 0.0, {"extension": True, "score": 5.0,
                                                                                  "max_score": 5.0})
    assert total_score(data) == 0
    row = _row("alice", result, ["W11", "W12"])
    assert (row["score"], row["max_score"], row["extension"], row["W12"]) == (0, 4, 5, 5)
