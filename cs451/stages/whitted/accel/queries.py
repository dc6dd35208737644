"""The compiled W1, W5 and W7: the same arguments and answers as the reference's functions, the work done by the
kernels (``kernels.camera``, ``closest``, ``transmission``) over chunks of rays in threads (``running.py``)."""
from __future__ import annotations

from typing import Any

import numpy as np

from ....tracescene import TraceScene

from .hierarchy import closest_args, shadow_args
from .kernels import camera, closest as closest_kernel, scratch, transmission as transmission_kernel
from .running import compiled, in_threads

#: Primitives per leaf before a node is split: the handout's (§W4), as ``reference/whitted/bvh.py`` has it.
LEAF_SIZE = 4


def camera_frame(cam: Any, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """W1: the reference's arithmetic (gluLookAt's frame, rays through pixel centres), compiled; equal to the
    numpy path's rays to the bit (tests/whitted/test_whitted_frame.py)."""
    eye, center, up = (np.asarray(v, dtype=np.float64) for v in (cam.eye, cam.center, cam.up))
    forward = center - eye
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    true_up = np.cross(right, forward)
    tan_y = np.tan(np.radians(cam.fovy) / 2.0)
    tan_x = tan_y * width / height
    origins, directions = np.empty((width * height, 3)), np.empty((width * height, 3))
    args = (eye, forward, right, true_up, float(tan_x), float(tan_y), int(width), int(height), origins, directions)
    compiled(camera, args)
    camera(*args)
    return origins, directions


def closest(scene: TraceScene, origins: np.ndarray, directions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """W5 through the compiled traversal; counts its nodes and tests into the scene's counters as W5 must."""
    o = np.ascontiguousarray(origins, dtype=np.float64)
    d = np.ascontiguousarray(directions, dtype=np.float64)
    n = len(o)
    t, prim, normals = np.empty(n), np.empty(n, np.int64), np.empty((n, 3))
    stats = np.empty((n, 2), np.int64)
    in_threads(closest_kernel, n, (o, d), closest_args(scene), (t, prim, normals, stats), scratch())
    scene.counters["nodes_visited"] += int(stats[:, 0].sum())
    scene.counters["tests"] += int(stats[:, 1].sum())
    return t, prim, normals


def transmission(scene: TraceScene, origins: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """W7 through the compiled any-hit traversal; counts the shadow rays, nodes and tests as W7 must."""
    o = np.ascontiguousarray(origins, dtype=np.float64)
    seg = np.asarray(targets, dtype=np.float64) - o
    dist = np.linalg.norm(seg, axis=1)
    d = np.ascontiguousarray(seg / np.where(dist > 0, dist, 1.0)[:, None])
    n = len(o)
    out = np.empty((n, 3))
    stats = np.empty((n, 2), np.int64)
    in_threads(transmission_kernel, n, (o, d, dist), shadow_args(scene), (out, stats), scratch())
    scene.counters["shadow"] += n
    scene.counters["nodes_visited"] += int(stats[:, 0].sum())
    scene.counters["tests"] += int(stats[:, 1].sum())
    return out
