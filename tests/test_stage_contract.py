"""The contract every stage keeps, checked over every registered stage (a new stage is checked by being added).

- the reference scores full marks and the starter zero, with a hint on every test;
- a submission with one task's function replaced by a stub loses that task's points, and keeps every
  point of a test that neither grades that task nor declares it in ``depends_on``;
- the student release holds no solution, no hidden test and no truth.
"""
from __future__ import annotations

import ast
import importlib
import json
from pathlib import Path

import pytest

from cs451 import KIT_ROOT
from cs451.grading.loader import load_tests
from cs451.grading.runner import grade
from cs451.packaging.release import build_release
from cs451.stages import get_stage, stage_names

STAGES = stage_names()


def stub_out(package: Path, function: str) -> Path:
    """Replace the body of ``def function`` in a package with ``raise NotImplementedError`` (signature and
    docstring stay, so the submission still loads and only this function is broken)."""
    for path in sorted(package.glob("*.py")):
        text = path.read_text()
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.FunctionDef) and node.name == function:
                body = node.body
                if isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) and len(body) > 1:
                    body = body[1:]                           # keep the docstring
                first = body[0]
                start = min([first.lineno] + [d.lineno for d in getattr(first, "decorator_list", [])]) - 1
                lines = text.splitlines(keepends=True)
                lines[start:node.end_lineno] = [f"{' ' * first.col_offset}raise NotImplementedError("
                                                f"'{function}: stubbed by the contract test')\n"]
                path.write_text("".join(lines))
                return path
    raise AssertionError(f"no def {function} in {package}")


def relies_on(tests: list) -> dict[str, set[str]]:
    """Each test's tasks it runs as the submission's own: its ``depends_on``, and what their tests rely on in
    turn (W11 runs your W5, whose tests run your W2)."""
    by_task: dict[str, set[str]] = {}
    for t in tests:
        by_task.setdefault(t.task, set()).update(t.depends_on)
    def closure(tasks: set[str]) -> set[str]:
        seen: set[str] = set()
        while tasks - seen:
            task = (tasks - seen).pop()
            seen.add(task)
            tasks = tasks | by_task.get(task, set())
        return seen
    return {t.number: closure(set(t.depends_on)) for t in tests}


@pytest.mark.spawns
@pytest.mark.parametrize("stage", STAGES)
def test_the_reference_scores_full_marks(stage, reference_grade_of):
    result = reference_grade_of(stage)
    failed = [(r.test.number, r.verdict.message) for r in result.results if not r.verdict.passed]
    assert failed == [] and result.score == result.max_score == 100


@pytest.mark.spawns
@pytest.mark.parametrize("stage", STAGES)
def test_the_starter_scores_zero_with_a_hint_per_test(stage):
    result = grade(stage, "starter", show_progress=False)
    assert result.score == 0 and result.max_score == 100
    for r in result.results:
        assert "not implemented yet" in r.verdict.message, (r.test.number, r.verdict.message)


@pytest.mark.spawns
@pytest.mark.slow
@pytest.mark.parametrize("stage, task", [(s, t.id) for s in STAGES for t in get_stage(s).tasks])
def test_a_task_stubbed_alone_loses_only_its_points(stage, task, make_submission, reference_grade_of):
    sub = make_submission(stage)
    stub_out(sub / stage, get_stage(stage).task(task).function)
    result = grade(stage, sub, show_progress=False)
    full = {r.test.number: r.score for r in reference_grade_of(stage).results}
    relies = relies_on(load_tests(stage))
    for r in result.results:
        if r.test.task == task:
            assert r.score == 0, (r.test.number, r.verdict.message)
        elif task not in relies[r.test.number]:
            assert r.score == full[r.test.number], (r.test.number, r.verdict.message)
        else:
            named = any(f"{t} " in r.verdict.message for t in relies[r.test.number])   # "fix W5 closest_hit() first"
            assert named or r.score == full[r.test.number], (r.test.number, r.verdict.message)


@pytest.mark.parametrize("stage", STAGES)
def test_the_stage_names_a_least_answer_for_every_task(stage):
    """The attack tests grade a submission made of these (tests/adversaries.py: it must score 0), so every task has
    one, in the stage's own package, and each is the body of a function that compiles."""
    answers = importlib.import_module(f"cs451.stages.{stage}.adversary")
    assert set(answers.NOTHING) == {t.id for t in get_stage(stage).tasks}
    compile(answers.HEADER, "HEADER", "exec")
    for task in get_stage(stage).tasks:
        compile(f"def {task.function}({', '.join(task.params)}):\n    {answers.NOTHING[task.id]}\n", task.id, "exec")


@pytest.mark.parametrize("stage", STAGES)
def test_the_release_holds_no_solution_no_hidden_test_and_no_truth(stage, tmp_path):
    out = build_release(stage, tmp_path / "repo")
    files = {p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file()}
    assert not [f for f in files if f.startswith("reference/") or f.endswith(("hidden.py", "truth.py", "public.py"))]
    assert [f for f in files if f.startswith(f"autograder/{stage}/answers/")]
    assert f"{stage}/__init__.py" in files and ".github/workflows/classroom.yml" in files
    from cs451 import ENGINE_DIR, instructor_only           # benchmarks, deck figures, speed layers: instructors'
    assert not [f for f in files if f.startswith("cs451/") and instructor_only(ENGINE_DIR.parent / f)]
    starter = KIT_ROOT / "starter" / stage
    for path in starter.rglob("*.py"):
        assert (out / stage / path.relative_to(starter)).read_text() == path.read_text(), path.name
    shipped_tests = json.loads((out / "autograder" / stage / "public.json").read_text())["tests"]
    public = [t for t in load_tests(stage) if not t.hidden]
    assert sorted((t["name"], t["points"]) for t in shipped_tests) == sorted((t.name, t.points) for t in public)
