"""P3: Russian roulette: end some paths at random, and weigh up those that go on, so that the mean is unchanged."""
from __future__ import annotations

import numpy as np


def roulette(weights: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Which paths go on, and their new weights: ``(alive (n,) bool, weights (n, 3))``.

    A path of weight β (RGB) goes on with probability p = min(1, max of β's channels): where ``u`` (n,) < p. One
    that goes on has weight β / p; one that ends, 0. So the mean weight over ``u`` is β: no bias, and a path that
    carries little light ends soon.
    """
    # BEGIN SOLUTION P3: survive with p = min(1, max β), divide the survivors by p (handout §P3)
    beta = np.asarray(weights, dtype=np.float64)
    p = np.minimum(1.0, beta.max(axis=1))
    alive = np.asarray(u, dtype=np.float64) < p
    out = np.zeros_like(beta)
    out[alive] = beta[alive] / p[alive, None]
    return alive, out
    # END SOLUTION
