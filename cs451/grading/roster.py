"""Grading a class: every submission in a folder, in parallel, into a gradebook CSV and one report each."""
from __future__ import annotations

import csv
import os
from concurrent.futures import ThreadPoolExecutor, as_completed
from pathlib import Path

from ..errors import KitError
from ..progress import Progress
from ..stages import get_stage
from .report import write_report
from .results import write_failure, write_results
from .runner import GradeResult, grade


def find_submissions(roster: Path) -> list[Path]:
    """Each sub-folder of ``roster`` is one student's submission, named after the student."""
    if not roster.is_dir():
        raise KitError(f"{roster}: roster folder not found")
    subs = sorted(p for p in roster.iterdir() if p.is_dir() and not p.name.startswith("."))
    if not subs:
        raise KitError(f"{roster}: no submission folders in it (expected one folder per student)")
    return subs


def grade_roster(*, stage: str, roster: str | Path, output: str | Path, include_hidden: bool = True,
                 parallel: int | None = None, show_progress: bool = True) -> Path:
    """Grade every submission under ``roster``; write ``output/gradebook.csv`` and ``output/<student>/``."""
    roster, output = Path(roster), Path(output)
    tasks = [t.id for t in get_stage(stage).tasks]
    subs = find_submissions(roster)
    output.mkdir(parents=True, exist_ok=True)
    bar = Progress(f"grading {len(subs)} submissions", len(subs), delay=0.0) if show_progress else None
    rows: dict[str, dict] = {}

    def one(sub: Path) -> dict:
        folder = output / sub.name
        try:
            result = grade(stage, sub, include_hidden=include_hidden, show_progress=False, jobs=1)
        except Exception as err:  # one broken submission (or folder) never stops the batch
            write_failure(folder / "results.json", f"{type(err).__name__}: {err}")
            return {"student": sub.name, "score": 0, "max_score": "", "seconds": "", "problems": str(err)}
        write_results(folder / "results.json", result)
        write_report(folder, result)
        return _row(sub.name, result, tasks)

    workers = parallel or max(1, (os.cpu_count() or 1))
    with ThreadPoolExecutor(max_workers=workers) as pool:
        for future in as_completed([pool.submit(one, s) for s in subs]):
            row = future.result()
            rows[row["student"]] = row
            if bar:
                bar.advance(note=row["student"])
    if bar:
        bar.close()
    path = output / "gradebook.csv"
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=["student", "score", "max_score", *tasks, "seconds", "problems"])
        writer.writeheader()
        for name in sorted(rows):
            writer.writerow(rows[name])
    return path


def _row(name: str, result: GradeResult, tasks: list[str]) -> dict:
    per_task = {t: 0.0 for t in tasks}
    for r in result.results:
        per_task[r.test.task] += r.score
    return {"student": name, "score": round(result.score, 2), "max_score": result.max_score,
            **{k: round(v, 2) for k, v in per_task.items()}, "seconds": round(result.seconds, 1),
            "problems": "; ".join(result.problems)}
