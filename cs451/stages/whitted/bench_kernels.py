"""Driving the Whitted reference's compiled kernels directly, for the bench: closest-hit and shadow-ray
queries without the stage's scaffolding, a thread count for a while, and the rays a frame casts.

These reach into the reference's speed layer (``cs451/stages/whitted/accel/``: kernels, hierarchy, running,
queries), which is not part of the stage's interface: the bench measures the reference, not a submission.
"""
from __future__ import annotations

import contextlib
import importlib
import math
import time
from types import ModuleType, SimpleNamespace
from typing import Callable, Iterator

import numpy as np

from cs451.stages import whitted as stage
from cs451.stages.base import functions_replaced
from cs451.tracescene import TraceScene


def best_of(fn: Callable[[], object], repeats: int) -> float:
    """The shortest of ``repeats`` wall-clock runs of fn, in seconds."""
    best = math.inf
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return best


def reference_parts(impl: ModuleType) -> SimpleNamespace:
    """The reference's compiled pieces the bench drives directly, and the reference itself (``impl``)."""
    part = lambda name: importlib.import_module(f"cs451.stages.whitted.accel.{name}")
    return SimpleNamespace(kernels=part("kernels"), hierarchy=part("hierarchy"), running=part("running"),
                           queries=part("queries"), impl=impl)


def closest_queries(ref: SimpleNamespace, ts: TraceScene) -> Callable[[np.ndarray, np.ndarray], tuple]:
    """Closest-hit queries through the compiled kernel alone; the function returns (t, prim, stats)."""
    shared = ref.hierarchy.closest_args(ts)

    def run(o: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        n = len(o)
        t, prim, nrm, stats = np.empty(n), np.empty(n, np.int64), np.empty((n, 3)), np.empty((n, 2), np.int64)
        ref.running.in_threads(ref.kernels.closest, n, (o, d), shared, (t, prim, nrm, stats), ref.kernels.scratch())
        return t, prim, stats
    return run


def shadow_queries(ref: SimpleNamespace, ts: TraceScene) -> Callable[[np.ndarray, np.ndarray, np.ndarray], None]:
    """Shadow-ray queries (origins, unit directions, lengths) through the compiled any-hit kernel alone."""
    shared = ref.hierarchy.shadow_args(ts)

    def run(o: np.ndarray, d: np.ndarray, dist: np.ndarray) -> None:
        n = len(o)
        ref.running.in_threads(ref.kernels.transmission, n, (o, d, dist), shared,
                               (np.empty((n, 3)), np.empty((n, 2), np.int64)), ref.kernels.scratch())
    return run


@contextlib.contextmanager
def threads(ref: SimpleNamespace, n: int) -> Iterator[None]:
    """The reference's kernels on n threads for a while."""
    saved = ref.running.THREADS
    ref.running.THREADS = n
    try:
        yield
    finally:
        ref.running.THREADS = saved


def frame_rays(ref: SimpleNamespace, ts: TraceScene, o: np.ndarray, d: np.ndarray) -> dict[str, tuple]:
    """The rays a frame casts, by query: closest hit (origins, directions: camera rays and every reflected
    and refracted one) and shadow (origins, unit directions, lengths).

    Found by tracing the frame bounce by bounce (the path the frame kernel replaces, same rays) with the
    tracer's two queries wrapped to record what they are asked (a replaced W5 or W7 keeps W11 off the fused
    frame kernel; the recorders pass each batch on to the compiled query).
    """
    asked: dict[str, list] = {"closest": [], "shadow": []}

    def recording(kind: str) -> Callable:
        def wrap(own: Callable) -> Callable:
            def asking(scene: TraceScene, origins: np.ndarray, other: np.ndarray) -> object:
                asked[kind].append((origins, other))
                return own(scene, origins, other)
            return asking
        return wrap

    with stage.STAGE.accelerated(ref.impl), \
            functions_replaced(stage.STAGE, ref.impl, {"W5": recording("closest"), "W7": recording("shadow")}):
        ref.impl.trace(ts, o, d)
    co = np.ascontiguousarray(np.concatenate([a for a, _ in asked["closest"]]))
    cd = np.ascontiguousarray(np.concatenate([b for _, b in asked["closest"]]))
    so = np.ascontiguousarray(np.concatenate([a for a, _ in asked["shadow"]] or [np.zeros((0, 3))]))
    seg = np.concatenate([b for _, b in asked["shadow"]] or [np.zeros((0, 3))]) - so
    dist = np.linalg.norm(seg, axis=1)
    sd = np.ascontiguousarray(seg / np.where(dist > 0, dist, 1.0)[:, None])
    return {"closest": (co, cd), "shadow": (so, sd, dist)}
