"""Given: camera rays through jittered points of each pixel, and ray casting against the scene's triangles.

Plain and brute force (every ray against every triangle, in chunks): a closed box of a few dozen triangles needs
no hierarchy. Your Whitted tracer (stage 2) does all of this faster; you may use yours instead.
"""
from __future__ import annotations

import numpy as np

#: rays × triangles tested at once (memory: about 100 bytes each)
CHUNK = 1 << 20


def camera_rays(camera, width: int, height: int, jitter: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One ray from the eye through a point of every pixel, row by row from the top left: ray ``j * width + i``
    goes through column ``i`` of row ``j`` at ``jitter[j * width + i]`` (in [0, 1)², (0.5, 0.5) is the centre).
    The camera is gluLookAt's (eye, center, up) with a vertical field of view ``fovy`` in degrees."""
    eye, center, up = (np.asarray(v, dtype=np.float64) for v in (camera.eye, camera.center, camera.up))
    forward = (center - eye) / np.linalg.norm(center - eye)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    true_up = np.cross(right, forward)
    tan_y = np.tan(np.radians(camera.fovy) / 2.0)
    tan_x = tan_y * width / height
    j, i = np.divmod(np.arange(width * height), width)
    jitter = np.asarray(jitter, dtype=np.float64).reshape(-1, 2)
    x = (2.0 * (i + jitter[:, 0]) / width - 1.0) * tan_x
    y = (1.0 - 2.0 * (j + jitter[:, 1]) / height) * tan_y
    directions = forward + x[:, None] * right + y[:, None] * true_up
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    return np.broadcast_to(eye, directions.shape).copy(), directions


def _hits(scene, o: np.ndarray, d: np.ndarray) -> np.ndarray:
    """t (n, m) of each ray with each triangle (Möller-Trumbore, both sides), inf where it misses or t <= 0."""
    e1, e2 = scene.v1 - scene.v0, scene.v2 - scene.v0
    p = np.cross(d[:, None, :], e2[None, :, :])
    det = np.einsum("nmk,mk->nm", p, e1)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
        s = o[:, None, :] - scene.v0[None, :, :]
        a = np.einsum("nmk,nmk->nm", s, p) * inv
        q = np.cross(s, e1[None, :, :])
        b = np.einsum("nk,nmk->nm", d, q) * inv
        t = np.einsum("mk,nmk->nm", e2, q) * inv
        ok = (det != 0) & (a >= 0) & (b >= 0) & (a + b <= 1) & (t > 0)
    return np.where(ok, t, np.inf)


def closest_hit(scene, origins: np.ndarray, directions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The nearest hit (t > 0) of each ray with the scene's triangles: ``(t, tri)``, t ``inf`` and tri -1 on a miss."""
    o, d = np.asarray(origins, dtype=np.float64), np.asarray(directions, dtype=np.float64)
    t, tri = np.full(len(o), np.inf), np.full(len(o), -1)
    step = max(1, CHUNK // max(scene.n_triangles, 1))
    for s in range(0, len(o), step):
        all_t = _hits(scene, o[s:s + step], d[s:s + step])
        k = np.argmin(all_t, axis=1)
        t[s:s + step] = all_t[np.arange(len(k)), k]
        tri[s:s + step] = np.where(np.isfinite(t[s:s + step]), k, -1)
    return t, tri


def unoccluded(scene, points: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """Whether nothing lies on each segment from a point to its target (n,) bool: a shadow ray. The points should
    already be moved off their surface; a hit within 1e-7 of the segment's length from the target is the target's
    own surface (the light), not a blocker."""
    p = np.asarray(points, dtype=np.float64)
    seg = np.asarray(targets, dtype=np.float64) - p
    out = np.ones(len(p), bool)
    step = max(1, CHUNK // max(scene.n_triangles, 1))
    for s in range(0, len(p), step):
        t = _hits(scene, p[s:s + step], seg[s:s + step])          # in units of the segment: the target is t = 1
        out[s:s + step] = ~(t < 1.0 - 1e-7).any(axis=1)
    scene.counters["shadow"] += len(p)
    return out
