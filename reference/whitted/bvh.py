"""W4, W5: a bounding volume hierarchy over the scene's primitives, and the closest hit of many rays.

The hierarchy is a dict of flat arrays (node 0 is the root)::

    lo, hi  (m, 3) float   each node's axis-aligned box
    child   (m,)   int     index of the node's first child (the second is child + 1); -1 at a leaf
    start   (m,)   int     a leaf's first slot in ``order``
    count   (m,)   int     how many primitives the leaf holds (at most 8)
    order   (n,)   int     primitive numbers, leaf by leaf
"""
from __future__ import annotations

import numpy as np

from cs451.raytrace import TraceScene

LEAF_SIZE = 4
# BEGIN SOLUTION
#: Batches at least this large go to the compiled kernels (kernels.py); smaller ones, to plain numpy
#: (wavefront.py), where compiling would cost more than it saves.
COMPILED_RAYS = 10_000
COMPILED_PRIMS = 5_000
_compiled = [False]


def use_compiled(n: int) -> bool:
    """Large batches compile the kernels once; after that, every batch uses them."""
    if n >= COMPILED_RAYS:
        _compiled[0] = True
    return _compiled[0]
# END SOLUTION


def build_bvh(lo: np.ndarray, hi: np.ndarray) -> dict[str, np.ndarray]:
    """A hierarchy over n primitives given by their boxes ``lo``, ``hi`` (n, 3); the format is above.

    Split each node where the surface area heuristic is lowest, so that rays visit few nodes.
    """
    # BEGIN SOLUTION W4: top-down: bin centroids along each axis, split where the surface area heuristic is lowest (handout §W4)
    lo = np.ascontiguousarray(lo, dtype=np.float64)
    hi = np.ascontiguousarray(hi, dtype=np.float64)
    if len(lo) < COMPILED_PRIMS:   # small: a numpy median split, level by level (no compiling)
        from .wavefront import median_bvh
        return median_bvh(lo, hi, LEAF_SIZE)
    from .kernels import build
    keys = ("lo", "hi", "child", "start", "count", "order")
    return dict(zip(keys, build(lo, hi, LEAF_SIZE)))
    # END SOLUTION


# BEGIN SOLUTION
def packed(scene: TraceScene) -> dict:
    """The scene's arrays in the layout the compiled kernels read, built once per scene."""
    cached = getattr(scene, "_reference_packed", None)
    if cached is not None:
        return cached
    bvh = scene.bvh
    one = np.zeros(1, np.int64)
    if bvh is None:
        tree = (np.zeros((1, 8), np.float32), one - 1, one, one, one, False)
    else:
        # node boxes in float32, rounded outwards, 32 bytes a node: the tree stays in the CPU's cache
        lo, hi = np.asarray(bvh["lo"], np.float64), np.asarray(bvh["hi"], np.float64)
        lo32, hi32 = lo.astype(np.float32), hi.astype(np.float32)
        lo32 = np.where(lo32 > lo, np.nextafter(lo32, np.float32(-np.inf)), lo32)
        hi32 = np.where(hi32 < hi, np.nextafter(hi32, np.float32(np.inf)), hi32)
        box = np.zeros((len(lo), 8), np.float32)
        box[:, :3], box[:, 3:6] = lo32, hi32
        tree = (box, np.ascontiguousarray(bvh["child"], np.int64), np.ascontiguousarray(bvh["start"], np.int64),
                np.ascontiguousarray(bvh["count"], np.int64), np.ascontiguousarray(bvh["order"], np.int64), True)
    sph = np.ascontiguousarray(np.column_stack([scene.sphere_center, scene.sphere_radius]).reshape(-1, 4))
    tri = np.ascontiguousarray(np.concatenate([scene.tri_v0, scene.tri_v1, scene.tri_v2], axis=1).reshape(-1, 9))
    planes = np.ascontiguousarray(np.concatenate([scene.plane_point, scene.plane_normal], axis=1).reshape(-1, 6))
    frame = np.ascontiguousarray(np.concatenate([scene.plane_u, scene.plane_v], axis=1).reshape(-1, 6))
    e1, e2 = scene.tri_v1 - scene.tri_v0, scene.tri_v2 - scene.tri_v0
    tn = np.cross(e1, e2)
    length = np.linalg.norm(tn, axis=1, keepdims=True)
    out = {"tree": tree, "nsph": scene.n_spheres, "sph": sph, "tri": tri, "planes": planes, "frame": frame,
           "tri_normal": np.ascontiguousarray(tn / np.where(length > 0, length, 1.0))}
    scene._reference_packed = out  # type: ignore[attr-defined]
    return out
# END SOLUTION


def closest_hit(scene: TraceScene, origins: np.ndarray, directions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The nearest hit (t > 0) of each ray (n, 3) with the scene's spheres, triangles and planes.

    Returns ``(t, prim, normals)``: t (n,) float, ``inf`` on a miss; prim (n,) int, the primitive's
    number (spheres, then triangles, then planes) or -1; normals (n, 3) unit geometric normals
    (a sphere's outward, a triangle's by its winding, a plane's own), zero on a miss. Uses
    ``scene.bvh`` when it is not None, and adds its work to ``scene.counters["nodes_visited"]``
    and ``scene.counters["tests"]``.
    """
    # BEGIN SOLUTION W5: traverse the hierarchy near child first, keep the nearest t (handout §W5)
    o = np.ascontiguousarray(origins, dtype=np.float64)
    d = np.ascontiguousarray(directions, dtype=np.float64)
    n = len(o)
    if not use_compiled(n):
        from .wavefront import closest as closest_numpy
        t, prim, normals, nodes, tests = closest_numpy(scene, o, d)
        scene.counters["nodes_visited"] += int(nodes)
        scene.counters["tests"] += int(tests)
        return t, prim, normals
    from .kernels import closest, in_threads
    p = packed(scene)
    t = np.empty(n)
    prim = np.empty(n, np.int64)
    normals = np.empty((n, 3))
    stats = np.empty((n, 2), np.int64)
    in_threads(closest, n, (o, d), (*p["tree"], p["nsph"], p["sph"], p["tri"], p["planes"], p["tri_normal"]),
               (t, prim, normals, stats))
    scene.counters["nodes_visited"] += int(stats[:, 0].sum())
    scene.counters["tests"] += int(stats[:, 1].sum())
    return t, prim, normals
    # END SOLUTION
