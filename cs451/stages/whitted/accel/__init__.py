"""The Whitted reference's speed layer: numba kernels that do the work of W1, W4, W5, W7 and W11 on large batches.

The reference in ``reference/whitted/`` is the algorithm as a student should read it, in plain numpy. It
opts in to this package by one declared hook, ``ACCELERATED = True`` in its package, and the stage honours
the hook for the kit's own reference only (:meth:`cs451.stages.base.Stage.accelerated`): while a call of the
stage's interface runs, the reference's W1, W4, W5, W7 and W11 are wrapped (through
:func:`~cs451.stages.base.functions_replaced`, the same declared mechanism the grader's trusted answers use),
and a wrapper hands a large batch to the compiled kernels and a small one to the reference's own function.
These compiled paths give the images the reference gave when this code lived inside it, to the last bit.

Instructor-side: no release and no grading sandbox holds this package (:func:`cs451.instructor_only`); where
it is missing, the reference simply runs its numpy code. ``cs451/stages/whitted/bench.py`` measures it against Embree and
Mitsuba 3; ``tests/whitted/test_whitted_frame.py`` and ``tests/whitted/test_whitted_robust.py`` check it against the numpy path.
"""
from __future__ import annotations

import contextlib
from typing import Any, Callable, Iterator

import numpy as np

from ...base import Stage, functions_replaced, replaced_tasks

#: Batches at least this large run compiled; smaller ones run the reference's numpy, where compiling would
#: cost more than it saves, until a large one has paid for the kernels: from then on, in this process, every
#: batch runs compiled (the demo's small pieces of a large frame, a large frame's later bounces).
COMPILED_RAYS = 10_000
#: Hierarchies over at least this many primitives are built compiled (binned SAH, hierarchy.py); smaller ones
#: by the reference's numpy median split.
COMPILED_PRIMS = 5_000
#: The tasks whose work the frame kernel fuses: while any of them is replaced by someone else (the grader's
#: trusted answers, the demo's shadow switch or ray-tree recording), W11 runs bounce by bounce, calling them.
FUSED = ("W5", "W6", "W7", "W8", "W9", "W10")

_active: set[str] = set()   # the implementations inside an accelerated() block
_paid = [False]      # whether a large batch has run compiled in this process
#: Which path the wrappers take: None (by size), or "numpy" / "compiled" / "bounces" (compiled, bounce by
#: bounce) for the tests and figures that compare them (:func:`forced`).
_forced: list[str | None] = [None]


@contextlib.contextmanager
def forced(path: str | None) -> Iterator[None]:
    """Within the block every batch takes ``path``: "numpy", "compiled" (whole frames for W11) or "bounces"
    (compiled W1, W5, W7, with W11 bounce by bounce); None restores the choice by size."""
    if path not in (None, "numpy", "compiled", "bounces"):
        raise ValueError(f"unknown path {path!r}")
    saved = _forced[0]
    _forced[0] = path
    try:
        yield
    finally:
        _forced[0] = saved


def _compiled(n: int) -> bool:
    if _forced[0] is not None:
        return _forced[0] != "numpy"
    if n >= COMPILED_RAYS:
        _paid[0] = True
    return _paid[0]


def forget_compiled() -> None:
    """Back to choosing by size, as in a fresh process (the tests call it before each test, so that which path a
    test runs never depends on the tests before it)."""
    _paid[0] = False


def _camera_rays(own: Callable) -> Callable:
    def camera_rays(camera: Any, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
        if not _compiled(width * height):
            return own(camera, width, height)
        from .queries import camera_frame
        return camera_frame(camera, width, height)
    return camera_rays


def _build_bvh(own: Callable) -> Callable:
    def build_bvh(lo: np.ndarray, hi: np.ndarray) -> dict[str, np.ndarray]:
        if len(lo) < COMPILED_PRIMS:
            return own(lo, hi)
        from .hierarchy import built
        from .queries import LEAF_SIZE
        return built(np.ascontiguousarray(lo, dtype=np.float64), np.ascontiguousarray(hi, dtype=np.float64),
                     LEAF_SIZE)
    return build_bvh


def _closest_hit(own: Callable) -> Callable:
    def closest_hit(scene: Any, origins: np.ndarray, directions: np.ndarray) -> tuple:
        if not _compiled(len(origins)):
            return own(scene, origins, directions)
        from .queries import closest
        return closest(scene, origins, directions)
    return closest_hit


def _shadow_transmission(own: Callable) -> Callable:
    def shadow_transmission(scene: Any, origins: np.ndarray, targets: np.ndarray) -> np.ndarray:
        if not _compiled(len(origins)):
            return own(scene, origins, targets)
        from .queries import transmission
        return transmission(scene, origins, targets)
    return shadow_transmission


def _trace(own: Callable, stage: Stage, impl: Any) -> Callable:
    def trace(scene: Any, origins: np.ndarray, directions: np.ndarray) -> np.ndarray:
        if not _compiled(len(origins)):
            return own(scene, origins, directions)
        whole = _forced[0] != "bounces" and not (replaced_tasks(impl) & set(FUSED))
        if whole:
            from .frame import trace_frame
            return trace_frame(scene, np.asarray(origins, dtype=np.float64), np.asarray(directions, dtype=np.float64))
        return own(scene, origins, directions)
    return trace


@contextlib.contextmanager
def accelerated(stage: Stage, impl: Any) -> Iterator[None]:
    """Within the block the reference's large batches run compiled (the module docstring says how). A task some
    caller has already replaced keeps its replacement; nesting is harmless (the outer block's wrappers stay)."""
    if impl.__name__ in _active:
        yield
        return
    taken = replaced_tasks(impl)
    wrappers = {"W1": _camera_rays, "W4": _build_bvh, "W5": _closest_hit, "W7": _shadow_transmission,
                "W11": lambda own: _trace(own, stage, impl)}
    _active.add(impl.__name__)
    try:
        with functions_replaced(stage, impl, {t: w for t, w in wrappers.items() if t not in taken}, record=False):
            yield
    finally:
        _active.discard(impl.__name__)
