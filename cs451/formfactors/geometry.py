"""Where hemicubes stand and look: up vectors, near and far planes, sub-quads, clipping and quadrature points."""
from __future__ import annotations

import functools

import numpy as np

from ..patches import as_quads, patch_centers, patch_normals
from .calls import StageCalls


def default_up(normal: np.ndarray) -> np.ndarray:
    """A unit vector perpendicular to ``normal``: the cross product with the least aligned coordinate axis."""
    axis = np.zeros(3)
    axis[int(np.argmin(np.abs(normal)))] = 1.0
    u = np.cross(normal, axis)
    return u / np.linalg.norm(u)


def hemicube_up(normal: np.ndarray, index: int, rotate: bool, seed: int) -> np.ndarray:
    """The hemicube's up vector for patch ``index``: seeded per patch, so a row never depends on the batch it was in."""
    u = default_up(normal)
    if not rotate:
        return u
    angle = rotation_angle(int(seed), int(index))
    return np.cos(angle) * u + np.sin(angle) * np.cross(normal, u)


@functools.lru_cache(maxsize=1 << 16)
def rotation_angle(seed: int, index: int) -> float:
    """Hemicube ``index``'s seeded turn about its normal (a generator made per call costs 0.1 ms; a patch that is
    looked at again, blind or split, asks again)."""
    return float(np.random.default_rng([seed, index]).uniform(0.0, 2 * np.pi))


def default_near_far(quads: np.ndarray) -> tuple[float, float]:
    """Near = 1e-3 of the scene's diagonal, far = 2 diagonals.

    Geometry closer than ``near`` is clipped away (the near-plane error), so near wants to be
    small; but a 24-bit depth buffer resolves depths about z²/(near·2²⁴) apart, so near must not
    be too small either. At 1e-5 of the diagonal, the Cornell box's light, 0.1 mm below the
    ceiling, lost the depth test to the ceiling behind it from every floor patch (F to the
    light came out 0). At 1e-3, surfaces 0.06 mm apart a diagonal away are still told apart.
    """
    diag = float(np.linalg.norm(np.ptp(quads.reshape(-1, 3), axis=0)))
    return 1e-3 * diag, 2.0 * diag


def hemicube_inputs(quads: np.ndarray, calls: StageCalls, patch: int, rotate: bool = False, seed: int = 0,
                    near: float | None = None) -> tuple[np.ndarray, np.ndarray, float, float]:
    """The views and projections of patch ``patch``'s hemicube as the stage computes them (H2, H3)."""
    q = as_quads(quads)
    n = patch_normals(q)[patch]
    c = patch_centers(q)[patch]
    d_near, far = default_near_far(q)
    near = d_near if near is None else near
    views = calls.views(c, n, hemicube_up(n, patch, rotate, seed))
    return views, calls.projections(near, far), near, far


def bilinear(quad: np.ndarray, st: np.ndarray) -> np.ndarray:
    """Points (..., 3) at bilinear coordinates st (..., 2) of quad (4, 3): corner 0 at (0, 0), 1 at (1, 0), 2 at (1, 1),
    3 at (0, 1), as stage 4's R1 places its patches' corners."""
    s, t = st[..., :1], st[..., 1:]
    return (1 - s) * (1 - t) * quad[0] + s * (1 - t) * quad[1] + s * t * quad[2] + (1 - s) * t * quad[3]


def _sub_quads(quad: np.ndarray, k: int) -> np.ndarray:
    """The k × k bilinear cells of one quad, (k², 4, 3): where a split shooter's hemicubes stand."""
    t = np.linspace(0.0, 1.0, k + 1)
    grid = bilinear(quad, np.stack(np.meshgrid(t, t, indexing="ij"), axis=-1))                # (k+1, k+1, 3)
    return np.stack([grid[:-1, :-1], grid[1:, :-1], grid[1:, 1:], grid[:-1, 1:]], axis=2).reshape(-1, 4, 3)


def clip_polygon_to_plane(polygon: np.ndarray, point: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """The part of a convex polygon (m, 3) with (x - point)·normal >= 0 (Sutherland-Hodgman, one plane)."""
    d = (polygon - point) @ normal
    out = []
    m = len(polygon)
    for k in range(m):
        a, b, da, db = polygon[k], polygon[(k + 1) % m], d[k], d[(k + 1) % m]
        if da >= 0:
            out.append(a)
        if (da >= 0) != (db >= 0):
            t = da / (da - db)
            out.append(a + t * (b - a))
    return np.array(out).reshape(-1, 3)


def gauss_points(quad: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre points (k², 3) on a planar quad's bilinear map and their area weights (summing to its area)."""
    x, w = np.polynomial.legendre.leggauss(k)
    s, ws = 0.5 * (x + 1), 0.5 * w
    S, T = np.meshgrid(s, s, indexing="ij")
    W = np.outer(ws, ws)
    a, b, c, d = quad
    S, T, W = S.ravel()[:, None], T.ravel()[:, None], W.ravel()
    p = (1 - S) * (1 - T) * a + S * (1 - T) * b + S * T * c + (1 - S) * T * d
    ds = (1 - T) * (b - a) + T * (c - d)
    dt = (1 - S) * (d - a) + S * (c - b)
    jac = np.linalg.norm(np.cross(ds, dt), axis=1)
    return p, W * jac
