"""Independent truths for stage 4, computed on the grader's side only; never shipped to students.

Nothing here comes from reference/ or from the hemicube: the white furnace's
closed form B = E/(1 − ρ); exact form factors of a cube (Howell's catalog,
C-11 parallel squares and C-14 perpendicular squares sharing an edge); form
factors of unoccluded patches by Lambert's contour formula integrated with
Gauss-Legendre points; progressive refinement worked by hand (scalar loops,
one channel at a time, no heap); the direct solve; vertex colours by brute force.
"""
from __future__ import annotations

import math

import numpy as np


# --- closed forms -----------------------------------------------------------------

def furnace(emission: float, albedo: float) -> float:
    """Radiosity of every patch of a closed enclosure of uniform albedo ρ and emission E: E / (1 − ρ)."""
    return emission / (1.0 - albedo)


def parallel_rectangles(a: float, b: float, c: float) -> float:
    """Howell C-11: directly opposed parallel rectangles a × b at distance c."""
    X, Y = a / c, b / c
    return 2.0 / (math.pi * X * Y) * (
        math.log(math.sqrt((1 + X * X) * (1 + Y * Y) / (1 + X * X + Y * Y)))
        + X * math.sqrt(1 + Y * Y) * math.atan(X / math.sqrt(1 + Y * Y))
        + Y * math.sqrt(1 + X * X) * math.atan(Y / math.sqrt(1 + X * X))
        - X * math.atan(X) - Y * math.atan(Y))


def perpendicular_rectangles(l: float, w: float, h: float) -> float:
    """Howell C-14: from rectangle w × l to rectangle h × l, perpendicular and sharing the edge of length l."""
    H, W = h / l, w / l
    A = (1 + W * W) * (1 + H * H) / (1 + W * W + H * H)
    B = (W * W * (1 + W * W + H * H) / ((1 + W * W) * (W * W + H * H))) ** (W * W)
    C = (H * H * (1 + H * H + W * W) / ((1 + H * H) * (H * H + W * W))) ** (H * H)
    return 1.0 / (math.pi * W) * (W * math.atan(1 / W) + H * math.atan(1 / H)
                                  - math.sqrt(H * H + W * W) * math.atan(1 / math.sqrt(H * H + W * W))
                                  + 0.25 * math.log(A * B * C))


def cube_formfactors(normals: np.ndarray) -> np.ndarray:
    """Exact 6 × 6 form factors between the faces of a cube, given each face's unit normal."""
    n = np.asarray(normals, dtype=np.float64)
    opposite = parallel_rectangles(1.0, 1.0, 1.0)
    adjacent = perpendicular_rectangles(1.0, 1.0, 1.0)
    dots = n @ n.T
    F = np.where(dots < -0.5, opposite, adjacent)
    np.fill_diagonal(F, 0.0)
    return F


# --- Lambert's contour formula, integrated over the emitting patch --------------------

def point_polygon(points: np.ndarray, normals: np.ndarray, quad: np.ndarray) -> np.ndarray:
    """Form factor from differential areas (points, normals: (k, 3)) to a polygon (4, 3), no occlusion.

    F = |Σ_e Θ_e (n · Γ_e)| / 2π (Lambert), Γ_e the unit normal of the triangle (x, v_e, v_e+1),
    Θ_e its angle at x; valid when the whole polygon lies in front of every point.
    """
    R = quad[None, :, :] - points[:, None, :]                        # (k, 4, 3)
    R1 = np.roll(R, -1, axis=1)
    cross = np.cross(R, R1)
    norm = np.linalg.norm(cross, axis=2)
    dot = (R * R1).sum(axis=2)
    theta = np.arctan2(norm, dot)
    gamma = cross / np.where(norm > 0, norm, 1.0)[..., None]
    total = (theta * (gamma * normals[:, None, :]).sum(axis=2)).sum(axis=1)
    return np.abs(total) / (2 * math.pi)


def contour_formfactors(quads: np.ndarray, order: int = 6) -> np.ndarray:
    """F_ij for patches of a convex enclosure (nothing occludes anything): Lambert's formula averaged over
    ``order``² Gauss-Legendre points of patch i, weighted by area. Each point's row sums to exactly 1 in a
    closed convex enclosure, so the rows do too, whatever the quadrature error of each entry."""
    q = np.asarray(quads, dtype=np.float64)
    g, w = np.polynomial.legendre.leggauss(order)
    u, wu = (g + 1) / 2, w / 2
    U, V = np.meshgrid(u, u, indexing="ij")
    W = np.outer(wu, wu)
    F = np.zeros((len(q), len(q)))
    for i, (p0, p1, p2, p3) in enumerate(q):
        s, t = U.ravel()[:, None], V.ravel()[:, None]
        pts = (1 - s) * (1 - t) * p0 + s * (1 - t) * p1 + s * t * p2 + (1 - s) * t * p3
        du = (1 - t) * (p1 - p0) + t * (p2 - p3)
        dv = (1 - s) * (p3 - p0) + s * (p2 - p1)
        jac = np.linalg.norm(np.cross(du, dv), axis=1) * W.ravel()
        normal = np.cross(p2 - p0, p3 - p1)
        normal /= np.linalg.norm(normal)
        normals = np.broadcast_to(normal, pts.shape)
        for j in range(len(q)):
            if j != i:
                F[i, j] = (point_polygon(pts, normals, q[j]) * jac).sum() / jac.sum()
    return F


