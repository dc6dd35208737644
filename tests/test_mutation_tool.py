"""The mutation bench's planting (bench/mutation.py): changes only inside task regions, at the right place, and
every mutant still a program; a planted mistake graded on its own task loses points."""
from __future__ import annotations

import ast

import pytest

import bench.mutation as mutation
from bench.mutation import GraderFailed, apply, mutants_of, stage_mutants, task_score

SOURCE = '''import numpy as np

LIMIT = 3   # outside every region: never mutated


def f(x, y):
    # BEGIN SOLUTION T1: a comparison, an operator, a constant, a sign
    if x < y:
        return -x + 2 * y
    total = 0
    total += x
    return total
    # END SOLUTION


def g(x):
    # BEGIN SOLUTION
    return x + 1
    # END SOLUTION
'''


def test01_only_task_regions_and_each_kind_once_where_expected():
    mutants = mutants_of(SOURCE, "toy", "toy.py")
    assert {m.task for m in mutants} == {"T1"}
    assert all(8 <= m.line <= 12 for m in mutants), [m.line for m in mutants]
    kinds = {(m.kind, m.before, m.after) for m in mutants}
    assert ("comparison", "<", "<=") in kinds
    assert ("operator", "+", "-") in kinds and ("operator", "*", "/") in kinds
    assert ("constant", "2", "3") in kinds and ("constant", "0", "1") in kinds
    assert ("sign dropped", "-", "") in kinds
    assert ("term dropped", " + 2 * y", "") in kinds
    assert ("statement dropped", "total += x", "pass") in kinds


def test02_every_mutant_is_a_program_that_differs_from_the_source():
    for m in mutants_of(SOURCE, "toy", "toy.py"):
        text = SOURCE[:m.start] + m.after + SOURCE[m.end:]
        assert text != SOURCE
        ast.parse(text)


def test03_the_reference_has_mutants_in_every_task_with_code():
    from cs451.stages import get_stage
    tasks = {m.task for m in stage_mutants("radiosity")}
    assert tasks == {t.id for t in get_stage("radiosity").tasks}    # R7, the optional extension, included


@pytest.mark.spawns
def test03b_a_mistake_in_an_optional_extension_loses_its_points_though_the_grade_holds_none(tmp_path):
    """R7 (optional) with its overshoot dropped: its points travel in results.json's extra_data, not its score."""
    mutant = next(m for m in stage_mutants("radiosity")
                  if m.task == "R7" and m.kind == "statement dropped" and m.before.startswith("unshot[i] = overshoot"))
    got, full = task_score("radiosity", apply(mutant, tmp_path), "R7")
    assert full == 5 and got < full


@pytest.mark.spawns
def test04_a_planted_mistake_loses_its_tasks_points(tmp_path):
    """R2 with the area ratio inverted (A_i / A_j becomes A_i * A_j) scores below full marks on R2."""
    mutant = next(m for m in stage_mutants("radiosity") if m.task == "R2" and m.kind == "operator" and m.before == "/")
    got, full = task_score("radiosity", apply(mutant, tmp_path), "R2")
    assert full > 0 and got < full


def test05_a_mutant_the_grader_wrote_nothing_for_is_not_graded_never_killed(monkeypatch):
    """A kit that cannot start (a broken import while the checkout changes) once counted every mutant as killed."""
    def broken(stage, submission, task):
        raise GraderFailed("exit 1: ImportError")
    monkeypatch.setattr(mutation, "task_score", broken)
    report = mutation.run("radiosity", sample=2, progress=lambda line: None)
    assert report["errors"] == 2 and report["killed"] == 0 and not any(r["killed"] for r in report["rows"])
