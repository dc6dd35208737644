"""Hostile submissions for the attack tests: packages that do nothing, and packages made of what a release ships.

A *vacuous* submission defines every task with the least answer of the right
form (identity matrices, empty meshes, misses, unchanged inputs): a grader whose
checks can pass on nothing gives it points. A *scavenger* submission answers every
task by calling whatever the student release ships (the engine ``cs451``, the
stage's ``checks.py``) whose name or parameters look like the task's: a release
that ships an answer gives it points. Both must score 0.
"""
from __future__ import annotations

import importlib
import shutil
from pathlib import Path

from cs451.stages import get_stage

HEADER = '''"""A submission that does nothing: the least answer of the right form for every task."""
import numpy as np
'''


def _define(task, body: str) -> str:
    return f"\n\ndef {task.function}({', '.join(task.params)}):\n    {body}\n"


def vacuous(stage: str, root: Path) -> Path:
    """A folder holding ``<stage>/__init__.py`` with every task answered by nothing."""
    answers = importlib.import_module(f"cs451.stages.{stage}.adversary")   # each stage's own (adding-a-stage.md)
    text = HEADER + answers.HEADER + "".join(_define(t, answers.NOTHING[t.id]) for t in get_stage(stage).tasks)
    (root / stage).mkdir(parents=True)
    (root / stage / "__init__.py").write_text(text)
    return root


SCAVENGER = '''"""A submission made of what the student release ships: each task tries the shipped functions that look like it."""
import importlib
import inspect
import pkgutil
import signal

import cs451

from . import shipped_checks


def _shipped():
    modules = [shipped_checks]
    for info in pkgutil.walk_packages(cs451.__path__, "cs451."):
        try:
            modules.append(importlib.import_module(info.name))
        except BaseException:
            continue
    seen = {}
    for module in modules:
        for name, fn in vars(module).items():
            if inspect.isfunction(fn) and fn.__module__ == module.__name__:
                seen[(module.__name__, name)] = fn
    return list(seen.values())


def _candidates(task_name, params):
    words = set(task_name.split("_"))
    found = []
    for fn in _shipped():
        try:
            names = tuple(inspect.signature(fn).parameters)
        except (TypeError, ValueError):
            continue
        if fn.__name__.strip("_") == task_name or names[:len(params)] == params or words & set(fn.__name__.strip("_").split("_")):
            found.append(fn)
    found.sort(key=lambda fn: (fn.__name__.strip("_") != task_name, -len(words & set(fn.__name__.split("_")))))
    return found[:12]


class _Late(Exception):
    pass


def _late(*_):
    raise _Late()


def _scavenge(task_name, params, args):
    signal.signal(signal.SIGALRM, _late)
    for fn in _candidates(task_name, params):
        signal.setitimer(signal.ITIMER_REAL, 0.5)
        try:
            return fn(*args)
        except BaseException:
            continue
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
    raise NotImplementedError(f"nothing shipped answers {task_name}")
'''


def scavenger(stage: str, release: Path, root: Path) -> Path:
    """A folder holding ``<stage>/`` whose every task is answered by the release's shipped functions, if any does."""
    pkg = root / stage
    pkg.mkdir(parents=True)
    shutil.copy(release / "autograder" / stage / "checks.py", pkg / "shipped_checks.py")
    text = SCAVENGER + "".join(
        f"\n\ndef {t.function}({', '.join(t.params)}):\n"
        f"    return _scavenge({t.function!r}, {tuple(t.params)!r}, ({''.join(p + ', ' for p in t.params)}))\n"
        for t in get_stage(stage).tasks)
    (pkg / "__init__.py").write_text(text)
    return root


def shipped_python(release: Path) -> list[Path]:
    """Every Python file of a release (what a student gets)."""
    return sorted(p for p in release.rglob("*.py") if ".venv" not in p.parts)


def task_answer_definitions(release: Path, stage: str) -> list[str]:
    """Places in a release outside the student's own package that define a function named after a task."""
    names = {t.function for t in get_stage(stage).tasks}
    found = []
    for path in shipped_python(release):
        if path.relative_to(release).parts[0] == stage:
            continue  # the starter: stubs by design
        for lineno, line in enumerate(path.read_text().splitlines(), 1):
            stripped = line.strip()
            if stripped.startswith("def ") and stripped[4:].split("(")[0] in names:
                found.append(f"{path.relative_to(release)}:{lineno}: {stripped}")
    return found


