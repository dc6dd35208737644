"""Each stage keeps its grading tolerances in one table (``cs451/stages/<stage>/tolerances.py``), each with why it has
its value; the stage's checks and tests use the table's names, never a number of their own, and their descriptions
print the same names, so what a test says and what it checks cannot drift apart (issue 35)."""
from __future__ import annotations

import ast
import importlib
import pickle
import re

import pytest

from cs451 import KIT_ROOT
from cs451.stages import stage_names
from cs451.stages.base import Tolerance, tolerance_table

STAGES = stage_names()
#: the parameters that hold a tolerance wherever the grading code passes or declares one
TOLERANCE_NAMES = {"rtol", "atol", "rel", "within", "max_bad", "min_same", "tol"}


def grading_files(stage: str) -> list:
    return [KIT_ROOT / "autograder" / stage / f"{name}.py" for name in ("checks", "public", "hidden")
            if (KIT_ROOT / "autograder" / stage / f"{name}.py").is_file()]


@pytest.mark.parametrize("stage", STAGES)
def test_every_tolerance_says_why(stage):
    table = tolerance_table(importlib.import_module(f"cs451.stages.{stage}.tolerances"))
    assert table, f"{stage}: no tolerances"
    for name, value in table.items():
        assert len(value.why) >= 40, (stage, name, value.why)
        assert 0 < value < 1, (stage, name)


def literal_tolerances(tree: ast.AST) -> list[str]:
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.keyword) and node.arg in TOLERANCE_NAMES and isinstance(node.value, ast.Constant) \
                and isinstance(node.value.value, float) and node.value.value:
            found.append(f"line {node.value.lineno}: {node.arg}={node.value.value}")
        if isinstance(node, (ast.FunctionDef, ast.Lambda)):
            args = node.args.args[len(node.args.args) - len(node.args.defaults):]
            for arg, default in zip(args, node.args.defaults):
                if arg.arg in TOLERANCE_NAMES and isinstance(default, ast.Constant) and isinstance(default.value, float):
                    found.append(f"line {default.lineno}: default {arg.arg}={default.value}")
        if isinstance(node, ast.Compare):
            for side in [node.left, *node.comparators]:
                if isinstance(side, ast.Constant) and isinstance(side.value, float) and 0 < side.value < 1e-2:
                    found.append(f"line {side.lineno}: compared with {side.value}")
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and re.search(r"within \d(\.\d+)?e-\d", node.value):
            found.append(f"line {node.lineno}: a description with its own number: {node.value[:60]!r}")
    return found


@pytest.mark.parametrize("stage", STAGES)
def test_the_grading_code_takes_its_tolerances_from_the_table(stage):
    found = {path.name: literal_tolerances(ast.parse(path.read_text())) for path in grading_files(stage)}
    assert not any(found.values()), found


def test_the_scan_finds_a_tolerance_of_its_own():
    code = 'def f(out, rel: float = 1e-9):\n    if err > 1e-6: pass\n    np.allclose(a, b, rtol=1e-9)\n    x = "within 1e-9"\n'
    assert len(literal_tolerances(ast.parse(code))) == 4


def test_a_tolerance_prints_and_travels_as_its_number():
    tol = Tolerance(1e-9, "because")
    assert f"{tol}" == "1e-9" and f"{Tolerance(5e-3, 'x')}" == "5e-3" and f"{Tolerance(0.99, 'x'):.0%}" == "99%"
    back = pickle.loads(pickle.dumps(tol))
    assert back == 1e-9 and back.why == "because" and 2 * tol == 2e-9
