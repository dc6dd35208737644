"""The proximity fix: a hemicube row corrected for the shooter's extent where the point estimate is measurably off.

A hemicube stands at a point (the patch centre; with a split shooter or a blind patch, a few points with
weights) and measures form factors from there, while F_ij is the average over patch i's area. For receiver j
the fix keeps what the hemicube saw and corrects its place:

    F_ij ≈ row_ij · avg_{p on i} F(p → j) / Σ_w w·F(P_w → j)

where P_w are the points the row's hemicubes stood at. The ratio carries the hemicube's visibility over (the
same fraction of j hidden), needs no cap (capping the visible fraction at 1 biased close entries low, mean
0.9977 over 1,024 pairs), and divides by what the hemicube's own points measure, so a split shooter is not
corrected twice (unit squares one apart, split 4 × 4: 0.1684 against 0.19982 before).

Which receivers, and how (chosen by the estimated error, not by a fixed distance alone):

* far (the gap to j's bounding sphere more than ``REACH`` shooter radii): the point estimate is off by less than
  about 2·(σ/d)² < 0.1% (σ² the shooter's positional variance); nothing is done;
* close (gap under ``proximity_distance`` times the larger radius): H6, the stage-3 implementation's exact
  point-to-polygon form factor, integrated over the shooter by a graded composite Gauss rule, finer toward j
  (near a shared edge F(p) changes on the scale of the distance to the edge, which a fixed 5 × 5 rule missed
  by 20% for a 5 × 1 floor beside a 1 × 0.2 wall; :mod:`.shooter_quadrature`). Visibility: where nothing can
  stand between i and j (:func:`~.visibility.occluders`), the hemicube's own fraction of j seen, as above
  (at most all of it where j is too nearly edge-on from the hemicubes' points for a cell to measure);
  where something can, the fraction each quadrature point sees, by sight lines to a grid on j
  (:class:`~.visibility.Sightlines`), the shooter refined where they disagree. Carrying the centre's view over
  the whole shooter was wrong under occlusion: the Cornell box's floor (one polygon, partly under the blocks)
  summed to 0.4687 against an area average of 0.698; with sight lines 0.694, every entry of the box's 16 × 16
  matrix within 0.006 of ray casting from random points (tests/hemicube/test_proximity_occlusion.py);
* in between: the ratio above from a cheap quadrature of the form-factor integral itself (cos·cos/πr²
  between Gauss points of both patches, the kit's own and not H6), applied where it moves the entry by more
  than ``PROXIMITY_ERROR`` (unit squares 0.2 wide five apart: +1.4% before). Where the hemicubes' points reach
  j by less than one cell can read, the corrected entry is at most the unoccluded quadrature (``fix_row``).
"""
from __future__ import annotations

from typing import Any

import numpy as np

from ..patches import patch_areas
from .geometry import clip_polygon_to_plane, gauss_points
from .shooter_quadrature import ContourIntegral
from .visibility import Sightlines, occluders

#: correct an entry where the kernel says the point estimate is off by more than this (relative)
PROXIMITY_ERROR = 1e-3
#: beyond this many shooter radii (gap to the receiver's bounding sphere) the point estimate is within ~0.1%
REACH = 40.0
#: a close receiver the hemicube sees within this fraction of wholly (row / H6 at its points) is taken as wholly
#: visible: its cells cannot tell finer (a 1 × 0.2 wall at grazing angle 2.5 away spans five rows and reads 1.01)
VISIBLE_SNAP = 0.02
#: Gauss points per side of the shooter (true average) and of the receiver, for the kernel
KERNEL_SHOOTER, KERNEL_RECEIVER = 3, 2


