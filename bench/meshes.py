"""Fine meshes of known scenes for the benchmarks and the kit's tests (not shipped to students).

Bilinear k × k subdivision is close to task R1's answer, so it lives here, not in the engine.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from cs451.errors import KitError
from cs451.patches import as_quads


def subdivide_uniform(quads: Any, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Bilinear subdivision of every quad into k×k quads (for benches and tests): (quads (n·k², 4, 3), parent (n·k²,)).

    A triangle patch (last corner repeated) becomes k² thin quads and triangles; all stay planar
    and keep the parent's orientation.
    """
    q = as_quads(quads)
    if k < 1:
        raise KitError(f"subdivision must be >= 1, got {k}")
    t = np.linspace(0.0, 1.0, k + 1)
    s_, t_ = np.meshgrid(t, t, indexing="ij")          # (k+1, k+1)
    a, b, c, d = (q[:, i][:, None, None, :] for i in range(4))
    s3, t3 = s_[None, :, :, None], t_[None, :, :, None]
    grid = (1 - s3) * (1 - t3) * a + s3 * (1 - t3) * b + s3 * t3 * c + (1 - s3) * t3 * d  # (n, k+1, k+1, 3)
    out = np.stack([grid[:, :-1, :-1], grid[:, 1:, :-1], grid[:, 1:, 1:], grid[:, :-1, 1:]], axis=3)  # (n, k, k, 4, 3)
    parent = np.repeat(np.arange(len(q)), k * k)
    return out.reshape(-1, 4, 3), parent
