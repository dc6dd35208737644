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

from cs451.tracescene import TraceScene

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


#: Whether ``trace`` runs compiled batches as whole frames (kernels.frame) rather than bounce by bounce in
#: numpy over the compiled closest-hit and shadow kernels (the tests compare the two).
FRAME_KERNEL = True
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
    from .hierarchy import built
    return built(lo, hi, LEAF_SIZE)   # compiled, and cached by the boxes' digest (hierarchy.py)
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
    from .hierarchy import closest_args
    from .kernels import closest, scratch
    from .running import in_threads
    t = np.empty(n)
    prim = np.empty(n, np.int64)
    normals = np.empty((n, 3))
    stats = np.empty((n, 2), np.int64)
    in_threads(closest, n, (o, d), closest_args(scene), (t, prim, normals, stats), scratch())
    scene.counters["nodes_visited"] += int(stats[:, 0].sum())
    scene.counters["tests"] += int(stats[:, 1].sum())
    return t, prim, normals
    # END SOLUTION
