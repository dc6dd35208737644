"""The starter is derived from reference/ by a pure function that fails loudly, and is kept in step."""
from __future__ import annotations

import pytest

from cs451.errors import KitError
from cs451.impl import load_impl, resolve_impl
from cs451.starter import check_starter, replace_solutions


def test01_region_in_a_function_becomes_a_stub():
    src = ["def f(x):", "    '''doc'''", "    # BEGIN SOLUTION S9: double it (handout §S9)", "    return 2 * x",
           "    # END SOLUTION", "", "y = 1"]
    out = replace_solutions(src)
    assert out == ["def f(x):", "    '''doc'''", "    # TODO S9: double it (handout §S9)",
                   '    raise NotImplementedError("S9: double it (handout §S9)")', "", "y = 1"]


def test02_module_level_region_is_removed():
    assert replace_solutions(["a = 1", "# BEGIN SOLUTION", "SECRET = 42", "# END SOLUTION", "b = 2"]) == ["a = 1", "b = 2"]


@pytest.mark.parametrize("src, message", [
    (["    # BEGIN SOLUTION S1: x", "    # BEGIN SOLUTION S2: y", "    # END SOLUTION"], "inside the region opened at line 1"),
    (["    # END SOLUTION"], "without a BEGIN"),
    (["    # BEGIN SOLUTION S1: x", "pass"], "never closed"),
    (["    # BEGIN SOLUTION", "    pass", "    # END SOLUTION"], "needs an ID and a hint"),
])
def test03_bad_markers_fail_loudly(src, message):
    with pytest.raises(KitError, match=message):
        replace_solutions(src, "f.py")


def test04_starter_is_in_step_with_reference():
    assert check_starter() == [], "run `cs451 starter` to regenerate starter/"


def test05_starter_imports_and_every_task_is_a_stub():
    from cs451.stages import get_stage
    stage = get_stage("sphere")
    module = load_impl(resolve_impl("starter", "sphere"), "sphere")
    for task in stage.tasks:
        fn = getattr(module, task.function)
        with pytest.raises(NotImplementedError, match=task.id):
            fn(*[None] * len(task.params))


def test06_starter_holds_no_solution_text(kit_root):
    starter = "".join(p.read_text() for p in (kit_root / "starter").rglob("*.py"))
    assert "fixed_function_lighting" not in starter and "BEGIN SOLUTION" not in starter


def test07_a_module_left_with_only_its_docstring_is_not_in_the_starter(tmp_path):
    """The reference's speed-ups are one solution region each; a student gets no empty file in their place."""
    from cs451.starter import generate_starter
    reference = tmp_path / "reference" / "toy"
    reference.mkdir(parents=True)
    (reference / "__init__.py").write_text('"""Toy."""\n')
    (reference / "fast.py").write_text('"""Compiled loops."""\nfrom __future__ import annotations\n'
                                       '# BEGIN SOLUTION\nimport math\nX = math.pi\n# END SOLUTION\n')
    (reference / "plain.py").write_text('"""Plain."""\n\n\ndef f():\n    # BEGIN SOLUTION T1: do it\n    return 1\n'
                                        '    # END SOLUTION\n')
    written = generate_starter(tmp_path / "reference", tmp_path / "starter")
    assert sorted(written) == ["toy/__init__.py", "toy/plain.py"]
    assert not (tmp_path / "starter" / "toy" / "fast.py").exists()
