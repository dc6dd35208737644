"""How a test is declared: points, tolerance, the probe it runs, the truth it needs and the check that judges.

Specs live in ``autograder/<stage>/``: ``public.py`` and ``hidden.py`` declare tests,
``truth.py`` computes independent answers (closed forms, libraries), ``checks.py``
judges a submission's arrays against them. A test never imports student code: it
names a *probe* that the worker runs on the submission in a subprocess.

Checks and truths are *named* (:class:`Ref`: a module, a function and JSON
arguments), never closures, for one reason: a student copy of the kit ships
the public tests as data (``public.json``, written by ``cs451 release``) with the
truths already evaluated into arrays beside the reference's answers, so that no
code that computes an answer ever reaches a student. Only ``checks.py`` ships,
and it only compares.

A public test also names a *variant* (``vary``, from ``autograder/<stage>/variants.py``,
which never ships either): a function that makes a fresh case of the same form from
the shipped one. Grading with the instructor's kit (a roster, the Gradescope zip,
``cs451 grade`` with the hidden tests) grades every public test on its fresh case, made
from the kit's private secret (:func:`cs451.grading.loader.load_tests`), so the answers
a release ships answer nothing there.
"""
from __future__ import annotations

import importlib
import json
import re
from dataclasses import dataclass, field
from typing import Any, Callable, Literal

import numpy as np

from .. import import_from_kit

Outputs = dict[str, np.ndarray]

#: Modules a check may come from (they ship to students) and modules a truth may come from (they never do).
CHECK_MODULES = re.compile(r"^(cs451\.grading\.checks|autograder\.\w+\.checks)$")
TRUTH_MODULES = re.compile(r"^autograder\.\w+\.truth$")
#: Modules a variant may come from (they never ship).
VARIANT_MODULES = re.compile(r"^autograder\.\w+\.variants$")


@dataclass
class Verdict:
    """A check's judgement: the fraction of the test's points earned, and a message a student can act on."""
    fraction: float
    message: str
    images: dict[str, np.ndarray] = field(default_factory=dict)  # reference, submission, difference, error map
    detail: dict[str, Any] = field(default_factory=dict)         # numbers for the report (error, bad pixels)

    @property
    def passed(self) -> bool:
        """Whether every point was earned (a partial score is not a pass)."""
        return self.fraction >= 1.0

    @staticmethod
    def of(ok: bool, message: str, **kw: Any) -> "Verdict":
        """An all-or-nothing verdict: every point where ``ok``, none otherwise."""
        return Verdict(1.0 if ok else 0.0, message, **kw)


def jsonable(value: Any) -> Any:
    """Numpy values as plain JSON values (lists and numbers), recursively."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    return value


@dataclass(frozen=True)
class Ref:
    """A module-level function by module and name, with keyword arguments kept as JSON text."""
    module: str
    name: str
    args: str = "{}"

    @staticmethod
    def to(fn: Callable[..., Any], **kwargs: Any) -> "Ref":
        """Name ``fn`` by module and name, its keyword arguments frozen as sorted JSON (equal refs compare equal)."""
        return Ref(fn.__module__, fn.__name__, json.dumps(jsonable(kwargs), sort_keys=True))

    @property
    def kwargs(self) -> dict[str, Any]:
        """The keyword arguments the named function is called with, decoded from their JSON text."""
        return json.loads(self.args)

    def resolve(self, allowed: re.Pattern) -> Callable[..., Any]:
        """The named function, imported only from a module that ``allowed`` matches (a spec may name nothing else);
        ValueError otherwise."""
        if not allowed.match(self.module):
            raise ValueError(f"{self.module}.{self.name}: not a module specs may name here")
        module = import_from_kit(self.module) if self.module.startswith("autograder.") \
            else importlib.import_module(self.module)
        fn = getattr(module, self.name, None)
        if not callable(fn):
            raise ValueError(f"{self.module}.{self.name}: no such function")
        return fn

    def to_json(self) -> dict[str, Any]:
        """The reference as a student copy's manifest holds it: module, name and keyword arguments."""
        return {"module": self.module, "name": self.name, "kwargs": self.kwargs}

    @staticmethod
    def from_json(data: dict[str, Any]) -> "Ref":
        """A reference back from :meth:`to_json`'s form."""
        return Ref(data["module"], data["name"], json.dumps(data.get("kwargs", {}), sort_keys=True))


