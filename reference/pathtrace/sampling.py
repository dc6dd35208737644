"""P1: directions about a normal, distributed as cos θ / π (cosine-weighted hemisphere sampling)."""
from __future__ import annotations

import numpy as np


def cosine_sample(normals: np.ndarray, u: np.ndarray) -> np.ndarray:
    """One direction (n, 3) per unit normal (n, 3), from two uniform numbers in [0, 1) each, ``u`` (n, 2).

    The directions must have the density cos θ / π over the hemisphere about the normal (θ from the normal), be
    unit vectors, and be a function of ``u`` alone (the same ``u``, the same direction): the kit hands you the
    random numbers, so that a render can be repeated.
    """
    # BEGIN SOLUTION P1: a uniform point of the unit disk lifted to the hemisphere (Malley's method), then the normal's frame (handout §P1)
    n = np.asarray(normals, dtype=np.float64)
    u = np.asarray(u, dtype=np.float64)
    r, phi = np.sqrt(u[:, 0]), 2.0 * np.pi * u[:, 1]
    x, y = r * np.cos(phi), r * np.sin(phi)
    z = np.sqrt(np.maximum(0.0, 1.0 - u[:, 0]))
    # an orthonormal frame about each normal, without a branch on its direction (Duff et al. 2017)
    sign = np.where(n[:, 2] >= 0.0, 1.0, -1.0)
    a = -1.0 / (sign + n[:, 2])
    b = n[:, 0] * n[:, 1] * a
    t1 = np.stack([1.0 + sign * n[:, 0] ** 2 * a, sign * b, -sign * n[:, 0]], axis=1)
    t2 = np.stack([b, sign + n[:, 1] ** 2 * a, -n[:, 1]], axis=1)
    return x[:, None] * t1 + y[:, None] * t2 + z[:, None] * n
    # END SOLUTION