# --- the solvers, by hand -------------------------------------------------------------------

def direct(F: np.ndarray, reflectance: np.ndarray, emission: np.ndarray) -> np.ndarray:
    """(I − ρF)B = E solved channel by channel."""
    F, rho, E = (np.asarray(x, dtype=np.float64) for x in (F, reflectance, emission))
    return np.column_stack([np.linalg.solve(np.eye(len(F)) - rho[:, c:c + 1] * F, E[:, c]) for c in range(E.shape[1])])


def shoot_by_hand(i: int, F, areas, reflectance, radiosity, unshot) -> tuple[list, list]:
    """One shot, written out with scalar loops: ΔRad = ρ_j ΔB_i F_ij A_i / A_j."""
    B = [list(map(float, r)) for r in radiosity]
    dB = [list(map(float, r)) for r in unshot]
    shot = list(dB[i])
    for j in range(len(areas)):
        for c in range(3):
            d = reflectance[j][c] * shot[c] * F[i][j] * areas[i] / areas[j]
            B[j][c] += d
            dB[j][c] += d
    dB[i] = [0.0, 0.0, 0.0]
    return B, dB


def overshoot_by_hand(i: int, F, areas, reflectance, B: list, dB: list, overshoot: float) -> tuple[list, list]:
    """One shot of ω·ΔB_i, leaving (1 − ω)·ΔB_i unshot at patch i (ω = 1: a plain shot)."""
    left = [(1 - overshoot) * x for x in dB[i]]
    dB[i] = [overshoot * x for x in dB[i]]
    B, dB = shoot_by_hand(i, F, areas, reflectance, B, dB)
    dB[i] = left
    return B, dB


def progressive_by_hand(F, areas, reflectance, emission, tolerance: float, max_shots: int,
                        overshoot: float = 1.0, stop_within_sweeps: bool = True) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """The notes' shooting loop (§2.5) with a sort for each sweep's order (keys at its start; ties to the lower index).
    ``stop_within_sweeps=False`` is a mistake the fresh cases must be able to tell: the tolerance checked only as a
    sweep starts, as if the keys stayed frozen through it."""
    B = [list(map(float, r)) for r in emission]
    dB = [list(map(float, r)) for r in emission]
    emitted = sum(sum(e) * a for e, a in zip(emission, areas))
    order: list[int] = []

    def keys() -> list[float]:
        return [sum(abs(x) for x in dB[j]) * areas[j] for j in range(len(areas))]

    while True:
        start = keys()
        sweep = sorted((j for j in range(len(areas)) if start[j] > 0), key=lambda j: (-start[j], j))
        if not sweep:
            break
        for i in sweep:
            checked = stop_within_sweeps or i == sweep[0]
            if len(order) >= max_shots or (checked and sum(keys()) <= tolerance * emitted):
                return np.array(B), np.array(dB), order
            B, dB = overshoot_by_hand(i, F, areas, reflectance, B, dB, overshoot)
            order.append(i)
    return np.array(B), np.array(dB), order


def largest_first_by_hand(F, areas, reflectance, emission, tolerance: float, max_shots: int,
                          overshoot: float = 1.0) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """The 1988 paper's loop: before every shot, the stopping rule, then the patch of the largest key now (a linear
    search, ties to the lower index)."""
    B = [list(map(float, r)) for r in emission]
    dB = [list(map(float, r)) for r in emission]
    emitted = sum(sum(e) * a for e, a in zip(emission, areas))
    order: list[int] = []
    while len(order) < max_shots:
        keys = [sum(abs(x) for x in dB[j]) * areas[j] for j in range(len(areas))]
        i = max(range(len(keys)), key=lambda j: (keys[j], -j))
        if sum(keys) <= tolerance * emitted or keys[i] <= 0:
            break
        B, dB = overshoot_by_hand(i, F, areas, reflectance, B, dB, overshoot)
        order.append(i)
    return np.array(B), np.array(dB), order


def ambient_by_hand(areas, reflectance, unshot) -> np.ndarray:
    total = sum(areas)
    out = []
    for c in range(3):
        rho_avg = sum(r[c] * a for r, a in zip(reflectance, areas)) / total
        out.append(sum(u[c] * a for u, a in zip(unshot, areas)) / total / (1 - rho_avg))
    return np.array(out)


