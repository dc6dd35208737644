"""The reference's compiled W11: a whole frame's recursion in one kernel (``kernels.frame``), so that no
per-bounce bookkeeping runs in numpy. ``tracer.trace`` hands large batches here; both give the same
colours to rounding and the same counters (``tests/whitted/test_whitted_frame.py``). A student's starter has no copy of it.
"""
from __future__ import annotations

import numpy as np

from ....tracescene import SPAWN_OFFSET, TraceScene

from . import kernels as K
from .hierarchy import closest_args, packed
from .running import in_threads


def frame_arrays(scene: TraceScene) -> tuple[np.ndarray, np.ndarray]:
    """Materials and light samples as the frame kernel's rows (column numbers: ``kernels.M_*``, ``L_*``)."""
    mats = np.zeros((len(scene.mat_ior), K.M_WIDTH))
    for col, values in ((K.M_AMBIENT, scene.mat_ambient), (K.M_DIFFUSE, scene.mat_diffuse),
                        (K.M_SPECULAR, scene.mat_specular), (K.M_EMISSION, scene.mat_emission),
                        (K.M_REFLECT, scene.mat_reflectance), (K.M_TRANSMIT, scene.mat_transmittance)):
        mats[:, col:col + 3] = values
    mats[:, K.M_SHININESS] = scene.mat_shininess
    mats[:, K.M_IOR] = scene.mat_ior
    mats[:, K.M_FRESNEL] = scene.mat_fresnel
    lights = np.zeros((len(scene.light_position), K.L_WIDTH))
    for col, values in ((K.L_POS, scene.light_position), (K.L_DIFFUSE, scene.light_diffuse),
                        (K.L_SPECULAR, scene.light_specular), (K.L_ATT, scene.light_attenuation),
                        (K.L_NORMAL, scene.light_normal)):
        lights[:, col:col + 3] = values
    lights[:, K.L_AREA] = np.any(scene.light_normal != 0, axis=1)
    return mats, lights


def frame_shared(scene: TraceScene, tree: tuple | None = None) -> tuple:
    """The frame kernel's arguments that every ray shares: the scene's geometry, hierarchy (``tree``: another
    layout of it, for the bench; the scene's own by default), materials, lights and options."""
    mats, lights = frame_arrays(scene)
    return (*closest_args(scene, tree), packed(scene)["frame"], scene.plane_checker, scene.plane_checker_material, scene.prim_material,
            np.ascontiguousarray(scene.mat_transmittance), mats, lights,
            np.ascontiguousarray(scene.ambient_light, np.float64), np.ascontiguousarray(scene.background, np.float64),
            int(scene.max_depth), float(scene.min_weight), SPAWN_OFFSET)


def trace_frame(scene: TraceScene, origins: np.ndarray, directions: np.ndarray,
                threads: int | None = None) -> np.ndarray:
    """``tracer.trace`` in one compiled kernel: the colour (n, 3) along each camera ray, counters updated.

    ``threads``: ``running.THREADS`` by default; the rays go in runs of 16 per thread, as the cost of a
    pixel varies (a glass sphere's pixels spawn many rays).
    """
    o = np.ascontiguousarray(origins, dtype=np.float64)
    d = np.ascontiguousarray(directions, dtype=np.float64)
    n = len(o)
    colour = np.empty((n, 3))
    counts = np.empty((n, 5), np.int64)
    in_threads(K.frame, n, (o, d), frame_shared(scene), (colour, counts), K.scratch(int(scene.max_depth)),
               threads=threads, chunks=16)
    total = np.einsum("ij->j", counts)   # the column sums; 4x faster than counts.sum(axis=0) on (n, 5) int64
    scene.counters["camera"] += n
    for k, name in enumerate(("shadow", "reflection", "transmission", "nodes_visited", "tests")):
        scene.counters[name] += int(total[k])
    return colour
