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
    # BEGIN SOLUTION S4: rings of vertices from the north pole down, then fans and strips of triangles (handout §S4)
    theta = np.pi * np.arange(1, stacks) / stacks              # ring angles from +z
    phi = -2.0 * np.pi * np.arange(slices) / slices            # freeglut walks clockwise seen from +z
    st, ct = np.sin(theta)[:, None], np.cos(theta)[:, None]
    ring = np.stack([np.cos(phi)[None, :] * st, np.sin(phi)[None, :] * st,
                     np.broadcast_to(ct, (stacks - 1, slices))], axis=-1).reshape(-1, 3)
    normals = np.vstack([[0.0, 0.0, 1.0], ring, [0.0, 0.0, -1.0]])
    positions = radius * normals

    top, bottom = 0, len(positions) - 1
    j = np.arange(slices)
    jn = (j + 1) % slices
    first = 1 + j                                              # ring 0 (nearest the north pole)
    tris = [np.stack([np.full(slices, top), 1 + jn, first], axis=1)]
    for i in range(stacks - 2):                                # quads between ring i and ring i+1
        a, b = 1 + i * slices + j, 1 + i * slices + jn
        c, d = a + slices, b + slices
        tris.append(np.stack([a, b, d], axis=1))
        tris.append(np.stack([a, d, c], axis=1))
    last = 1 + (stacks - 2) * slices
    tris.append(np.stack([last + j, last + jn, np.full(slices, bottom)], axis=1))
    triangles = np.vstack(tris)
    # phi decreases with j, so (top, j+1, j) is counter-clockwise seen from outside
    return positions, normals, triangles.astype(np.int64)
    # END SOLUTION
