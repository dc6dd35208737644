"""The proximity fix's integral over the shooter: ∫ F(p → receiver) dA by Gauss points on pieces graded toward
the receiver, with each point's view of the receiver cut by what stands between.

F(p → j) is H6, the stage-3 implementation's exact point-to-polygon form factor. It changes on the scale of
p's distance to j, so the shooter is cut into pieces no wider than ``GRADING`` times their distance to j
(a fixed 5 × 5 rule missed a 5 × 1 floor beside a 1 × 0.2 wall by 20%). Where something may stand between
(:class:`~.visibility.Sightlines`), each point's F is scaled by the fraction of j it sees. Visibility jumps
where a shadow's edge crosses the shooter, on a scale of its own: a piece whose points disagree is refined
for visibility alone (rays are cheap, H6 is the student's code): H6 keeps its 3 × 3 values on the piece,
interpolated, and the sight lines are followed down ``VISIBILITY_LEVELS`` halvings. A point behind j's plane
sees its back, which receives nothing (H4), and counts 0.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from .geometry import _sub_quads
from .visibility import Sightlines

#: split a piece of the shooter while its radius exceeds this fraction of its distance to the receiver
GRADING = 0.7
#: at most this many halvings of a piece for the grading
MAX_DEPTH = 3
#: Gauss points per side on each piece
LEAF_GAUSS = 3
#: refine a piece for visibility where its points' visible fractions differ by more than this ...
VISIBILITY_SPLIT = 0.05
#: ... and where that difference could move the integral by more than this fraction of it ...
VISIBILITY_TOLERANCE = 5e-3
#: ... by at most this many further halvings (a shadow's edge followed to 1/32 of a piece)
VISIBILITY_LEVELS = 4

_X, _W = np.polynomial.legendre.leggauss(LEAF_GAUSS)
NODES, NODE_WEIGHTS = 0.5 * (_X + 1), 0.5 * _W


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


def grid(quad: np.ndarray, ku: int, kv: int) -> np.ndarray:
    """The ku × kv bilinear cells of a quad (ku along its first edge)."""
    s, t = np.linspace(0.0, 1.0, ku + 1), np.linspace(0.0, 1.0, kv + 1)
    S, T = (g[:, :, None] for g in np.meshgrid(s, t, indexing="ij"))
    a, b, c, d = quad
    cells = (1 - S) * (1 - T) * a + S * (1 - T) * b + S * T * c + (1 - S) * T * d
    return np.stack([cells[:-1, :-1], cells[1:, :-1], cells[1:, 1:], cells[:-1, 1:]], axis=2).reshape(-1, 4, 3)


def _bilinear(quads: np.ndarray, s: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points (M, P, 3) at parameters (M, P) of quads (M, 4, 3), and the area Jacobian there (M, P)."""
    a, b, c, d = (quads[:, m][:, None, :] for m in range(4))
    S, T = s[..., None], t[..., None]
    p = (1 - S) * (1 - T) * a + S * (1 - T) * b + S * T * c + (1 - S) * T * d
    ds = (1 - T) * (b - a) + T * (c - d)
    dt = (1 - S) * (d - a) + S * (c - b)
    return p, np.linalg.norm(np.cross(ds, dt), axis=2)


def _lagrange(x: np.ndarray) -> np.ndarray:
    """(…, k): the Lagrange basis on the Gauss nodes at parameters x (…)."""
    out = np.ones(x.shape + (LEAF_GAUSS,))
    for a in range(LEAF_GAUSS):
        for b in range(LEAF_GAUSS):
            if a != b:
                out[..., a] *= (x - NODES[b]) / (NODES[a] - NODES[b])
    return out


