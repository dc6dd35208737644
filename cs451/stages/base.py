"""What a stage is: its tasks (the functions a submission provides), what each returns, its options, the scene
kinds it draws, its renderer, its probes and its demo.

A stage's interface is declared once, in its module, with the pieces here; the CLI,
the autograder and the demos reach student code only through it. A task declares
what it returns (:class:`Out`), and :meth:`Stage.call` checks every answer against
that, so a malformed answer becomes one line naming the task, never a traceback deep
in the engine.
"""
from __future__ import annotations

import importlib
import inspect
import sys
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any, Callable, Iterator

import numpy as np

from ..errors import KitError


@dataclass(frozen=True)
class Out:
    """One value a task returns: its name (for messages), its shape and its kind.

    ``shape`` entries are lengths, ``None`` (any length), or expressions of the call's arguments
    and of the values before it (``"len(origins)"``, ``"resolution // 2"``, ``"len(positions)"``).
    ``kind``: ``f`` finite floats, ``f+inf`` floats where infinity means a miss (NaN never), ``i``
    integers, ``b`` booleans, ``text`` a string, ``dict`` a dict (checked by the caller), ``any``.
    ``below``: integers must index into something of this length (an expression as above).
    """
    name: str
    shape: tuple[int | str | None, ...] = ()
    kind: str = "f"
    below: str | None = None


@dataclass(frozen=True)
class Task:
    """One thing the student writes, with the stable ID used in the handout, the code, the tests and the rubric."""
    id: str             # "S1"
    function: str       # the name the submission must define
    title: str          # "Perspective projection"
    params: tuple[str, ...]  # expected parameter names, checked when a submission loads
    returns: tuple[Out, ...] = ()   # one Out: a single value; several: a tuple of them
    #: an optional extension: its tests are graded and reported, but their points stay out of the grade (a
    #: submission may leave the function out)
    optional: bool = False

    @property
    def label(self) -> str:
        """How messages name the task: its ID and function, ``S1 perspective()``."""
        return f"{self.id} {self.function}()"


class Probes(dict):
    """A stage's probes by name; ``@PROBES.register`` adds ``probe_<name>`` as ``<name>``."""

    def register(self, fn: Callable[..., dict[str, np.ndarray]]) -> Callable[..., dict[str, np.ndarray]]:
        """Add ``probe_<name>`` as the probe ``<name>`` (a decorator: the function comes back unchanged)."""
        self[fn.__name__.removeprefix("probe_")] = fn
        return fn


class Tolerance(float):
    """A grading tolerance: a float, to use wherever the number goes, that carries why it has its value. A stage keeps
    its own in one table (``cs451/stages/<stage>/tolerances.py``); the tests' descriptions print them (``f"{tol}"``
    gives ``1e-9``, not ``1e-09``), so a description and its check cannot disagree."""
    why: str

    def __new__(cls, value: float, why: str) -> "Tolerance":
        made = super().__new__(cls, value)
        made.why = why
        return made

    def __reduce__(self) -> tuple:
        return Tolerance, (float(self), self.why)

    def __str__(self) -> str:
        value = float(self)
        if value != 0 and abs(value) < 1e-2:
            mantissa, exponent = f"{value:.0e}".split("e")
            return f"{mantissa}e{int(exponent)}"
        return f"{value:g}"

    def __format__(self, spec: str) -> str:
        return str(self) if not spec else float(self).__format__(spec)

    def __repr__(self) -> str:
        return f"Tolerance({str(self)})"


