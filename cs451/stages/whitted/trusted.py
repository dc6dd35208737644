"""Trusted parts for the tests of later Whitted tasks (the answers a test gives a submission as arrays).

A test of W5 or W11 should judge that task, not the earlier ones it calls. The grader runs the
reference first (through ``given``) and hands the submission arrays: the camera rays, the
reference's hierarchy, and the reference's answers to reflect, refract and fresnel for the
queries its own trace made. While the submission's trace runs, its W8 to W10 are answered from
those arrays wherever it asks what the reference asked (a correct trace asks exactly that), and
left to the submission's own functions elsewhere: a bug in W8 then costs W8's points only.
"""
from __future__ import annotations

from typing import Any, Callable

import numpy as np

from ... import tracescene
from . import tolerances

BVH_GIVEN = {k: f"bvh_{k}" for k in tracescene.BVH_KEYS}
#: Per optics task: the per-ray arrays of a query and of its answer (given as answer_<function>_<name>),
#: and whether each holds a vector (3 columns) per ray.
OPTICS = {"W8": ((("d", 3), ("n", 3)), (("r", 3),)), "W9": ((("d", 3), ("n", 3), ("eta", 1)), (("t", 3), ("tir", 1))),
          "W10": ((("cos", 1), ("eta", 1)), (("f", 1),))}
#: Queries match when they agree to this, after rounding (the stage's table says why).
ANSWER_DIGITS = tolerances.ANSWER_DIGITS


def given_bvh(given: dict[str, np.ndarray]) -> dict[str, np.ndarray] | None:
    """The reference's hierarchy where the test gives it (``bvh_*`` arrays), else None (the submission builds its own)."""
    if not all(name in given for name in BVH_GIVEN.values()):
        return None
    return {k: given[name] for k, name in BVH_GIVEN.items()}


def _query(task: str, args: tuple) -> tuple[np.ndarray, list[np.ndarray]]:
    """One row per ray of what an optics call asks, as floats (the key), and the arguments broadcast per ray.

    Raises ValueError for a call that is not a batch of rays as the interface has it ((n,) or (n, 3) arrays).
    """
    if task == "W10":
        cos = np.asarray(args[0], dtype=np.float64)
        if cos.ndim != 1:
            raise ValueError("not a batch")
        eta = np.broadcast_to(np.asarray(args[1], dtype=np.float64), cos.shape)
        return np.column_stack([cos, eta]), [cos, eta]
    d = np.asarray(args[0], dtype=np.float64)
    n = np.asarray(args[1], dtype=np.float64)
    if d.ndim != 2 or d.shape[1:] != (3,) or n.shape != d.shape:
        raise ValueError("not a batch")
    if task == "W8":  # the mirror direction is the same about -n: key the normal facing the ray
        facing = np.where((np.einsum("ij,ij->i", d, n) > 0)[:, None], -n, n)
        return np.column_stack([d, facing]), [d, n]
    eta = np.broadcast_to(np.asarray(args[2], dtype=np.float64), (len(d),))
    return np.column_stack([d, n, eta]), [d, n, eta]


def _keys(rows: np.ndarray) -> list[bytes]:
    return [r.tobytes() for r in np.round(rows / ANSWER_DIGITS).astype(np.int64)]


class Answers:
    """The reference's answers to one optics task, looked up by query."""

    def __init__(self, task: str, queries: list[np.ndarray], answers: list[np.ndarray]):
        self.task, self.answers = task, answers
        self.index = {k: i for i, k in enumerate(_keys(_query(task, tuple(queries))[0]))}

    def wrap(self, own: Any) -> Any:
        """``own`` (the submission's function) answering from the reference's answers where it asks what the
        reference asked, and by itself elsewhere."""
        def answered(*args: Any) -> Any:
            try:
                query, per_ray = _query(self.task, args)
            except (TypeError, ValueError, IndexError):
                return own(*args)               # not a batch of rays: the submission's own answer
            found = np.array([self.index.get(k, -1) for k in _keys(query)], dtype=np.int64)
            missing = found < 0
            parts = [a[found[~missing]] for a in self.answers]
            if missing.any():                   # rays the reference never cast: the submission's own function
                mine = own(*[a[missing] for a in per_ray])
                mine = mine if isinstance(mine, (tuple, list)) else (mine,)
                parts = [_merge(p, np.asarray(m), missing) for p, m in zip(parts, mine)]
            return tuple(parts) if len(parts) > 1 else parts[0]
        return answered


def _merge(found: np.ndarray, mine: np.ndarray, missing: np.ndarray) -> np.ndarray:
    out = np.zeros((len(missing),) + found.shape[1:], dtype=np.result_type(found, mine))
    out[~missing], out[missing] = found, mine
    return out


def answer_names(task: str) -> tuple[list[str], list[str]]:
    """The names a test gives an optics task's queries and answers under (``answer_<function>_<name>``)."""
    from .. import get_stage                            # the registry: this package's interface imports this module
    name = get_stage("whitted").task(task).function
    queries, results = OPTICS[task]
    return [f"answer_{name}_{q}" for q, _ in queries], [f"answer_{name}_{r}" for r, _ in results]


def answers_from(given: dict[str, np.ndarray]) -> dict[str, Answers]:
    """Per optics task the test gives answers for, the reference's answers to look up by query."""
    out = {}
    for task in OPTICS:
        queries, results = answer_names(task)
        if all(k in given for k in queries + results):
            out[task] = Answers(task, [given[k] for k in queries], [np.asarray(given[k]) for k in results])
    return out


def recorder(task: str, log: dict[str, list]) -> Callable[[Any], Any]:
    """A wrapper for the reference's own optics function that logs each batch it is asked and answers (the
    reference's trace, run first, records what a submission's trace will ask)."""
    def wrap(own: Any) -> Any:
        def recording(*args: Any) -> Any:
            out = own(*args)
            _, per_ray = _query(task, args)
            log[task].append((per_ray, out if isinstance(out, (tuple, list)) else (out,)))
            return out
        return recording
    return wrap
