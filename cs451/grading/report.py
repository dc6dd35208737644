"""A self-contained HTML report: reference, submission, difference and error map side by side per image test.

Like Stanford draw-svg's reference-and-diff viewer, but a single file a student
can open offline or an instructor can attach to a grade.
"""
from __future__ import annotations

import base64
import html
import io
from pathlib import Path

import numpy as np
from PIL import Image as PILImage

from .runner import GradeResult

STYLE = """
body{font-family:system-ui,sans-serif;margin:2em;max-width:1200px;color:#222}
table{border-collapse:collapse;margin:1em 0}td,th{padding:.3em .7em;border-bottom:1px solid #ddd;text-align:left}
.ok{color:#17803d}.fail{color:#b42318}.part{color:#b54708}.muted{color:#666}
.imgs{display:flex;gap:1em;flex-wrap:wrap}.imgs figure{margin:0}.imgs img{image-rendering:pixelated;max-width:270px;border:1px solid #ccc}
figcaption{font-size:.85em;color:#555}section{margin:1.5em 0;padding-top:.5em;border-top:1px solid #eee}
code{background:#f4f4f4;padding:0 .2em}
"""
CAPTIONS = {"reference": "reference (as <code>cs451 render</code> writes it)",
            "submission": "yours (as <code>cs451 render</code> writes it)",
            "difference": "|difference| × 4, linear: black where they agree",
            "error": "error map after the 3×3 allowance: black where equal, yellow up to the threshold, red over it"}


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


def render_report(result: GradeResult, show_hidden: bool = True) -> str:
    """The report as HTML; with ``show_hidden=False`` hidden tests are counted, not shown (the student's view)."""
    esc = html.escape
    shown = [r for r in result.results if show_hidden or not r.test.hidden]
    score = sum(r.score for r in shown)
    total = sum(r.test.points for r in shown)
    parts = [f"<!doctype html><meta charset=utf-8><title>cs451 {esc(result.stage)}: {score:g}/{total:g}</title>",
             f"<style>{STYLE}</style>",
             f"<h1>Stage {esc(result.stage)}: {score:g} / {total:g} points</h1>",
             f"<p class=muted>submission <code>{esc(result.submission)}</code>, graded in {result.seconds:.1f} s</p>"]
    note = hidden_note(result, show_hidden)
    if note:
        parts.append(f"<p><b>{esc(note)}</b></p>")
    if result.problems:
        parts.append("<h2>Problems found before testing</h2><ul>" +
                     "".join(f"<li>{esc(p)}</li>" for p in result.problems) + "</ul>")
    parts.append("<table><tr><th>test</th><th>points</th><th></th><th>name</th><th>tolerance</th></tr>")
    for r in shown:
        cls, word = _status(r)
        tag = " <span class=muted>(hidden)</span>" if r.test.hidden else ""
        parts.append(f"<tr><td><a href='#t{esc(r.test.number)}'>{esc(r.test.number)}</a></td>"
                     f"<td>{r.score:g} / {r.test.points:g}</td><td class={cls}>{word}</td>"
                     f"<td>{esc(r.test.name)}{tag}</td><td class=muted>{esc(r.test.tolerance)}</td></tr>")
    parts.append("</table>")
    failed = [r for r in shown if not r.verdict.passed]
    passed = [r for r in shown if r.verdict.passed]
    parts += [_section(r) for r in failed]           # failures first: what a student came to see
    if passed:
        parts.append(f"<details><summary>{len(passed)} passing test{'s' if len(passed) != 1 else ''}</summary>")
        parts += [_section(r) for r in passed]
        parts.append("</details>")
    return "\n".join(parts)


def _section(r) -> str:
    esc = html.escape
    cls, word = _status(r)
    parts = [f"<section id='t{esc(r.test.number)}'><h3>{esc(r.test.number)} {esc(r.test.name)} "
             f"<span class={cls}>{word}</span></h3><p>{esc(r.verdict.message)}</p>"]
    if r.verdict.images:
        parts.append("<div class=imgs>")
        for key in ("reference", "submission", "difference", "error"):
            if key in r.verdict.images:
                parts.append(f"<figure><img src='{_png_data_uri(r.verdict.images[key])}' alt='{key}'>"
                             f"<figcaption>{CAPTIONS[key]}</figcaption></figure>")
        parts.append("</div>")
    if r.output.strip():
        parts.append(f"<details><summary>your code printed</summary><pre>{esc(r.output)}</pre></details>")
    parts.append("</section>")
    return "".join(parts)


def write_report(folder: str | Path, result: GradeResult, show_hidden: bool = True) -> Path:
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "report.html"
    path.write_text(render_report(result, show_hidden))
    return path