def corner_colors_by_hand(quads, parent, radiosity) -> np.ndarray:
    """(m, 4, 3): for each patch corner, the mean radiosity of the patches of the same polygon touching that point."""
    q = np.asarray(quads, dtype=np.float64)
    scale = float(np.ptp(q.reshape(-1, 3), axis=0).max())
    out = np.zeros(q.shape[:2] + (3,))
    for p in range(len(q)):
        for c in range(4):
            touching = [k for k in range(len(q)) if parent[k] == parent[p]
                        and np.min(np.abs(q[k] - q[p, c]).max(axis=1)) <= 1e-7 * scale]
            out[p, c] = np.mean([radiosity[k] for k in touching], axis=0)
    return out


def subdivide_by_hand(quads, max_edge: float) -> tuple[np.ndarray, np.ndarray]:
    """The handout's grid, cell by cell: nu × nv cells per quad, corners by bilinear interpolation."""
    out, parent = [], []
    for k, quad in enumerate(np.asarray(quads, dtype=np.float64)):
        p0, p1, p2, p3 = quad
        nu = nv = 1
        if max_edge > 0:
            nu = max(1, math.ceil(max(np.linalg.norm(p1 - p0), np.linalg.norm(p2 - p3)) / max_edge))
            nv = max(1, math.ceil(max(np.linalg.norm(p3 - p0), np.linalg.norm(p2 - p1)) / max_edge))

        def at(a: int, b: int) -> np.ndarray:
            u, v = a / nu, b / nv
            return (1 - u) * (1 - v) * p0 + u * (1 - v) * p1 + u * v * p2 + (1 - u) * v * p3

        for b in range(nv):
            for a in range(nu):
                out.append([at(a, b), at(a + 1, b), at(a + 1, b + 1), at(a, b + 1)])
                parent.append(k)
    return np.array(out), np.array(parent)


# --- truths of tests' parameters ------------------------------------------------------------

def subdivision(p: dict) -> dict[str, np.ndarray]:
    patches, parent = subdivide_by_hand(p["quads"], p["max_edge"])
    return {"patches": patches.reshape(-1, 4, 3), "parent": parent}


def shot(p: dict) -> dict[str, np.ndarray]:
    B, dB = shoot_by_hand(p["i"], p["F"], p["areas"], p["reflectance"], p["radiosity"], p["unshot"])
    return {"radiosity": np.array(B), "unshot": np.array(dB)}


def shooting_loop(p: dict) -> dict[str, np.ndarray]:
    B, dB, order = progressive_by_hand(p["F"], p["areas"], p["reflectance"], p["emission"], p["tolerance"],
                                       p["max_shots"], p.get("overshoot", 1.0))
    return {"radiosity": B, "unshot": dB, "order": np.array(order, dtype=np.int64)}


def largest_first(p: dict) -> dict[str, np.ndarray]:
    B, dB, order = largest_first_by_hand(p["F"], p["areas"], p["reflectance"], p["emission"], p["tolerance"],
                                         p["max_shots"], p.get("overshoot", 1.0))
    return {"radiosity": B, "unshot": dB, "order": np.array(order, dtype=np.int64)}


def resolved(p: dict) -> dict[str, np.ndarray]:
    """R6: R3's loop worked by hand, and the rows it must compute: each shooter not in ``known_rows``, once, in the
    order of its first shot."""
    out = shooting_loop(p)
    known, asked = {int(i) for i in p["known_rows"]}, []
    for i in out["order"].tolist():
        if i not in known and i not in asked:
            asked.append(i)
    return {**out, "rows_asked": np.array(asked, dtype=np.int64)}


def stops_within_a_sweep(p: dict) -> bool:
    """Whether the tolerance stops this loop in the middle of a sweep (so a loop checking it only as sweeps start,
    with frozen keys, shoots more)."""
    frozen = progressive_by_hand(p["F"], p["areas"], p["reflectance"], p["emission"], p["tolerance"], p["max_shots"],
                                 p.get("overshoot", 1.0), stop_within_sweeps=False)[2]
    return frozen != shooting_loop(p)["order"].tolist()


def ambient(p: dict) -> np.ndarray:
    return ambient_by_hand(p["areas"], p["reflectance"], p["unshot"])


def vertex_colours(p: dict) -> dict[str, np.ndarray]:
    """Each corner's colour, and how many vertices there are: one per distinct point per polygon."""
    q = np.asarray(p["quads"])
    keys = {(int(par), *np.round(c / 1e-6).astype(int).tolist()) for quad, par in zip(q, p["parent"]) for c in quad}
    return {"corner_colors": corner_colors_by_hand(p["quads"], p["parent"], np.asarray(p["radiosity"])),
            "vertex_count": np.array(len(keys))}
