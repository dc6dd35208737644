"""The reference's answers to a stage's tests, computed ahead of time.

Gradescope runs every submission in a fresh container, so answers computed while
grading would be computed again for each of 300 students: ``setup.sh`` warms the
cache once, when the image is built. A student copy has no reference at all, so
it ships the answers to the public tests instead.
"""
from __future__ import annotations

import shutil
from pathlib import Path

from ..grading.runner import ReferenceAnswers, load_tests
from ..grading.spec import Test
from ..progress import Progress


def answer_files(stage: str, tests: list[Test] | None = None, show_progress: bool = False) -> list[Path]:
    """Compute (or find in the cache) the reference's answer for every test that needs one; their files."""
    tests = load_tests(stage) if tests is None else tests
    reference = ReferenceAnswers(stage)
    files: list[Path] = []
    bar = Progress(f"reference answers for {stage}", len(tests)) if show_progress else None
    for t in tests:
        given = None
        if t.given:
            given = reference.get(t.given, t.params)
            files.append(reference.path(t.given, t.params))
        if t.expected == "reference":
            reference.get(t.probe, t.params, given)
            files.append(reference.path(t.probe, t.params, given))
        if bar:
            bar.advance(note=t.number)
    if bar:
        bar.close()
    return sorted(set(files))


def export_answers(stage: str, tests: list[Test], dest: Path) -> list[Path]:
    """Copy the answers to ``tests`` into ``dest`` (a student copy's ``autograder/<stage>/answers``)."""
    dest.mkdir(parents=True, exist_ok=True)
    return [Path(shutil.copy2(f, dest / f.name)) for f in answer_files(stage, tests)]
