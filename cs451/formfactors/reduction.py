"""Rows of a whole batch from its atlas at once: the trusted engine's sum of delta form factors per item.

Stage 3's H5 sums one hemicube's item buffers, and stays the student's task (graded on its own). The
trusted engine (the reference, radiosity, benches, slides) instead reduces a batch's atlas where it was
read back: one weighted ``np.bincount`` per row of tiles, keyed by (hemicube, item), with H1's tables laid
out as the tiles are. No tile is copied and no call is made per hemicube. The sums are H5's up to the order
of float64 additions (``tests/test_formfactors.py`` checks the built-in scenes). A numba loop summed 2×
faster, but importing numba alone added 63 MB to the radiosity main job's peak (265 MB before this engine).
"""
from __future__ import annotations

import numpy as np


class AtlasReduction:
    """Sums the delta form factors of an atlas's tiles per item: rows (count, n) of a batch.

    ``cols`` tiles across, each ``resolution`` wide and 3 · resolution high (the top face, then the four
    sides r/2 high, as :class:`~.atlas.ItemBufferRenderer` lays them out); ``top`` (r, r) and ``side``
    (r/2, r) are H1's tables; items are 0 (nothing) or j + 1 (patch j) of ``n``.
    """

    def __init__(self, top: np.ndarray, side: np.ndarray, cols: int, n: int):
        top, side = np.asarray(top, dtype=np.float64), np.asarray(side, dtype=np.float64)
        tile = np.concatenate([top, side, side, side, side])               # (3r, r): one hemicube's weights
        self.r, self.cols, self.n = top.shape[1], int(cols), int(n)
        self.weights = np.tile(tile, (1, self.cols))                        # (3r, cols·r): a row of tiles
        # (n + 1) · column, per pixel: a tile's items land in its own block of bins
        self.offsets = np.repeat(np.arange(self.cols, dtype=np.int64) * (self.n + 1), self.r)[None, :]
        self._keys = np.empty(self.weights.shape, dtype=np.int64)          # reused: nothing new for the kernel to zero

    def rows(self, atlas: np.ndarray, count: int) -> np.ndarray:
        """Rows (count, n), float64, of the first ``count`` tiles of ``atlas`` ((tile rows · 3r, cols · r), uint32)."""
        r3, n1 = 3 * self.r, self.n + 1
        out = np.empty((count, self.n))
        for start in range(0, count, self.cols):
            k = min(self.cols, count - start)
            band = atlas[(start // self.cols) * r3:(start // self.cols + 1) * r3, :k * self.r]
            keys = np.add(band, self.offsets[:, :k * self.r], out=self._keys[:, :k * self.r])   # (3r, k·r)
            weights = self.weights if k == self.cols else self.weights[:, :k * self.r]
            sums = np.bincount(keys.ravel(), weights=weights.ravel(), minlength=k * n1)
            out[start:start + k] = sums.reshape(k, n1)[:, 1:]
        return out