def tolerance_table(module: Any) -> dict[str, Tolerance]:
    """A stage's tolerances by name, from its ``tolerances`` module (for the docs and the tests)."""
    return {name: value for name, value in vars(module).items() if isinstance(value, Tolerance)}


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
    #: the demo's keys, (key, what it does), in the order the window title and ``cs451 demo --help`` list them
    demo_keys: tuple[tuple[str, str], ...] = ()
    #: earlier stages whose implementation this stage's engine runs (radiosity: the hemicube), see :meth:`trusted`;
    #: never in a grading sandbox, where the tests pass that stage's results in as arrays (``Test.given``)
    builds_on: tuple[str, ...] = ()
    #: the stage's record of ``options.<name>`` in a scene file (a dataclass of schema fields)
    options_type: type | None = None
    #: the kinds of scene object and light the stage draws; a scene holding others is refused, naming them
    draws: tuple[type, ...] = ()
    #: estimate(scene, size) -> list of cs451.limits.Cost: the memory a render of the scene needs, from its
    #: parameters alone (see :meth:`check_cost`)
    estimate: Callable[..., list] | None = None
    #: diagrams() -> {file name: draw() -> uint8 RGB image}: the handout's explanatory pictures
    #: (:mod:`cs451.packaging.diagrams`), loaded only when asked for
    diagrams: Callable[[], dict[str, Callable[[], np.ndarray]]] | None = None
    #: warm(module) -> [(what, do())]: the steps that compile, once, what a first render or demo of the stage
    #: would compile, so that ``cs451 warm`` (setup.sh) pays it rather than a first render or a lecture
    warm: Callable[[Any], list[tuple[str, Callable[[], Any]]]] | None = None
    #: the module of the stage's speed layer (instructor-side, see :meth:`accelerated`), or None
    accelerator: str | None = None
    #: scene_check(scene): refuse, in one KitError naming the field, a scene of drawn kinds the stage still cannot
    #: render (stage 5: not exactly one area light); run by :meth:`check_scene` before any work
    scene_check: Callable[[Any], None] | None = None

    def task(self, task_id: str) -> Task:
        """The task with this ID (``S1``); KeyError where the stage has none."""
        for t in self.tasks:
            if t.id == task_id:
                return t
        raise KeyError(task_id)

    def call(self, impl: Any, task_id: str, *args: Any) -> Any:
        """Call a task's function and check its answer against the task's declared ``returns``."""
        task = self.task(task_id)
        return check_returns(task, student_call(self, impl, task_id, *args), dict(zip(task.params, args)))

    def accelerated(self, impl: Any) -> Any:
        """A context in which the kit's own reference runs through the stage's speed layer, where the reference
        asks for it (its package's ``ACCELERATED``), the stage has one and this copy of the kit holds it (no
        release or sandbox does). Any other implementation runs as it is, whatever it declares: the speed
        layer does tasks' work, so a submission never gets it."""
        from contextlib import nullcontext
        from .. import KIT_ROOT
        if self.accelerator is None or getattr(impl, "ACCELERATED", False) is not True:
            return nullcontext()
        own = (KIT_ROOT / "reference" / self.name).resolve()
        if Path(getattr(impl, "__file__", "") or "/").resolve().parent != own:
            return nullcontext()
        try:
            layer = importlib.import_module(self.accelerator)
        except ModuleNotFoundError:
            return nullcontext()
        return layer.accelerated(self, impl)

    def options(self, scene: Any, **overrides: Any) -> Any:
        """The scene's ``options.<stage>``, validated; ``overrides`` that are not None replace fields."""
        from .. import schema
        data = dict(scene.options.get(self.name, {}))
        data.update({k: v for k, v in overrides.items() if v is not None})
        return schema.parse_record(self.options_type, data, schema.Context(scene.label, f"options.{self.name}"))

    def draws_scene(self, scene: Any) -> bool:
        """Whether the stage draws ``scene``: every object and light of a kind it draws, and its own check passed
        (:meth:`check_scene` says why not)."""
        try:
            self.check_scene(scene)
        except KitError:
            return False
        return True

    def check_scene(self, scene: Any) -> None:
        """Refuse a scene holding an object or light this stage does not draw, naming the first and the stage,
        or nothing at all to draw (before any kernel is compiled for it)."""
        check_not_empty(scene)
        for group in ("objects", "lights"):
            for k, item in enumerate(getattr(scene, group)):
                if not isinstance(item, self.draws):
                    kinds = sorted({_kind(c) for c in self.draws})
                    raise KitError(f"{scene.label}: {group}[{k}]: stage {self.number} ({self.name}) does not draw a "
                                   f"{_kind(type(item))} (it draws: {', '.join(kinds)})")
        if self.scene_check is not None:
            self.scene_check(scene)

    def check_cost(self, scene: Any, size: tuple[int, int] | None = None) -> None:
        """Refuse, before any work, a render of ``scene`` that would not fit in this machine's memory budget."""
        from ..limits import refuse_over_budget
        if self.estimate is not None:
            refuse_over_budget(scene.label, self.estimate(scene, size))

    def trusted(self, earlier: str) -> Any:
        """The implementation of an earlier stage this one builds on, loaded (:func:`cs451.impl.earlier_stage_impl`)."""
        from ..impl import earlier_stage_impl, load_impl
        if earlier not in self.builds_on:
            raise KitError(f"stage {self.name} does not build on stage {earlier!r}")
        return load_impl(earlier_stage_impl(earlier), earlier)

    def handout_link(self, task: Task) -> str:
        """Where the handout explains a task, as a path from the kit's root with GitHub's heading anchor (the hint
        an unimplemented stub's message gives)."""
        anchor = f"{task.id}-{task.title}".lower().replace(" ", "-")
        anchor = "".join(c for c in anchor if c.isalnum() or c == "-")
        return f"assignments/{self.handout}/README.md#{anchor}"


