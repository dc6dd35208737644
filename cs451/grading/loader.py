"""Finding a stage's tests: the spec modules in the instructor's kit, the manifest in a student copy.

The kit declares tests in ``autograder/<stage>/public.py`` and ``hidden.py``; every
test of ``hidden.py`` is hidden, whatever it says. A student copy has neither
(they import the truths): it has ``public.json``, the public tests as data,
written by :func:`write_manifest` when the copy is built.
"""
from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from types import ModuleType
from typing import Any

from .. import KIT_ROOT, import_from_kit
from ..errors import KitError
from ..stages import get_stage
from .spec import Test

MANIFEST = "public.json"


def spec_dir(stage: str) -> Path:
    return KIT_ROOT / "autograder" / stage


def _load_spec_module(stage: str, name: str) -> ModuleType | None:
    """Import autograder/<stage>/<name>.py in the grader's process (specs import each other as ``autograder.*``)."""
    if not (spec_dir(stage) / f"{name}.py").exists():
        return None
    return import_from_kit(f"autograder.{stage}.{name}")


def _declared(stage: str, include_hidden: bool) -> list[Test]:
    public = _load_spec_module(stage, "public")
    if public is not None:
        tests = [replace(t, hidden=False) for t in public.TESTS]
        hidden = _load_spec_module(stage, "hidden") if include_hidden else None
        if hidden is not None:
            tests += [replace(t, hidden=True) for t in hidden.TESTS]
        return tests
    manifest = spec_dir(stage) / MANIFEST
    if manifest.exists():
        return [Test.from_json(t) for t in json.loads(manifest.read_text())["tests"]]
    raise KitError(f"no autograder tests for stage {stage!r} (expected autograder/{stage}/public.py or {MANIFEST})")


def load_tests(stage: str, include_hidden: bool = True) -> list[Test]:
    """The stage's tests in rubric order, numbered per task (S1.1, S1.2, …)."""
    tests = _declared(stage, include_hidden)
    order = [t.id for t in get_stage(stage).tasks]
    unknown = sorted({t.task for t in tests} - set(order))
    if unknown:
        raise KitError(f"autograder/{stage}: tests name unknown tasks {unknown}")
    tests.sort(key=lambda t: (order.index(t.task), t.hidden))
    counts: dict[str, int] = {}
    numbered = []
    for t in tests:
        counts[t.task] = counts.get(t.task, 0) + 1
        numbered.append(replace(t, number=f"{t.task}.{counts[t.task]}"))
    return numbered


def hidden_summary(stage: str) -> dict[str, Any]:
    """How many hidden tests there are and what they are worth, without what they check.

    From hidden.py where it exists (the instructor's copy), else from the summary
    a student copy ships (``autograder/<stage>/hidden.json``, written by ``cs451 release``).
    """
    hidden = _load_spec_module(stage, "hidden")
    if hidden is not None:
        by_task: dict[str, float] = {}
        for t in hidden.TESTS:
            by_task[t.task] = by_task.get(t.task, 0.0) + t.points
        return {"count": len(hidden.TESTS), "points": sum(by_task.values()), "by_task": by_task}
    path = spec_dir(stage) / "hidden.json"
    if path.exists():
        return json.loads(path.read_text())
    return {"count": 0, "points": 0.0, "by_task": {}}


def write_manifest(stage: str, tests: list[Test], dest: Path) -> Path:
    """The public tests as data, for a student copy (checks by name, truths only as keys)."""
    path = dest / MANIFEST
    path.write_text(json.dumps({"stage": stage, "tests": [t.to_json() for t in tests if not t.hidden]}, indent=1) + "\n")
    return path
