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

LEAF_SIZE = 4   # split every node of more primitives than this; a leaf may hold at most 8 (handout §W4)
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
def _tree(bvh: dict, nsph: int, tri: np.ndarray) -> tuple:
    """The hierarchy as the kernels read it: four-wide, one 128-byte row per node (two cache lines).

    The binary tree is collapsed: each row takes a binary node's children and opens the largest
    inner one until it has four. Row q, in 32 words: float32 boxes of its four children as
    lo x, y, z then hi x, y, z, four of each (rounded outwards; words 0-23), then int32 words 24-27
    the children's rows (or a leaf's first slot in ``order``) and 28-31: -1 for a row, the leaf's
    count, or -2 for an empty slot. Row 0 holds only the root. Triangles are copied into slot order.
    """
    lo, hi = np.asarray(bvh["lo"], np.float64), np.asarray(bvh["hi"], np.float64)
    lo32, hi32 = lo.astype(np.float32), hi.astype(np.float32)
    lo32 = np.where(lo32 > lo, np.nextafter(lo32, np.float32(-np.inf)), lo32)
    hi32 = np.where(hi32 < hi, np.nextafter(hi32, np.float32(np.inf)), hi32)
    child = np.asarray(bvh["child"], np.int64).tolist()
    start = np.asarray(bvh["start"], np.int64)
    count = np.asarray(bvh["count"], np.int64)
    ext = hi - lo
    area = (ext[:, 0] * ext[:, 1] + ext[:, 1] * ext[:, 2] + ext[:, 2] * ext[:, 0]).tolist()
    kids = [[0]]                 # row 0: the root alone
    row_of = {}
    todo = [0] if child[0] >= 0 else []
    while todo:
        node = todo.pop()
        row_of[node] = len(kids)
        group = [child[node], child[node] + 1]
        while len(group) < 4:
            inner = [k for k in group if child[k] >= 0]
            if not inner:
                break
            k = max(inner, key=lambda k: area[k])
            i = group.index(k)
            group[i:i + 1] = [child[k], child[k] + 1]
        kids.append(group)
        todo.extend(k for k in reversed(group) if child[k] >= 0)
    raw = np.zeros(len(kids) * 32 + 16, np.int32)  # rows start on 64-byte cache lines
    skip = (-raw.ctypes.data % 64) // 4
    ni = raw[skip:skip + len(kids) * 32].reshape(-1, 32)
    nf = ni.view(np.float32)
    ni[:, 28:32] = -2
    nf[:, :24] = np.inf          # an empty slot's box: no ray enters it
    for q, group in enumerate(kids):
        for c, k in enumerate(group):
            nf[q, c:24:4] = np.concatenate([lo32[k], hi32[k]])
            if child[k] >= 0:
                ni[q, 24 + c], ni[q, 28 + c] = row_of[k], -1
            else:
                ni[q, 24 + c], ni[q, 28 + c] = start[k], count[k]
    order = np.ascontiguousarray(bvh["order"], np.int64)
    ltri = np.zeros((len(order), 9))
    is_tri = order >= nsph
    ltri[is_tri] = tri[order[is_tri] - nsph]
    return nf, ni, order, ltri, True


def packed(scene: TraceScene) -> dict:
    """The scene's arrays in the layout the compiled kernels read, built once per scene."""
    cached = getattr(scene, "_reference_packed", None)
    if cached is not None:
        return cached
    bvh = scene.bvh
    tri = np.ascontiguousarray(np.concatenate([scene.tri_v0, scene.tri_v1, scene.tri_v2], axis=1).reshape(-1, 9))
    if bvh is None:
        ni = np.zeros((1, 32), np.int32)
        tree = (ni.view(np.float32), ni, np.zeros(1, np.int64), tri, False)
    else:
        tree = _tree(bvh, scene.n_spheres, tri)
    sph = np.ascontiguousarray(np.column_stack([scene.sphere_center, scene.sphere_radius]).reshape(-1, 4))
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
