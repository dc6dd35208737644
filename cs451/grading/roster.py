"""Grading a class: every submission in a folder, in parallel, into a gradebook CSV and one report each.

Each submission is graded in a process of its own (one that crashes takes no
classmate with it), in its own sandbox, with the roster folder and the output
folder on the list of what no submission may read. Where the sandbox cannot give
each test its own namespaces (the uid-only fallback, see :mod:`.sandbox`), one
submission is graded at a time, so no two students' code ever runs together.
"""
from __future__ import annotations

import csv
import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

from ..errors import KitError
from ..progress import Progress
from ..stages import get_stage
from .report import write_report
from .results import write_failure, write_results
from .runner import GradeResult, grade
from .untrusted import printable


def find_submissions(roster: Path) -> list[Path]:
    """Each sub-folder of ``roster`` is one student's submission, named after the student."""
    if not roster.is_dir():
        raise KitError(f"{roster}: roster folder not found")
    subs = sorted(p for p in roster.iterdir() if p.is_dir() and not p.name.startswith("."))
    if not subs:
        raise KitError(f"{roster}: no submission folders in it (expected one folder per student)")
    return subs


def grade_roster(*, stage: str, roster: str | Path, output: str | Path, include_hidden: bool = True,
                 parallel: int | None = None, show_progress: bool = True, only: list[str] | None = None) -> Path:
    """Grade every submission under ``roster``; write ``output/gradebook.csv`` and ``output/<student>/``."""
    roster, output = Path(roster), Path(output)
    tasks = [t.id for t in get_stage(stage).tasks]
    subs = find_submissions(roster)
    output.mkdir(parents=True, exist_ok=True)
    bar = Progress(f"grading {len(subs)} submissions", len(subs), delay=0.0) if show_progress else None
    rows: dict[str, dict] = {}

    protected = (roster.resolve(), output.resolve())
    workers = 1 if not _namespaces_available() else (parallel or max(1, (os.cpu_count() or 1)))
    # a clean process to fork from: a grader that has run threaded native code (ꟻLIP in a report, llvmpipe)
    # cannot fork safely; the forkserver has run none of it
    context = multiprocessing.get_context("forkserver" if "forkserver" in multiprocessing.get_all_start_methods() else "spawn")
    with ProcessPoolExecutor(max_workers=workers, mp_context=context) as pool:
        futures = {pool.submit(_grade_one, stage, sub, output / sub.name, include_hidden, tasks, protected, only): sub
                   for sub in subs}
        for future in as_completed(futures):
            sub = futures[future]
            try:
                row = future.result()
            except Exception as err:  # the student's grader process itself died: a row all the same
                write_failure(output / sub.name / "results.json", f"{type(err).__name__}: {err}")
                row = {"student": sub.name, "score": 0, "max_score": "", "seconds": "", "problems": str(err)}
            rows[row["student"]] = row
            if bar:
                bar.advance(note=row["student"])
    if bar:
        bar.close()
    path = output / "gradebook.csv"
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=["student", "score", "max_score", *tasks, "extension", "seconds", "problems"])
        writer.writeheader()
        for name in sorted(rows):
            writer.writerow({k: spreadsheet_safe(v) for k, v in rows[name].items()})
    return path


def spreadsheet_safe(value: object) -> object:
    """A cell a spreadsheet shows as text, on one line: control and bidi characters escaped (``printable``), and a
    leading = + - @ (a formula) quoted with an apostrophe."""
    if not isinstance(value, str):
        return value
    value = printable(value, lines=False)
    return "'" + value if value[:1] in ("=", "+", "-", "@") else value


def _namespaces_available() -> bool:
    from .sandbox import namespaces_work
    return namespaces_work()


def _grade_one(stage: str, sub: Path, folder: Path, include_hidden: bool, tasks: list[str],
               protected: tuple[Path, ...], only: list[str] | None) -> dict:
    """In a grading process of its own: one submission's results, report and gradebook row."""
    try:
        result = grade(stage, sub, include_hidden=include_hidden, show_progress=False, jobs=1, protected=protected,
                       tasks=only)
    except Exception as err:  # one broken submission (or folder) never stops the batch
        write_failure(folder / "results.json", f"{type(err).__name__}: {err}")
        return {"student": sub.name, "score": 0, "max_score": "", "seconds": "", "problems": str(err)}
    write_results(folder / "results.json", result)
    write_report(folder, result)
    return _row(sub.name, result, tasks)


def _row(name: str, result: GradeResult, tasks: list[str]) -> dict:
    per_task = {t: 0.0 for t in tasks}
    for r in result.results:
        per_task[r.test.task] += r.score
    return {"student": name, "score": round(result.score, 2), "max_score": result.max_score,
            **{k: round(v, 2) for k, v in per_task.items()}, "extension": round(result.extension_score, 2),
            "seconds": round(result.seconds, 1),
            "problems": "; ".join(result.problems)}