def check(fn: Callable[..., Verdict], **kwargs: Any) -> Ref:
    """Name a check ``fn(out, expected, params, **kwargs) -> Verdict`` from a ``checks`` module."""
    ref = Ref.to(fn, **kwargs)
    ref.resolve(CHECK_MODULES)
    return ref


def truth(fn: Callable[..., Any], **kwargs: Any) -> Ref:
    """Name a truth ``fn(params, **kwargs) -> dict of arrays`` from a ``truth`` module."""
    ref = Ref.to(fn, **kwargs)
    ref.resolve(TRUTH_MODULES)
    return ref


@dataclass(frozen=True)
class Case:
    """A variant's fresh case: the new parameters, a short description a student can act on, and the check
    when the check itself holds numbers of the case (a closed form, a count of rays)."""
    params: dict[str, Any]
    describe: str
    check: Ref | None = None


def variant(fn: Callable[..., Case], **kwargs: Any) -> Ref:
    """Name a variant ``fn(params, rng, **kwargs) -> Case`` from a ``variants`` module."""
    ref = Ref.to(fn, **kwargs)
    ref.resolve(VARIANT_MODULES)
    return ref


@dataclass(frozen=True)
class Test:
    """One graded test; ``task`` is the stable ID shared with the handout, the code and the rubric.

    The check receives the submission's arrays, ``expected`` (the reference's answer to the same
    probe when ``expected == "reference"``, and the truth's arrays when ``truth`` is set) and the
    parameters. ``hidden`` is set by the loader: every test of ``hidden.py`` is hidden.
    """
    name: str
    task: str
    points: float
    probe: str
    params: dict[str, Any]
    check: Ref
    tolerance: str
    expected: Literal["reference", "none"] = "reference"  # run the same probe on the reference for the truth?
    given: str | None = None        # a reference probe whose outputs feed the submission's probe (trusted inputs)
    truth: Ref | None = None
    edge_case: bool = False         # its right answer is a do-nothing one: it counts only beside a passing main test
    hidden: bool = False
    timeout: float = 60.0
    number: str = ""                # filled in by the loader: "S1.2"
    #: earlier tasks whose functions this test runs as the submission's own (no trusted stand-in exists):
    #: a failing test names them, and says which of them fail their own tests
    depends_on: tuple[str, ...] = ()
    #: a public test's variant (:func:`variant`): the fresh case the instructor's kit grades instead of this one
    vary: Ref | None = None
    #: set by the loader: the test grades an optional extension, whose points stay out of the grade
    extension: bool = False

    @property
    def visibility(self) -> str:
        """Gradescope's visibility: hidden tests appear only after the grades are published."""
        return "after_published" if self.hidden else "visible"

    def to_json(self) -> dict[str, Any]:
        """The test as a student copy's manifest holds it (``truth`` by name only: its arrays ship beside)."""
        return {"name": self.name, "task": self.task, "points": self.points, "probe": self.probe,
                "params": self.params, "check": self.check.to_json(), "tolerance": self.tolerance,
                "expected": self.expected, "given": self.given, "truth": self.truth.to_json() if self.truth else None,
                "edge_case": self.edge_case, "timeout": self.timeout, "depends_on": list(self.depends_on)}

    @staticmethod
    def from_json(data: dict[str, Any]) -> "Test":
        """A test back from a student copy's manifest (:meth:`to_json`): never hidden, and with no variant."""
        return Test(data["name"], data["task"], float(data["points"]), data["probe"], data["params"],
                    Ref.from_json(data["check"]), data["tolerance"], data["expected"], data.get("given"),
                    Ref.from_json(data["truth"]) if data.get("truth") else None, bool(data.get("edge_case")), False,
                    float(data["timeout"]), depends_on=tuple(data.get("depends_on", ())))
