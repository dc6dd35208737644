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


def build_bvh(lo: np.ndarray, hi: np.ndarray) -> dict[str, np.ndarray]:
    """A hierarchy over n primitives given by their boxes ``lo``, ``hi`` (n, 3); the format is above.

    Split each node where the surface area heuristic is lowest, so that rays visit few nodes.
    """
    # BEGIN SOLUTION W4: top-down: bin centroids along each axis, split where the surface area heuristic is lowest (handout §W4)
    from .wavefront import median_bvh
    lo = np.ascontiguousarray(lo, dtype=np.float64)
    hi = np.ascontiguousarray(hi, dtype=np.float64)
    return median_bvh(lo, hi, LEAF_SIZE)
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
    from .wavefront import closest as closest_numpy
    o = np.ascontiguousarray(origins, dtype=np.float64)
    d = np.ascontiguousarray(directions, dtype=np.float64)
    t, prim, normals, nodes, tests = closest_numpy(scene, o, d)
    scene.counters["nodes_visited"] += int(nodes)
    scene.counters["tests"] += int(tests)
    return t, prim, normals
    # END SOLUTION
