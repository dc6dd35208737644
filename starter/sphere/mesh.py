"""S4: the sphere of glutSolidSphere as a triangle mesh, built once and drawn every frame."""
from __future__ import annotations

import numpy as np


def sphere_mesh(radius: float, slices: int, stacks: int) -> tuple:
    """The vertices, normals and triangles of glutSolidSphere(radius, slices, stacks).

    Returns ``(positions, normals, triangles)``:
    positions (n, 3) float, normals (n, 3) float of unit length,
    triangles (m, 3) int indexing the vertices, counter-clockwise seen from outside.
    As in freeglut: poles on the z axis, ``slices * (stacks - 1) + 2`` vertices,
    ``2 * slices * (stacks - 1)`` triangles.
    """
    # TODO S4: rings of vertices from the north pole down, then fans and strips of triangles (handout §S4)
    raise NotImplementedError("S4: rings of vertices from the north pole down, then fans and strips of triangles (handout §S4)")
