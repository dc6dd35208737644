"""P1: directions about a normal, distributed as cos θ / π (cosine-weighted hemisphere sampling)."""
from __future__ import annotations

import numpy as np


def cosine_sample(normals: np.ndarray, u: np.ndarray) -> np.ndarray:
    """One direction (n, 3) per unit normal (n, 3), from two uniform numbers in [0, 1) each, ``u`` (n, 2).

    The directions must have the density cos θ / π over the hemisphere about the normal (θ from the normal), be
    unit vectors, and be a function of ``u`` alone (the same ``u``, the same direction): the kit hands you the
    random numbers, so that a render can be repeated.
    """
    # TODO P1: a uniform point of the unit disk lifted to the hemisphere (Malley's method), then the normal's frame (handout §P1)
    raise NotImplementedError("P1: a uniform point of the unit disk lifted to the hemisphere (Malley's method), then the normal's frame (handout §P1)")
