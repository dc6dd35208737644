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
