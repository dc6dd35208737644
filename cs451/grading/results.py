"""Grading results as Gradescope's results.json and as a terminal table.

Gradescope's format (https://gradescope-autograders.readthedocs.io, "Output format"):
top-level ``score``, ``execution_time``, ``output``, ``visibility``, ``stdout_visibility``
and a list of ``tests`` each with ``score``, ``max_score``, ``status``, ``name``,
``number``, ``output``, ``tags`` and ``visibility``.
"""
from __future__ import annotations

import html
import json
from pathlib import Path
from typing import Any

import numpy as np

from .runner import GradeResult
from .untrusted import printable


def to_gradescope(result: GradeResult) -> dict[str, Any]:
    """Gradescope's results.json: per-test text output, and an HTML summary with thumbnails of failed image tests.

    With hidden tests in it, no top-level ``score`` (Gradescope's "overrides total of tests if specified") and no
    ``execution_time``: Gradescope then adds up the tests' own scores, hidden ones included, and a student sees
    that total only once the hidden tests are shown; before, only the visible tests' points (the summary's)."""
    tests = []
    for r in result.results:
        t = r.test
        output = r.verdict.message
        if r.output.strip():
            output += "\n\nYour code printed:\n" + r.output.strip()[:MAX_PRINTED]
        entry = {"score": r.score, "max_score": t.points, "status": "passed" if r.verdict.passed else "failed",
                 "name": printable(t.name, lines=False), "number": t.number, "output": printable(output),
                 "output_format": "text", "tags": [t.task], "visibility": t.visibility}
        if t.extension:   # shown, never added to the grade: its points travel in extra_data
            entry.update(score=0.0, max_score=0.0, name=f"[optional extension] {entry['name']}",
                         output=f"Optional extension, not part of the grade: {r.score:g} / {t.points:g}.\n\n" + entry["output"],
                         extra_data={"extension": True, "score": r.score, "max_score": t.points})
        tests.append(entry)
    data: dict[str, Any] = {"output": _summary_html(result), "output_format": "html",
                            "visibility": "visible", "stdout_visibility": "hidden", "tests": tests}
    if not any(r.test.hidden for r in result.results):
        data = {"score": round(result.score, 4), "execution_time": round(result.seconds, 2), **data}
    return data


def total_score(data: dict[str, Any]) -> float:
    """The score Gradescope records for a results.json: its top-level score if given, else its tests' scores added."""
    if "score" in data:
        return float(data["score"])
    return round(sum(float(t.get("score", 0)) for t in data.get("tests", [])), 4)


#: Characters of a test's printed output kept in results.json (Gradescope pages get slow beyond that).
MAX_PRINTED = 4000
#: Thumbnails in the Gradescope summary are at most this many pixels wide and tall.
THUMBNAIL = 160


def _summary_html(result: GradeResult) -> str:
    from PIL import Image as PILImage
    from .report import _png_data_uri, extension_line, hidden_note
    def esc(text: object) -> str:
        return html.escape(printable(text))
    visible = [r for r in result.graded if not r.test.hidden]
    score, total = sum(r.score for r in visible), sum(r.test.points for r in visible)
    parts = [f"<p><b>{score:g} / {total:g} points</b> on the tests you can see now.</p>"]
    if result.extensions:
        parts.append(f"<p>{esc(extension_line(result))}</p>")
    note = hidden_note(result, show_hidden=False)
    if note:
        parts.append(f"<p>{esc(note)}</p>")
    if result.problems:
        parts.append("<p>Problems found before testing:</p><ul>" +
                     "".join(f"<li>{esc(p)}</li>" for p in result.problems) + "</ul>")
    for r in visible + result.extensions:
        if r.verdict.passed or not r.verdict.images:
            continue
        parts.append(f"<p>{esc(r.test.number)} {esc(r.test.name)}: {esc(r.verdict.message)}</p><p>")
        for key in ("reference", "submission", "error"):
            if key in r.verdict.images:
                img = PILImage.fromarray(r.verdict.images[key])
                img.thumbnail((THUMBNAIL, THUMBNAIL))
                parts.append(f"<img alt='{key}' title='{key}' src='{_png_data_uri(np.asarray(img))}'> ")
        parts.append("</p>")
    parts.append(f"<p>Isolation in force: {esc(result.isolation or 'unknown')}.</p>")
    return "\n".join(parts)


def write_results(path: str | Path, result: GradeResult) -> Path:
    """Write Gradescope's results.json to ``path`` (its folder made if need be) and return the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(to_gradescope(result), indent=2))
    return path


def format_table(result: GradeResult, width: int = 100) -> str:
    """The per-test table printed by ``cs451 grade``: failures first (in test order), every failure's message
    whole, wrapped under its test, then the tests that passed.

    Its totals count the visible tests; with hidden tests graded, one more line (the grader's) counts them too."""
    import textwrap
    from .report import failures_first
    indent = " " * 27
    lines = [f"{'test':<7} {'points':>11}  {'':4} name / message", "-" * width]
    for r in failures_first(result.results):
        t = r.test
        mark = "ok" if r.verdict.passed else ("part" if r.score > 0 else "FAIL")
        hidden = " [hidden]" if t.hidden else (" [optional]" if t.extension else "")
        lines.append(f"{t.number:<7} {r.score:>5g} / {t.points:<3g}  {mark:4} {printable(t.name, lines=False)}{hidden}")
        if not r.verdict.passed:
            lines += textwrap.wrap(printable(r.verdict.message, lines=False), width, initial_indent=indent,
                                   subsequent_indent=indent, break_long_words=True, break_on_hyphens=False)
    lines.append("-" * width)
    visible = [r for r in result.graded if not r.test.hidden]
    held = len(visible) < len(result.graded)
    by_task: dict[str, list[float]] = {}
    for r in visible + [r for r in result.extensions if not r.test.hidden]:
        acc = by_task.setdefault(r.test.task, [0.0, 0.0])
        acc[0] += r.score
        acc[1] += r.test.points
    lines.append(f"by task{' (visible tests)' if held else ''}: " +
                 "  ".join(f"{k} {v[0]:g}/{v[1]:g}" for k, v in by_task.items()))
    seconds = f"   ({result.seconds:.1f} s)"
    lines.append(f"total: {sum(r.score for r in visible):g} / {sum(r.test.points for r in visible):g}"
                 + (" on the visible tests" if held else seconds))
    if result.extensions:
        from .report import extension_line
        lines.append(extension_line(result))
    if held:   # the time too counts the hidden tests
        lines.append(f"total with the hidden tests: {result.score:g} / {result.max_score:g}{seconds} "
                     "(a student sees it once grades are published)")
    if result.isolation:
        lines.append(f"isolation: {printable(result.isolation, lines=False)}")
    if result.hidden_not_run.get("count"):
        from .report import hidden_note
        lines.append(f"not run here: {hidden_note(result)}")
    for p in result.problems:
        lines.append(f"problem: {printable(p, lines=False)}")
    return printable("\n".join(lines))


def write_failure(path: str | Path, reason: str, blame_submission: bool = False) -> Path:
    """The results file when grading could not finish: zero points, and why.

    ``blame_submission``: the upload itself is unusable (no stage package in it), which the student can fix.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    reason = printable(reason)
    if blame_submission:
        text = f"Your submission could not be graded: {reason}"
    else:
        text = (f"The autograder could not finish: {reason}\n"
                "This is not a verdict on your code; tell your instructor.")
    path.write_text(json.dumps({"score": 0, "output": text, "visibility": "visible", "tests": []}, indent=2))
    return path
