"""What the form-factor engine asks of a stage-3 implementation, and nothing more.

The engine never imports a stage: whoever builds a :class:`~cs451.formfactors.rows.HemicubeFormFactors`
hands it an object with these six calls (``cs451.stages.hemicube.calls(impl)`` wraps a
student's or the reference's package, checking every answer it gives). Tests can hand it
anything that answers the same way.
"""
from __future__ import annotations

from typing import Protocol

import numpy as np


class StageCalls(Protocol):
    """The six tasks of stage 3 as the engine uses them (H1–H6), each answer already checked."""

    def tables(self, resolution: int) -> tuple[np.ndarray, np.ndarray]:
        """H1: the delta form factors of the top face (r, r) and of a side face (r/2, r)."""

    def views(self, center: np.ndarray, normal: np.ndarray, up: np.ndarray) -> np.ndarray:
        """H2: the five view matrices (5, 4, 4) of a hemicube."""

    def projections(self, near: float, far: float) -> np.ndarray:
        """H3: the top and side projections (2, 4, 4)."""

    def shaders(self) -> tuple[str, str]:
        """H4: the item-buffer shaders (vertex, fragment), without a #version line."""

    def row(self, top_items: np.ndarray, side_items: np.ndarray, top_weights: np.ndarray, side_weights: np.ndarray,
            n: int) -> np.ndarray:
        """H5: the row of form factors (n,) from one hemicube's item buffers."""

    def contour(self, point: np.ndarray, normal: np.ndarray, polygon: np.ndarray) -> float:
        """H6: the exact form factor from a point to a polygon."""