def _rect_nodes(s0: np.ndarray, t0: np.ndarray, size: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Gauss nodes (M, k²) in the parameter squares [s0, s0 + size] × [t0, t0 + size], and their weights (M, k²)."""
    S, T = np.meshgrid(NODES, NODES, indexing="ij")
    W = np.outer(NODE_WEIGHTS, NODE_WEIGHTS).ravel()
    return (s0[:, None] + size[:, None] * S.ravel(), t0[:, None] + size[:, None] * T.ravel(),
            (size * size)[:, None] * W)


class ContourIntegral:
    """∫ over a shooter (normal ``normal``) of F(p → polygon) · (the fraction of it p sees) dA, as the module says."""

    def __init__(self, calls: Any, normal: np.ndarray, polygon: np.ndarray, receiver_normal: np.ndarray,
                 receiver_point: np.ndarray, sightlines: Sightlines | None = None):
        self.calls, self.normal, self.polygon, self.receiver_normal = calls, normal, polygon, receiver_normal
        self.receiver_point, self.sightlines = receiver_point, sightlines
        self.evaluations = 0

    def at(self, points: np.ndarray) -> np.ndarray:
        """H6 at each point (P, 3)."""
        self.evaluations += len(points)
        return np.array([float(self.calls.contour(p, self.normal, self.polygon)) for p in points])

    def pieces(self, quad: np.ndarray) -> np.ndarray:
        """The graded pieces (L, 4, 3): first near-square cells (a 5 × 1 floor into five), then halved toward j."""
        u = max(np.linalg.norm(quad[1] - quad[0]), np.linalg.norm(quad[2] - quad[3]))
        v = max(np.linalg.norm(quad[3] - quad[0]), np.linalg.norm(quad[2] - quad[1]))
        ku, kv = (int(min(8, max(1, round(x / max(min(u, v), 1e-300))))) for x in (u, v))
        out: list[np.ndarray] = []

        def grade(piece: np.ndarray, depth: int) -> None:
            centre = piece.mean(axis=0)
            radius = float(np.linalg.norm(piece - centre, axis=1).max())
            if depth < MAX_DEPTH and radius > GRADING * distance_to_polygon(centre, self.polygon, self.receiver_normal):
                for child in _sub_quads(piece, 2):
                    grade(child, depth + 1)
            else:
                out.append(piece)

        for cell in grid(quad, ku, kv):
            grade(cell, 0)
        return np.stack(out)

    def seen(self, points: np.ndarray) -> np.ndarray:
        """(…,) the fraction of the receiver each point (…, 3) sees: 0 behind its plane, else 1 or the sight lines'."""
        flat = points.reshape(-1, 3)
        front = (flat - self.receiver_point) @ self.receiver_normal > 0
        out = front.astype(np.float64)
        if self.sightlines is not None and front.any():
            out[front] = self.sightlines.fraction(flat[front])
        return out.reshape(points.shape[:-1])

    def integral(self, quad: np.ndarray) -> float:
        leaves = self.pieces(quad)
        L = len(leaves)
        s, t, w = _rect_nodes(np.zeros(L), np.zeros(L), np.ones(L))
        points, jac = _bilinear(leaves, s, t)
        weights = w * jac
        seen = self.seen(points)                                                     # (L, k²)
        partial = np.ptp(seen, axis=1) > VISIBILITY_SPLIT if self.sightlines is not None else np.zeros(L, bool)
        total = 0.0
        whole = ~partial[:, None] & (seen > 0)
        if whole.any():
            total += float((weights[whole] * seen[whole] * self.at(points[whole])).sum())
        if partial.any():
            front = (points[partial] - self.receiver_point) @ self.receiver_normal > 0
            h = np.zeros(front.shape)
            h[front] = self.at(points[partial][front])
            rough = total + float((weights[partial] * seen[partial] * h).sum())
            total += self._shadowed(leaves[partial], h, VISIBILITY_TOLERANCE * rough)
        return total

    def _shadowed(self, leaves: np.ndarray, h: np.ndarray, tolerance: float) -> float:
        """∫ over pieces of H6 (interpolated from its values h (M, k²) at their Gauss nodes) times the visible
        fraction, refined breadth-first where the fraction changes."""
        M = len(leaves)
        which, s0, t0, size = np.arange(M), np.zeros(M), np.zeros(M), np.ones(M)
        total = 0.0
        for level in range(VISIBILITY_LEVELS + 1):
            s, t, w = _rect_nodes(s0, t0, size)
            points, jac = _bilinear(leaves[which], s, t)
            seen = self.seen(points)
            k = LEAF_GAUSS
            value = np.maximum(np.einsum("mpa,mab,mpb->mp", _lagrange(s), h[which].reshape(-1, k, k), _lagrange(t)), 0.0)
            area = (w * jac).sum(axis=1)
            change = np.ptp(seen, axis=1)
            split = (change > VISIBILITY_SPLIT) & (change * value.max(axis=1) * area > tolerance)
            if level == VISIBILITY_LEVELS:
                split[:] = False
            keep = ~split
            total += float((w[keep] * jac[keep] * seen[keep] * value[keep]).sum())
            if not split.any():
                break
            half = size[split] / 2
            which = np.repeat(which[split], 4)
            s0 = np.repeat(s0[split], 4) + np.tile([0.0, 1.0, 0.0, 1.0], int(split.sum())) * np.repeat(half, 4)
            t0 = np.repeat(t0[split], 4) + np.tile([0.0, 0.0, 1.0, 1.0], int(split.sum())) * np.repeat(half, 4)
            size = np.repeat(half, 4)
        return total
