"""Patch geometry as (n, 4, 3) quads; relied on by stage 3 (form factors), stage 4 (radiosity) and the benches.

A patch is a planar convex quad with its corners counter-clockwise seen from
the front (its front normal is the Newell normal). A triangle is a quad whose
last corner repeats the third. Everything here is float64 and vectorised over
patches; nothing here subdivides: subdividing is a stage-4 task (R1), and this
module ships to students (the benchmarks' and tests' fine meshes come from
``bench/meshes.py``).
"""
from __future__ import annotations

from typing import Any

import numpy as np

from .errors import KitError


def as_quads(quads: Any) -> np.ndarray:
    """``quads`` as a float64 array of shape (n, 4, 3), or a KitError saying what is wrong."""
    q = np.asarray(quads, dtype=np.float64)
    if q.ndim != 3 or q.shape[1:] != (4, 3):
        raise KitError(f"patches must have shape (n, 4, 3), got {q.shape}")
    if not np.isfinite(q).all():
        raise KitError("patches contain NaN or infinite coordinates")
    return q


def _newell(quads: np.ndarray) -> np.ndarray:
    nxt = np.roll(quads, -1, axis=1)
    return 0.5 * np.cross(quads, nxt).sum(axis=1)  # half the Newell vector: length = area


def patch_normals(quads: Any) -> np.ndarray:
    """Unit front normals (n, 3), by Newell's method (robust for planar polygons, and for repeated corners)."""
    v = _newell(as_quads(quads))
    length = np.linalg.norm(v, axis=1, keepdims=True)
    if np.any(length <= 0):
        bad = int(np.argmin(length[:, 0]))
        raise KitError(f"patch {bad} is degenerate (zero area)")
    return v / length


def patch_areas(quads: Any) -> np.ndarray:
    """Areas (n,) of planar polygons: half the length of the Newell vector."""
    return np.linalg.norm(_newell(as_quads(quads)), axis=1)


def patch_centers(quads: Any) -> np.ndarray:
    """Area centroids (n, 3): the two triangles (0,1,2) and (0,2,3) weighted by their areas.

    A triangle (last corner repeating the third) gets its own centroid, not the corners' mean.
    """
    q = as_quads(quads)
    a, b, c, d = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    w1 = np.linalg.norm(np.cross(b - a, c - a), axis=1)
    w2 = np.linalg.norm(np.cross(c - a, d - a), axis=1)
    c1, c2 = (a + b + c) / 3, (a + c + d) / 3
    total = w1 + w2
    safe = np.where(total > 0, total, 1.0)
    centroid = (c1 * w1[:, None] + c2 * w2[:, None]) / safe[:, None]
    return np.where((total > 0)[:, None], centroid, q.mean(axis=1))


def patch_triangles(quads: Any) -> tuple[np.ndarray, np.ndarray]:
    """Two triangles per patch for rasterising: positions (2n, 3, 3) and the patch id of each triangle (2n,).

    A triangle patch's second triangle is degenerate (zero area) and draws nothing.
    """
    q = as_quads(quads)
    tris = np.stack([q[:, [0, 1, 2]], q[:, [0, 2, 3]]], axis=1).reshape(-1, 3, 3)
    ids = np.repeat(np.arange(len(q)), 2)
    return tris, ids


def polygon_to_quads(vertices: Any) -> np.ndarray:
    """A planar convex polygon (m, 3), m >= 3, as quads: itself when m <= 4, else a fan of triangles."""
    v = np.asarray(vertices, dtype=np.float64)
    if len(v) == 3:
        return v[[0, 1, 2, 2]][None]
    if len(v) == 4:
        return v[None]
    return np.stack([v[[0, k, k + 1, k + 1]] for k in range(1, len(v) - 1)])


def scene_polygons(scene: Any) -> tuple[np.ndarray, list[str], np.ndarray]:
    """A loaded Scene's polygons and area lights as patches: (quads (n,4,3), material names (n,), emission (n,3)).

    Polygon objects keep their corners (more than four are fanned into triangles);
    each area light becomes one emitting quad (corner, +u, +u+v, +v), whose front
    faces ``edge_u × edge_v`` as the scene schema says, with material name
    ``"light"`` and emission = its radiance. Polygons' emission is their
    material's ``emission``. Any other kind (a sphere, a plane, a mesh, a point light) is not a patch and is
    refused, naming it, rather than left out of the energy balance unseen.
    """
    from .scene import AreaLight, Polygon  # local: keep this module cheap to import

    quads, names, emission = [], [], []
    for k, obj in enumerate(scene.objects):
        if not isinstance(obj, Polygon):
            raise KitError(f"{scene.label}: objects[{k}]: patches are made of polygons and area lights, "
                           f"not of a {type(obj).__name__}")
        q = polygon_to_quads(obj.vertices)
        quads.append(q)
        names += [obj.material] * len(q)
        emission += [tuple(scene.material(obj.material).emission)] * len(q)
    for k, light in enumerate(scene.lights):
        if not isinstance(light, AreaLight):
            raise KitError(f"{scene.label}: lights[{k}]: patches are made of polygons and area lights, "
                           f"not of a {type(light).__name__}")
        c, u, v = (np.asarray(x, dtype=np.float64) for x in (light.corner, light.edge_u, light.edge_v))
        quads.append(np.array([[c, c + u, c + u + v, c + v]]))
        names.append("light")
        emission.append(tuple(light.radiance))
    if not quads:
        raise KitError(f"{scene.label}: objects: no polygons or area lights to make patches of")
    return np.concatenate(quads), names, np.asarray(emission, dtype=np.float64).reshape(-1, 3)
