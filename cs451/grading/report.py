"""A self-contained HTML report: reference, submission, difference, error map and FLIP side by side per image test.

Like Stanford draw-svg's reference-and-diff viewer, but a single file a student can open offline or an
instructor can attach to a grade. The page is a Jinja2 template (``templates/report.html.j2``, escaped
by default); failures come first and passing tests are folded; small images are scaled up by whole pixels
and enlarge on a click; a failing image test whose submission drew nothing still shows the target.
"""
from __future__ import annotations

import base64
import io
import math
from pathlib import Path

import numpy as np
from jinja2 import Environment, PackageLoader, select_autoescape
from PIL import Image as PILImage

from ..compare import flip_error
from .runner import GradeResult, TestResult
from .untrusted import printable

CAPTIONS = {"reference": "reference (as <code>cs451 render</code> writes it)",
            "submission": "yours (as <code>cs451 render</code> writes it)",
            "difference": "|difference| × 4, linear: black where they agree",
            "error": "error map after the 3×3 allowance: black where equal, yellow up to the threshold, red over it",
            "flip": "FLIP, the perceptual error (NVIDIA's ꟻLIP; magma: black where a viewer sees no difference): "
                    "mean {mean:.3f}"}
ORDER = ("reference", "submission", "difference", "error", "flip")
#: images narrower than this are shown scaled up by a whole factor (W11's 96 × 72 renders)
MIN_SHOWN_WIDTH = 256
#: larger ones are shown at most this wide, five in a row; a click shows them up to ZOOMED_WIDTH
MAX_SHOWN_WIDTH = 300
ZOOMED_WIDTH = 1100

_env = Environment(loader=PackageLoader("cs451.grading", "templates"), autoescape=select_autoescape(["j2", "html"]),
                   trim_blocks=True, lstrip_blocks=True)
_env.filters["num"] = lambda x: f"{x:g}"


def _png_data_uri(image: np.ndarray) -> str:
    buf = io.BytesIO()
    PILImage.fromarray(image).save(buf, format="PNG")
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode()


def _status(r) -> tuple[str, str]:
    if r.verdict.passed:
        return "ok", "passed"
    return ("part", "partly") if r.score > 0 else ("fail", "failed")


def hidden_note(result: GradeResult, show_hidden: bool = False) -> str:
    """One line counting the hidden tests a student cannot see (those held back, or not run in a public-only run)."""
    held = [r for r in result.results if r.test.hidden and not show_hidden]
    if held:
        count, points = len(held), sum(r.test.points for r in held)
        when = "graded now, shown after grades are published"
    elif result.hidden_not_run.get("count"):
        count, points = result.hidden_not_run["count"], result.hidden_not_run["points"]
        when = "run after the deadline"
    else:
        return ""
    return (f"{count} hidden test{'s' if count != 1 else ''} ({points:g} points), {when}; "
            "they check the same tasks on other scenes, sizes and parameters.")


def extension_line(result: GradeResult) -> str:
    """One line for the optional extension's tests, which stay out of the grade."""
    tasks = sorted({r.test.task for r in result.extensions})
    return (f"optional extension {', '.join(tasks)}: {result.extension_score:g} / {result.extension_max:g} "
            "(not part of the grade)")


def figures(images: dict[str, np.ndarray]) -> list[dict]:
    """The pictures of one test in the report's order, with the FLIP map where both renders are there."""
    images = dict(images)
    captions = dict(CAPTIONS)
    ref, got = images.get("reference"), images.get("submission")
    if ref is not None and got is not None and ref.shape == got.shape and ref.ndim == 3:
        mean, images["flip"] = flip_error(ref, got)
        captions["flip"] = CAPTIONS["flip"].format(mean=mean)
    out = []
    for key in ORDER:
        if key in images:
            image = np.asarray(images[key])
            native = max(image.shape[1], 1)
            shown = native * math.ceil(MIN_SHOWN_WIDTH / native) if native < MIN_SHOWN_WIDTH else min(native, MAX_SHOWN_WIDTH)
            zoom = min(max(native, 3 * shown), ZOOMED_WIDTH)
            out.append({"key": key, "uri": _png_data_uri(image), "width": shown, "zoom": zoom, "caption": captions[key]})
    return out


def failures_first(results: list[TestResult]) -> list[TestResult]:
    """The tests that lost points, then those that passed, each group in test order: what to fix comes first. A
    hidden test's outcome moves only hidden rows, so the visible rows' order says nothing about it."""
    return [r for r in results if not r.verdict.passed] + [r for r in results if r.verdict.passed]


def _row(r) -> dict:
    status, word = _status(r)
    return {"number": r.test.number, "name": printable(r.test.name), "score": r.score, "points": r.test.points,
            "status": status, "word": word, "hidden": r.test.hidden, "extension": r.test.extension, "tolerance": r.test.tolerance,
            "message": printable(r.verdict.message), "output": r.output.strip() and printable(r.output)}


def render_report(result: GradeResult, show_hidden: bool = True) -> str:
    """The report as HTML; with ``show_hidden=False`` hidden tests are counted, not shown (the student's view).

    The headline counts the visible tests; the hidden tests' points, when shown, are on a line of their own."""
    shown = [r for r in result.results if show_hidden or not r.test.hidden]
    failed = [dict(_row(r), figures=figures(r.verdict.images)) for r in shown if not r.verdict.passed]
    passed = [dict(_row(r), figures=figures(r.verdict.images)) for r in shown if r.verdict.passed]
    visible = [r for r in shown if not r.test.hidden and not r.test.extension]
    held = [r for r in shown if r.test.hidden and not r.test.extension]
    held_back = not show_hidden and any(r.test.hidden for r in result.results)   # its time counts the hidden tests
    return _env.get_template("report.html.j2").render(
        stage=result.stage, submission=printable(result.submission, lines=False),
        seconds=None if held_back else result.seconds, isolation=printable(result.isolation),
        score=sum(r.score for r in visible), total=sum(r.test.points for r in visible),
        hidden_score=sum(r.score for r in held), hidden_total=sum(r.test.points for r in held),
        hidden_note=hidden_note(result, show_hidden),
        extension_note=extension_line(result) if result.extensions else "", problems=[printable(p) for p in result.problems],
        rows=[_row(r) for r in failures_first(shown)],
        failed=failed, passed=passed)


def write_report(folder: str | Path, result: GradeResult, show_hidden: bool = True) -> Path:
    """Write the HTML report to ``folder/report.html`` (the folder made if need be) and return that path."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "report.html"
    path.write_text(render_report(result, show_hidden))
    return path
