"""Rows of a whole batch from its atlas at once: the trusted engine's sum of delta form factors per item.

Stage 3's H5 sums one hemicube's item buffers, and stays the student's task (graded on its own). The
trusted engine (the reference, radiosity, benches, slides) instead reduces a batch's atlas where it was
read back: one weighted ``np.bincount`` per row of tiles over the runs of equal items along the tiles' rows,
keyed by (hemicube, item), with H1's tables laid out as the tiles are. No tile is copied and no call is made per
hemicube. The sums are H5's up to float64 rounding (``tests/hemicube/test_formfactors.py`` checks the built-in scenes).
A numba loop over the pixels was as fast, but importing numba added 63 MB to the radiosity main job's peak.
"""
from __future__ import annotations

import numpy as np


class AtlasReduction:
    """Sums the delta form factors of an atlas's tiles per item: rows (count, n) of a batch.

    ``cols`` tiles across, each ``resolution`` wide and 3 · resolution high (the top face, then the four
    sides r/2 high, as :class:`~.atlas.ItemBufferRenderer` lays them out); ``top`` (r, r) and ``side``
    (r/2, r) are H1's tables; items are 0 (nothing) or j + 1 (patch j) of ``n``.

    An item covers runs of pixels along a tile's rows, and the weights' running sums along each tile row are
    fixed: a run's sum is a difference of two of them. So only the runs are counted (one comparison per
    pixel finds them), not the pixels: at resolution 256, about a tenth as many bins to add.
    """

    def __init__(self, top: np.ndarray, side: np.ndarray, cols: int, n: int):
        top, side = np.asarray(top, dtype=np.float64), np.asarray(side, dtype=np.float64)
        tile = np.concatenate([top, side, side, side, side])               # (3r, r): one hemicube's weights
        self.r, self.cols, self.n = top.shape[1], int(cols), int(n)
        # (3r, cols·r), a row of tiles: the weights' running sum along each tile row, up to each pixel included
        self.through = np.tile(np.cumsum(tile, axis=1), (1, self.cols))

    def rows(self, atlas: np.ndarray, count: int) -> np.ndarray:
        """Rows (count, n), float64, of the first ``count`` tiles of ``atlas`` ((tile rows · 3r, cols · r), uint32)."""
        r, r3, n1 = self.r, 3 * self.r, self.n + 1
        out = np.empty((count, self.n))
        for start in range(0, count, self.cols):
            k = min(self.cols, count - start)
            band = np.ascontiguousarray(atlas[(start // self.cols) * r3:(start // self.cols + 1) * r3, :k * r])
            starts = np.empty(band.shape, dtype=bool)
            np.not_equal(band[:, 1:], band[:, :-1], out=starts[:, 1:])
            starts[:, ::r] = True                                            # every tile row starts a run
            first = np.flatnonzero(starts)
            last = np.empty_like(first)
            last[:-1] = first[1:] - 1                                       # a run ends where the next begins
            last[-1] = band.size - 1
            width = k * r
            through = self.through if k == self.cols else np.ascontiguousarray(self.through[:, :width])
            through = through.ravel()
            sums = through[last] - np.where(first % r == 0, 0.0, through[first - 1])   # a run's own weights
            keys = (first % width) // r * n1 + band.ravel()[first]
            out[start:start + k] = np.bincount(keys, weights=sums, minlength=k * n1).reshape(k, n1)[:, 1:]
        return out