def check_not_empty(scene: Any) -> None:
    """Refuse a scene with nothing in it: every pixel would be the background, and a stage would still compile
    its kernels (two minutes, the first time) to find that out."""
    if not scene.objects:
        raise KitError(f"{scene.label}: objects: the scene has no objects, so every pixel would be the background")


def _kind(cls: type) -> str:
    """A kind as a scene file names it: its ``type`` ("sphere"), and "light" after a light's ("point light")."""
    name = getattr(cls, "type_name", None) or cls.__name__.lower()
    return f"{name} light" if any(base.__name__ == "Light" for base in cls.__mro__[1:]) else name


def _shape(shape: tuple[int | str | None, ...], names: dict[str, Any]) -> tuple[int | None, ...]:
    return tuple(s if s is None or isinstance(s, int) else int(eval(s, {"len": len}, names)) for s in shape)


def check_returns(task: Task, value: Any, names: dict[str, Any]) -> Any:
    """``value`` checked against ``task.returns`` (the arguments by name in ``names``); the checked value(s)."""
    outs = task.returns
    if not outs:
        return value
    if len(outs) == 1:
        return _check_out(task, outs[0], value, names, single=True)
    if not isinstance(value, (tuple, list)) or len(value) != len(outs):
        got = f"{len(value)} values" if isinstance(value, (tuple, list)) else type(value).__name__
        raise KitError(f"{task.label} must return ({', '.join(o.name for o in outs)}), got {got}")
    names = dict(names)
    checked = []
    for out, part in zip(outs, value):
        checked.append(_check_out(task, out, part, names, single=False))
        names[out.name] = checked[-1]
    return tuple(checked)


def _check_out(task: Task, out: Out, value: Any, names: dict[str, Any], single: bool) -> Any:
    what = task.label if single else f"{task.label} {out.name}"
    if out.kind == "any":
        return value
    if out.kind == "text":
        if not isinstance(value, str):
            raise KitError(f"{what} must be a string, got {type(value).__name__}")
        return value
    if out.kind == "dict":
        if not isinstance(value, dict):
            raise KitError(f"{what} must be a dict, got {type(value).__name__}")
        return value
    shape = _shape(out.shape, names)
    if out.kind == "f+inf":
        arr = as_array(value, shape, what, kind="f", allow_inf=True)
    elif out.kind == "b":
        arr = as_array(value, shape, what, kind="b")
    else:
        arr = as_array(value, shape, what, kind=out.kind)
    if out.below is not None and arr.size:
        bound = int(eval(out.below, {"len": len}, names))
        if arr.min() < 0 or arr.max() >= bound:
            raise KitError(f"{what} holds {int(arr.max() if arr.max() >= bound else arr.min())}, but indices "
                           f"run from 0 to {bound - 1}")
    return arr


