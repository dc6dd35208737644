"""Grading results as Gradescope's results.json and as a terminal table.

Gradescope's format (https://gradescope-autograders.readthedocs.io, "Output format"):
top-level ``score``, ``execution_time``, ``output``, ``visibility``, ``stdout_visibility``
and a list of ``tests`` each with ``score``, ``max_score``, ``status``, ``name``,
``number``, ``output``, ``tags`` and ``visibility``.
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from .runner import GradeResult


def to_gradescope(result: GradeResult) -> dict[str, Any]:
    tests = []
    for r in result.results:
        t = r.test
        output = r.verdict.message
        if r.output.strip():
            output += "\n\nYour code printed:\n" + r.output.strip()
        tests.append({"score": r.score, "max_score": t.points, "status": "passed" if r.verdict.passed else "failed",
                      "name": t.name, "number": t.number, "output": output, "tags": [t.task],
                      "visibility": t.visibility})
    summary = f"{result.score:g} / {result.max_score:g} points"
    if result.problems:
        summary += "\nProblems found before testing:\n" + "\n".join(f"- {p}" for p in result.problems)
    return {"score": round(result.score, 4), "execution_time": round(result.seconds, 2), "output": summary,
            "visibility": "visible", "stdout_visibility": "hidden", "tests": tests}


def write_results(path: str | Path, result: GradeResult) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(to_gradescope(result), indent=2))
    return path


def format_table(result: GradeResult, width: int = 100) -> str:
    """The per-test table printed by ``cs451 grade``."""
    lines = [f"{'test':<7} {'points':>11}  {'':4} name / message", "-" * width]
    for r in result.results:
        t = r.test
        mark = "ok" if r.verdict.passed else ("part" if r.score > 0 else "FAIL")
        hidden = " [hidden]" if t.hidden else ""
        lines.append(f"{t.number:<7} {r.score:>5g} / {t.points:<3g}  {mark:4} {t.name}{hidden}")
        if not r.verdict.passed:
            msg = r.verdict.message
            lines.append(f"{'':27}{msg if len(msg) < width - 27 else msg[:width - 30] + '...'}")
    lines.append("-" * width)
    by_task: dict[str, list[float]] = {}
    for r in result.results:
        acc = by_task.setdefault(r.test.task, [0.0, 0.0])
        acc[0] += r.score
        acc[1] += r.test.points
    lines.append("by task: " + "  ".join(f"{k} {v[0]:g}/{v[1]:g}" for k, v in by_task.items()))
    lines.append(f"total: {result.score:g} / {result.max_score:g}   ({result.seconds:.1f} s)")
    for p in result.problems:
        lines.append(f"problem: {p}")
    return "\n".join(lines)


def write_failure(path: str | Path, reason: str) -> Path:
    """The results file when grading itself could not finish: zero points, and why."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({"score": 0, "output": f"The autograder could not finish: {reason}\n"
                                "This is not a verdict on your code; tell your instructor.",
                                "visibility": "visible", "tests": []}, indent=2))
    return path
