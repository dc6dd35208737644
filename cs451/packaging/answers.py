"""The answers a stage's tests compare with, computed ahead of time.

Gradescope runs every submission in a fresh container, so answers computed while
grading would be computed again for each of 300 students: ``setup.sh`` warms the
cache once, when the image is built: the answers to the hidden tests and to the fresh
cases of the public tests, made from the image's own secret (``setup.sh`` makes a new
one for each image). A student copy has neither the reference nor the truths: it ships
their answers to the shipped public cases instead, as arrays.
"""
from __future__ import annotations

import shutil
from pathlib import Path

from ..grading.expected import ReferenceAnswers, TruthValues, expected_for
from ..grading.loader import load_tests, variant_secret
from ..grading.spec import Test
from ..progress import Progress


def answer_files(stage: str, tests: list[Test] | None = None, show_progress: bool = False) -> list[Path]:
    """Compute (or find in the cache) every answer the tests need: the reference's and the truths'; their files.

    ``tests``: by default what the kit grades, the hidden tests and the public tests on their fresh cases."""
    tests = load_tests(stage, secret=variant_secret()) if tests is None else tests
    reference = ReferenceAnswers(stage)
    truths = TruthValues(stage)
    files: list[Path] = []
    bar = Progress(f"answers for {stage}", len(tests)) if show_progress else None
    for t in tests:
        given, _ = expected_for(t, reference, truths)
        if t.given:
            files.append(reference.path(t.given, t.params))
        if t.expected == "reference":
            files.append(reference.path(t.probe, t.params, given))
        if t.truth is not None:
            files.append(truths.path(t))
        if bar:
            bar.advance(note=t.number)
    if bar:
        bar.close()
    return sorted(set(files))


def export_answers(stage: str, tests: list[Test], dest: Path) -> list[Path]:
    """Copy the answers to ``tests`` into ``dest`` (a student copy's ``autograder/<stage>/answers``)."""
    dest.mkdir(parents=True, exist_ok=True)
    return [Path(shutil.copy2(f, dest / f.name)) for f in answer_files(stage, tests)]