def check_interface(stage: Stage, module: ModuleType) -> list[str]:
    """Problems with a submission's interface: missing functions or wrong parameter names."""
    problems = []
    for task in stage.tasks:
        fn = getattr(module, task.function, None)
        if fn is None and task.optional:
            continue
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
    if getattr(module, task.function, None) is None:
        if task.optional:
            raise KitError(f"{task.id} {task.function}() is an optional extension this submission does not attempt")
        raise KitError(f"{task.id} {task.function}() is missing from the submission")
    try:
        with stage.accelerated(module):
            return getattr(module, task.function)(*args)
    except NotImplementedError as err:
        hint = str(err).removeprefix(f"{task.id}: ") or f"see {stage.handout_link(task)}"
        raise KitError(f"{task.id} {task.function}() is not implemented yet: {hint}") from None


def shape_text(shape: tuple[int | None, ...]) -> str:
    """A shape as Python writes it, with ``n`` for any length: ``(7,)``, ``(n, 3)``, ``(4, 4)``."""
    inner = ", ".join("n" if s is None else str(s) for s in shape)
    return f"({inner},)" if len(shape) == 1 else f"({inner})"


def as_array(value: Any, shape: tuple[int | None, ...], what: str, kind: str = "f", allow_inf: bool = False) -> np.ndarray:
    """Check a student's result: array-like, of this shape (None = any length), finite (or inf where
    ``allow_inf``, never NaN), integers for ``kind="i"``, booleans for ``kind="b"``; else a KitError."""
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
    elif kind == "b":
        if arr.dtype.kind != "b":
            if arr.dtype.kind in "iuf" and np.isin(arr, (0, 1)).all():
                arr = arr.astype(bool)
            else:
                raise KitError(f"{what} returned {arr.dtype} values, expected booleans")
    elif np.isnan(arr).any() or (not allow_inf and not np.isfinite(arr).all()):
        raise KitError(f"{what} returned NaN" + ("" if allow_inf else " or infinite values") +
                       (" (a miss must be inf)" if allow_inf else ""))
    return arr


#: Per implementation (its module name), the tasks replaced by :func:`functions_replaced` blocks now running.
_REPLACED: dict[str, list[str]] = {}


def replaced_tasks(impl: Any) -> set[str]:
    """The tasks of ``impl`` some caller has replaced for now (a speed layer asks before fusing their work)."""
    return set(_REPLACED.get(impl.__name__, ()))


@contextmanager
def functions_replaced(stage: Stage, impl: Any, wrappers: dict[str, Callable[[Any], Any]],
                       record: bool = True) -> Iterator[None]:
    """Within the block, each task's function is replaced by ``wrappers[task](own)`` in every module of the
    implementation's package that holds it, under whatever name, so that its other functions call the replacement.

    How a later task's test gets trusted answers from an earlier task the submission's code calls (W11's trace
    calling W8 to W10, S7's reshape calling S1), and how the reference's calls are recorded to give them. The
    tasks are recorded for :func:`replaced_tasks` unless ``record`` is false (the speed layer's own wrappers).
    """
    own = {task: getattr(impl, stage.task(task).function, None) for task in wrappers}
    changed = []
    made: dict[str, Any] = {}
    prefix = impl.__name__
    for name, module in list(sys.modules.items()):
        if module is None or not (name == prefix or name.startswith(prefix + ".")):
            continue
        for attr, value in list(vars(module).items()):
            for task, fn in own.items():
                if fn is not None and value is fn:
                    if task not in made:   # one wrapper per task, so a block nested inside finds it everywhere
                        made[task] = wrappers[task](fn)
                    setattr(module, attr, made[task])
                    changed.append((module, attr, value))
    tasks = _REPLACED.setdefault(impl.__name__, []) if record else []
    tasks.extend(wrappers)
    try:
        yield
    finally:
        for module, attr, value in reversed(changed):
            setattr(module, attr, value)
        for task in wrappers:
            tasks.remove(task)


def part(package: str, name: str) -> ModuleType:
    """A module of a stage's package loaded by name when first asked for (its demo, its diagrams): they load GLFW
    and window loops a render never needs, and since the stage never imports them they may import the stage."""
    return importlib.import_module(f"{package}.{name}")
