"""How a test is declared: points, visibility, tolerance, the probe it runs and how it judges the answer.

Specs live in ``autograder/<stage>/`` (public.py ships to students; hidden.py
does not). A test never imports student code: it names a *probe* that the
worker runs on the submission in a subprocess, and a *check* that judges the
arrays that come back, against a truth computed here (closed form, a library,
or the reference's answer to the same probe).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Literal

import numpy as np

Outputs = dict[str, np.ndarray]


@dataclass
class Verdict:
    """A check's judgement: the fraction of the test's points earned, and a message a student can act on."""
    fraction: float
    message: str
    images: dict[str, np.ndarray] = field(default_factory=dict)  # reference, submission, difference, error map
    detail: dict[str, Any] = field(default_factory=dict)         # numbers for the report (error, bad pixels)

    @property
    def passed(self) -> bool:
        return self.fraction >= 1.0

    @staticmethod
    def of(ok: bool, message: str, **kw: Any) -> "Verdict":
        return Verdict(1.0 if ok else 0.0, message, **kw)


Check = Callable[[Outputs, "Outputs | None", dict], Verdict]


@dataclass(frozen=True)
class Test:
    """One graded test; ``task`` is the stable ID shared with the handout, the code and the rubric."""
    name: str
    task: str
    points: float
    probe: str
    params: dict[str, Any]
    check: Check
    tolerance: str
    expected: Literal["reference", "none"] = "reference"  # run the same probe on the reference for the truth?
    given: str | None = None        # a reference probe whose outputs feed the submission's probe (trusted inputs)
    hidden: bool = False
    timeout: float = 60.0
    number: str = ""                # filled in by the loader: "S1.2"

    @property
    def visibility(self) -> str:
        """Gradescope's visibility: hidden tests appear only after the grades are published."""
        return "after_published" if self.hidden else "visible"
