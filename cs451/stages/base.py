"""What a stage is: its tasks (the functions a submission provides), its renderer and its probes.

A stage's interface is declared once, here and in the stage's module; the CLI,
the autograder and the demos reach student code only through it.
"""
from __future__ import annotations

import inspect
import sys
from contextlib import contextmanager
from dataclasses import dataclass, field
from types import ModuleType
from typing import Any, Callable, Iterator

import numpy as np

from ..errors import KitError


@dataclass(frozen=True)
class Task:
    """One thing the student writes, with the stable ID used in the handout, the code, the tests and the rubric."""
    id: str             # "S1"
    function: str       # the name the submission must define
    title: str          # "Perspective projection"
    params: tuple[str, ...]  # expected parameter names, checked when a submission loads


@dataclass(frozen=True)
class Stage:
    name: str                 # "sphere": CLI name and folder under reference/ and starter/
    number: int
    title: str
    handout: str              # folder under assignments/
    tasks: tuple[Task, ...]
    render: Callable[..., Any]          # render(scene, impl, size=None, **opts) -> float image (h, w, 3)
    probes: dict[str, Callable[..., dict[str, np.ndarray]]] = field(default_factory=dict)
    #: demo(module, output: Path, window: bool, frames: int | None) -> list[Path] of files written (none in a window)
    demo: Callable[..., list] | None = None
    #: earlier stages whose trusted reference this stage's engine runs (radiosity: the hemicube); a student
    #: release of this stage ships their reference, whose solutions are out by the time this stage starts
    builds_on: tuple[str, ...] = ()

    def task(self, task_id: str) -> Task:
        for t in self.tasks:
            if t.id == task_id:
                return t
        raise KeyError(task_id)

    def handout_link(self, task: Task) -> str:
        anchor = f"{task.id}-{task.title}".lower().replace(" ", "-")
        anchor = "".join(c for c in anchor if c.isalnum() or c == "-")
        return f"assignments/{self.handout}/README.md#{anchor}"


def check_interface(stage: Stage, module: ModuleType) -> list[str]:
    """Problems with a submission's interface: missing functions or wrong parameter names."""
    problems = []
    for task in stage.tasks:
        fn = getattr(module, task.function, None)
        if fn is None:
            problems.append(f"{task.id}: missing function {task.function}()")
            continue
        if not callable(fn):
            problems.append(f"{task.id}: {task.function} is not a function")
            continue
        try:
            names = tuple(p.name for p in inspect.signature(fn).parameters.values())
        except (TypeError, ValueError):
            continue
        if names != task.params:
            problems.append(f"{task.id}: {task.function}({', '.join(names)}) should take ({', '.join(task.params)})")
    return problems


def student_call(stage: Stage, module: Any, task_id: str, *args: Any) -> Any:
    """Call a task's function, turning an unimplemented stub into a one-line KitError."""
    task = stage.task(task_id)
    fn = getattr(module, task.function, None)
    if fn is None:
        raise KitError(f"{task.id} {task.function}() is missing from the submission")
    try:
        return fn(*args)
    except NotImplementedError as err:
        hint = str(err).removeprefix(f"{task.id}: ") or f"see {stage.handout_link(task)}"
        raise KitError(f"{task.id} {task.function}() is not implemented yet: {hint}") from None


def shape_text(shape: tuple[int | None, ...]) -> str:
    """A shape as Python writes it, with ``n`` for any length: ``(7,)``, ``(n, 3)``, ``(4, 4)``."""
    inner = ", ".join("n" if s is None else str(s) for s in shape)
    return f"({inner},)" if len(shape) == 1 else f"({inner})"


def as_array(value: Any, shape: tuple[int | None, ...], what: str, kind: str = "f") -> np.ndarray:
    """Check a student's result: array-like, of this shape (None = any length), finite; else a KitError."""
    try:
        arr = np.asarray(value, dtype=np.float64 if kind == "f" else None)
    except (TypeError, ValueError) as err:
        raise KitError(f"{what} returned something that is not an array ({type(value).__name__}: {err})") from None
    if arr.ndim != len(shape) or any(s is not None and s != a for s, a in zip(shape, arr.shape)):
        raise KitError(f"{what} returned shape {arr.shape}, expected {shape_text(shape)}")
    if kind == "i":
        if arr.dtype.kind not in "iu":
            if arr.dtype.kind == "f" and np.isfinite(arr).all() and np.all(arr == np.round(arr)):
                arr = arr.astype(np.int64)
            else:
                raise KitError(f"{what} returned {arr.dtype} values, expected integers")
    elif not np.isfinite(arr).all():
        raise KitError(f"{what} returned NaN or infinite values")
    return arr


@contextmanager
def functions_replaced(stage: Stage, impl: Any, wrappers: dict[str, Callable[[Any], Any]]) -> Iterator[None]:
    """Within the block, each task's function is replaced by ``wrappers[task](own)`` in every module of the
    implementation's package that holds it, under whatever name, so that its other functions call the replacement.

    How a later task's test gets trusted answers from an earlier task the submission's code calls (W11's trace
    calling W8 to W10, S6's reshape calling S1), and how the reference's calls are recorded to give them.
    """
    own = {task: getattr(impl, stage.task(task).function, None) for task in wrappers}
    changed = []
    prefix = impl.__name__
    for name, module in list(sys.modules.items()):
        if module is None or not (name == prefix or name.startswith(prefix + ".")):
            continue
        for attr, value in list(vars(module).items()):
            for task, fn in own.items():
                if fn is not None and value is fn:
                    setattr(module, attr, wrappers[task](fn))
                    changed.append((module, attr, value))
    try:
        yield
    finally:
        for module, attr, value in changed:
            setattr(module, attr, value)
