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
  by 20% for a 5 × 1 floor beside a 1 × 0.2 wall);
* in between: the ratio above from a cheap quadrature of the form-factor integral itself (cos·cos/πr²
  between Gauss points of both patches, the kit's own and not H6), applied where it moves the entry by more
  than ``PROXIMITY_ERROR`` (unit squares 0.2 wide five apart: +1.4% before).
"""
from __future__ import annotations

from typing import Any

import numpy as np

from ..patches import patch_areas
from .geometry import _sub_quads, clip_polygon_to_plane, gauss_points

#: correct an entry where the kernel says the point estimate is off by more than this (relative)
PROXIMITY_ERROR = 1e-3
#: beyond this many shooter radii (gap to the receiver's bounding sphere) the point estimate is within ~0.1%
REACH = 40.0
#: graded quadrature: split a piece of the shooter while its radius exceeds this fraction of its distance to j
GRADING = 0.7
#: graded quadrature: at most this many halvings of a piece
MAX_DEPTH = 3
#: Gauss points per side on each leaf of the graded quadrature
LEAF_GAUSS = 3
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


def distance_to_polygon(point: np.ndarray, polygon: np.ndarray, normal: np.ndarray) -> float:
    """Distance from a point to a planar convex polygon (its plane's ``normal``): to the plane when the point
    projects inside, else to the nearest edge."""
    height = float((point - polygon[0]) @ normal)
    foot = point - height * normal
    edges = np.roll(polygon, -1, axis=0) - polygon
    inside = np.cross(edges, foot - polygon) @ normal
    if (inside >= -1e-12).all() or (inside <= 1e-12).all():
        return abs(height)
    t = np.clip(np.einsum("ij,ij->i", point - polygon, edges) / np.maximum((edges * edges).sum(axis=1), 1e-300), 0, 1)
    return float(np.linalg.norm(polygon + t[:, None] * edges - point, axis=1).min())


class GradedContour:
    """∫ over the shooter of H6's F(p → polygon) dA, by Gauss points on pieces graded toward the polygon."""

    def __init__(self, calls: Any, normal: np.ndarray, polygon: np.ndarray, receiver_normal: np.ndarray):
        self.calls, self.normal, self.polygon, self.receiver_normal = calls, normal, polygon, receiver_normal
        self.evaluations = 0

    def at(self, point: np.ndarray) -> float:
        self.evaluations += 1
        return float(self.calls.contour(point, self.normal, self.polygon))

    def integral(self, quad: np.ndarray) -> float:
        """The integral over a quad: first cut into near-square pieces (a 5 × 1 floor into five), then graded."""
        u = max(np.linalg.norm(quad[1] - quad[0]), np.linalg.norm(quad[2] - quad[3]))
        v = max(np.linalg.norm(quad[3] - quad[0]), np.linalg.norm(quad[2] - quad[1]))
        ku, kv = (int(min(8, max(1, round(x / max(min(u, v), 1e-300))))) for x in (u, v))
        return sum(self._piece(piece, 0) for piece in _grid(quad, ku, kv))

    def _piece(self, quad: np.ndarray, depth: int) -> float:
        centre = quad.mean(axis=0)
        radius = float(np.linalg.norm(quad - centre, axis=1).max())
        if depth < MAX_DEPTH and radius > GRADING * distance_to_polygon(centre, self.polygon, self.receiver_normal):
            return sum(self._piece(child, depth + 1) for child in _sub_quads(quad, 2))
        points, weights = gauss_points(quad, LEAF_GAUSS)
        return float(sum(w * self.at(p) for p, w in zip(points, weights)))


def _grid(quad: np.ndarray, ku: int, kv: int) -> np.ndarray:
    """The ku × kv bilinear cells of a quad (ku along its first edge)."""
    s, t = np.linspace(0.0, 1.0, ku + 1), np.linspace(0.0, 1.0, kv + 1)
    S, T = (g[:, :, None] for g in np.meshgrid(s, t, indexing="ij"))
    a, b, c, d = quad
    grid = (1 - S) * (1 - T) * a + S * (1 - T) * b + S * T * c + (1 - S) * T * d
    return np.stack([grid[:-1, :-1], grid[1:, :-1], grid[1:, 1:], grid[:-1, 1:]], axis=2).reshape(-1, 4, 3)


def fix_row(calls: Any, quads: np.ndarray, normals: np.ndarray, centers: np.ndarray, radii: np.ndarray, i: int,
            row: np.ndarray, stands: tuple[np.ndarray, np.ndarray], proximity_distance: float,
            counters: dict[str, int]) -> np.ndarray:
    """Row ``row`` of patch i, measured from the points ``stands`` = (points, weights summing to 1), with each
    entry corrected as the module says. Counts ``proximity_pairs`` (H6), ``proximity_kernel_pairs`` and
    ``proximity_evaluations`` (H6 calls)."""
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
        out[J[moved]] = row[J[moved]] * ratio[moved]
        counters["proximity_kernel_pairs"] = counters.get("proximity_kernel_pairs", 0) + int(moved.sum())
    area = float(patch_areas(quads[i:i + 1])[0])
    for j in np.flatnonzero(close):
        poly = clip_polygon_to_plane(quads[j], c, n)
        if len(poly) < 3:
            continue
        contour = GradedContour(calls, n, poly, normals[j])
        measured = float(sum(w * contour.at(p) for p, w in zip(points, weights)))
        if measured > 1e-12:
            if row[j] <= 0.0:
                continue                       # seen from where the hemicubes stood, and hidden: stays 0
            scale = row[j] / measured          # the hemicube's visibility, carried over
            if abs(scale - 1.0) <= VISIBLE_SNAP:
                scale = 1.0                    # within what its cells can tell from wholly visible
        else:
            scale = 1.0                        # edge-on from the hemicubes' points: they cannot tell; assume unoccluded
        out[j] = scale * contour.integral(quads[i]) / area
        counters["proximity_pairs"] = counters.get("proximity_pairs", 0) + 1
        counters["proximity_evaluations"] = counters.get("proximity_evaluations", 0) + contour.evaluations
    return out