def _gauss_many(quads: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss points (J, k², 3) and area weights (J, k²) on many quads' bilinear maps at once."""
    x, w = np.polynomial.legendre.leggauss(k)
    s, ws = 0.5 * (x + 1), 0.5 * w
    S, T = (g.ravel()[None, :, None] for g in np.meshgrid(s, s, indexing="ij"))
    W = np.outer(ws, ws).ravel()[None, :]
    a, b, c, d = (quads[:, m][:, None, :] for m in range(4))
    p = (1 - S) * (1 - T) * a + S * (1 - T) * b + S * T * c + (1 - S) * T * d
    ds = (1 - T) * (b - a) + T * (c - d)
    dt = (1 - S) * (d - a) + S * (c - b)
    return p, W * np.linalg.norm(np.cross(ds, dt), axis=2)


def kernel(points: np.ndarray, normal: np.ndarray, weights: np.ndarray, receivers: np.ndarray,
           receiver_normals: np.ndarray) -> np.ndarray:
    """Σ_w weights_w · F(points_w → j) for receivers j, F by Gauss points on j of cos⁺·cos⁺/(π r²): (J,)."""
    q, a = _gauss_many(receivers, KERNEL_RECEIVER)                                 # (J, g, 3), (J, g)
    d = q[None] - points[:, None, None, :]                                         # (P, J, g, 3)
    r2 = np.maximum((d * d).sum(axis=3), 1e-300)
    cos_i = np.maximum(d @ normal, 0.0)
    cos_j = np.maximum(-(d * receiver_normals[None, :, None, :]).sum(axis=3), 0.0)
    f = (cos_i * cos_j / (np.pi * r2 * r2) * a[None]).sum(axis=2)                  # (P, J)
    return weights @ f


def fix_row(calls: Any, quads: np.ndarray, normals: np.ndarray, centers: np.ndarray, radii: np.ndarray, i: int,
            row: np.ndarray, stands: tuple[np.ndarray, np.ndarray], proximity_distance: float,
            counters: dict[str, int], cell: float) -> np.ndarray:
    """Row ``row`` of patch i, measured from the points ``stands`` = (points, weights summing to 1), with each
    entry corrected as the module says. ``cell``: the largest delta form factor of one hemicube cell, the least
    the row can tell. Where the points reach a receiver by less than that, the ratio of what the row read to
    what they reach is not a fraction seen, and is capped at 1: a block's face whose centre lay in the plane of
    the other block's top (reached by 1e-18) once read one cell of it, and the entry became 5e9.

    Counts ``proximity_pairs`` (H6), ``proximity_kernel_pairs``, ``proximity_evaluations`` (H6 calls),
    ``proximity_occluded_pairs`` (close pairs with something between) and ``proximity_rays`` (their sight lines)."""
    c, n, r_i = centers[i], normals[i], radii[i]
    points, weights = stands
    gap = np.linalg.norm(centers - c, axis=1) - radii
    heights = (quads - c) @ n
    ahead = heights.max(axis=1) > 1e-9 * r_i
    ahead[i] = False
    close = ahead & (gap < proximity_distance * np.maximum(r_i, radii))
    middle = ahead & ~close & (gap < REACH * r_i) & (row > 0)
    out = np.array(row, dtype=np.float64)
    if middle.any():
        J = np.flatnonzero(middle)
        true_points, true_w = gauss_points(quads[i], KERNEL_SHOOTER)
        true = kernel(true_points, n, true_w / true_w.sum(), quads[J], normals[J])
        measured = kernel(points, n, weights, quads[J], normals[J])
        ok = measured > 0
        ratio = np.where(ok, true / np.where(ok, measured, 1.0), 1.0)
        moved = ok & (np.abs(ratio - 1.0) > PROXIMITY_ERROR)
        fixed = row[J] * ratio
        faint = measured <= cell              # below what a cell can tell: the fraction seen is at most 1
        fixed[faint] = np.minimum(fixed[faint], true[faint])
        out[J[moved]] = fixed[moved]
        counters["proximity_kernel_pairs"] = counters.get("proximity_kernel_pairs", 0) + int(moved.sum())
    area = float(patch_areas(quads[i:i + 1])[0])
    size = float(np.ptp(quads.reshape(-1, 3), axis=0).max())
    for j in np.flatnonzero(close):
        poly = clip_polygon_to_plane(quads[j], c, n)
        if len(poly) < 3:
            continue
        blockers = occluders(quads, normals, i, j, size)
        sightlines = Sightlines(quads[blockers], quads[j], normals[j], n, c) if len(blockers) else None
        contour = ContourIntegral(calls, n, poly, normals[j], quads[j][0], sightlines)
        if sightlines is None:                 # nothing between: the hemicube's cells tell the visible fraction
            reach = float(weights @ (contour.at(points) * contour.seen(points)))   # 0 where they stood behind j
            if reach > 1e-12 and row[j] <= 0.0:
                continue                       # seen from where the hemicubes stood, and hidden: stays 0
            scale = row[j] / reach if reach > 1e-12 else 1.0
            if reach <= cell:
                scale = min(scale, 1.0)        # (nearly) edge-on from where they stood: a cell's reading is
                #                                rasterisation, not a fraction seen, and no fraction is over 1
            if abs(scale - 1.0) <= VISIBLE_SNAP:
                scale = 1.0                    # within what its cells can tell from wholly visible
        else:
            scale = 1.0                        # the sight lines tell it, point by point
        out[j] = scale * contour.integral(quads[i]) / area
        counters["proximity_pairs"] = counters.get("proximity_pairs", 0) + 1
        counters["proximity_evaluations"] = counters.get("proximity_evaluations", 0) + contour.evaluations
        if sightlines is not None:
            counters["proximity_occluded_pairs"] = counters.get("proximity_occluded_pairs", 0) + 1
            counters["proximity_rays"] = counters.get("proximity_rays", 0) + sightlines.rays
    return out
