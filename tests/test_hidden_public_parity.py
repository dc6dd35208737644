"""Every hidden test has a public test of the same form (docs/grading.md: a student can prepare for every kind of
case the hidden tests hold, not for their numbers).

A test's form: its task, probe, check (by name, and the names of its settings), trusted inputs, truth and fresh-case
maker, and the shape of its parameters: the same names, and each scalar in the same class (0, negative or
positive; a flag or a word by its value), and its fresh-case maker's settings in the same classes. A hidden test that overshoots (ω = 1.5) with a tolerance that
stops the loop needs a public one that does both; one on a scene (a dict) needs a public one on a scene.
"""
from __future__ import annotations

from typing import Any

import pytest

from cs451.grading.loader import load_tests
from cs451.stages import stage_names


def _class(value: Any) -> Any:
    if isinstance(value, bool) or isinstance(value, str):
        return value
    if isinstance(value, (int, float)):
        return "0" if value == 0 else "negative" if value < 0 else "positive"
    return type(value).__name__


def form(test) -> tuple:
    ref = lambda r: None if r is None else (r.module, r.name, tuple(sorted(r.kwargs)))
    vary = None if test.vary is None else (test.vary.module, test.vary.name,
                                           tuple(sorted((k, _class(v)) for k, v in test.vary.kwargs.items())))
    return (test.task, test.probe, ref(test.check), test.given, test.expected, ref(test.truth), vary, test.edge_case,
            tuple(sorted((k, _class(v)) for k, v in test.params.items())))


@pytest.mark.parametrize("stage", stage_names())
def test01_every_hidden_test_has_a_public_twin(stage):
    tests = load_tests(stage)
    public = {form(t) for t in tests if not t.hidden}
    lonely = [f"{t.number} {t.name}: {form(t)}" for t in tests if t.hidden and form(t) not in public]
    assert not lonely, "hidden tests with no public test of the same form:\n" + "\n".join(lonely)


def test02_the_form_tells_what_the_issue_found():
    """The frozen-keys case (a tolerance reached with overshooting) differs in form from an overshoot without one."""
    tests = {t.name: t for t in load_tests("radiosity")}
    closed = next(t for n, t in tests.items() if "closed random system, overshooting" in n)
    overshoot_only = next(t for n, t in tests.items() if "hand-worked scene overshooting" in n)
    assert form(closed) != form(overshoot_only)
