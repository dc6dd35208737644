"""A ray tree, the one way the kit builds it: the rays a W11 cast for a few camera rays, recorded through its W5
(closest hit) and W7 (shadow rays) queries, each joined to the hit it leaves from. The demo draws one pixel's
tree over the picture, through a pinhole fitted to the submission's own camera rays; the deck's figures
(``figure_rays.py``) draw the reference's.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np



#: Colours of the ray tree, by kind of ray, and of shadow rays by how much light they let through.
RAY_COLOURS = {"camera": (255, 255, 255), "reflection": (0, 225, 255), "refraction": (255, 80, 255),
               "ray": (210, 210, 210)}
SHADOW_COLOURS = {"lit": (80, 255, 80), "dimmed": (255, 170, 30), "blocked": (255, 40, 40)}
LEGEND = "tree: cyan reflected | magenta refracted | shadow rays: green lit, orange through glass, red blocked"


@dataclass
class TracedRay:
    kind: str                      # camera, reflection, refraction, shadow; "ray" where no parent was found
    start: np.ndarray
    direction: np.ndarray          # unit; a shadow ray's towards its light sample
    end: np.ndarray                # the hit, the light sample, or ``reach`` along a miss
    hit: bool
    parent: int | None             # the ray whose hit this one leaves from
    depth: int                     # the camera ray's is 0
    prim: int = -1                 # the primitive hit (-1: none)
    normal: np.ndarray | None = None
    through: np.ndarray | None = None   # a shadow ray's: the RGB factor of the light that gets through


#: A spawned ray starts within this of its parent's hit, relative to the point's size (spawn moves it by 1e-9).
JOIN = 1e-3


def build_tree(closest_calls: list[tuple], shadow_calls: list[tuple], reach: float) -> list[TracedRay]:
    """The rays of W5 calls ``(origins, directions, t, prim, normals)`` and W7 calls ``(origins, targets, through)``,
    in the order they were made. The first W5 call casts the camera rays; every later ray leaves from the nearest
    earlier hit (whatever order a W11 casts in: bounce by bounce, or depth first), as a reflection when it leaves
    on the side its parent came from and a refraction otherwise, one level deeper; a ray with no hit near its
    origin is drawn as a "ray" of its own. Misses are drawn ``reach`` long."""
    rays: list[TracedRay] = []
    for call, (o, d, t, prim, normals) in enumerate(closest_calls):
        hits = [i for i, r in enumerate(rays) if r.hit]
        for k in range(len(o)):
            parent = _parent(rays, hits, o[k]) if call else None
            kind, depth = ("camera", 0) if call == 0 else ("ray", call)
            if parent is not None:
                p = rays[parent]
                kind = "reflection" if (d[k] @ p.normal) * (p.direction @ p.normal) < 0 else "refraction"
                depth = p.depth + 1
            hit = bool(np.isfinite(t[k]) and prim[k] >= 0)
            end = o[k] + (t[k] if hit else reach) * d[k]
            rays.append(TracedRay(kind, o[k], d[k], end, hit, parent, depth, int(prim[k]) if hit else -1, normals[k]))
    hits = [i for i, r in enumerate(rays) if r.hit]
    for o, targets, through in shadow_calls:
        for k in range(len(o)):
            parent = _parent(rays, hits, o[k])
            target = np.asarray(targets[k], dtype=np.float64)
            seg = target - o[k]
            rays.append(TracedRay("shadow", o[k], seg / max(float(np.linalg.norm(seg)), 1e-300), target, False, parent,
                                  1 if parent is None else rays[parent].depth + 1,
                                  through=np.asarray(through[k], dtype=np.float64)))
    return rays


def _parent(rays: list[TracedRay], candidates: list[int], origin: np.ndarray) -> int | None:
    if not candidates:
        return None
    dist = [float(np.linalg.norm(rays[i].end - origin)) for i in candidates]
    best = int(np.argmin(dist))
    return candidates[best] if dist[best] <= JOIN * (1.0 + np.abs(origin).max()) else None


@dataclass
class RayTree:
    """One pixel's rays as the submission's W11 cast them: its W5 queries (rays) and W7 queries (shadow rays)."""
    pixel: tuple[int, int]
    rays: list[TracedRay]
    shadows: list[tuple[np.ndarray, np.ndarray, float]]      # origin, light sample, light let through (max RGB)
    counters: dict[str, int]                                 # W11's own counters for this one camera ray

    def count(self, kind: str) -> int:
        """How many of the tree's rays are of ``kind`` (camera, reflection, refraction or ray), for the caption."""
        return sum(r.kind == kind for r in self.rays)

    def shadow_state(self, passed: float) -> str:
        """A shadow ray by the light it lets through (max RGB): ``blocked`` at none, ``lit`` at all, ``dimmed``
        between (its colour in the drawing)."""
        return "blocked" if passed <= 1e-9 else ("lit" if passed >= 1 - 1e-9 else "dimmed")

    def summary(self) -> list[str]:
        """Two caption lines: the tree as drawn, and what the submission's W11 counted for this camera ray."""
        blocked = sum(self.shadow_state(p) == "blocked" for _, _, p in self.shadows)
        hits = sum(r.hit for r in self.rays)
        c = self.counters
        return [f"pixel ({self.pixel[0]}, {self.pixel[1]}): {self.count('reflection')} reflected, "
                f"{self.count('refraction')} refracted, {len(self.shadows)} shadow rays ({blocked} blocked), {hits} hits",
                f"W11's counters for it: {c.get('camera', 0)} camera, {c.get('reflection', 0)} reflection, "
                f"{c.get('transmission', 0)} transmission, {c.get('shadow', 0)} shadow"]


class Pinhole:
    """Where world points land in the image: a homography of directions fitted to the submission's camera rays."""

    def __init__(self, origins: np.ndarray, directions: np.ndarray, width: int, height: int, k: int):
        cols, rows = (np.unique(np.linspace(0, n * k - 1, 7).round().astype(int)) for n in (width, height))
        idx = (rows[:, None] * width * k + cols[None, :]).ravel()
        d = directions[idx]
        u = np.tile((cols + 0.5) / k / width, len(rows))             # in image widths and heights: well conditioned
        v = np.repeat((rows + 0.5) / k / height, len(cols))
        zero = np.zeros_like(d)
        a = np.concatenate([np.hstack([d, zero, -u[:, None] * d]), np.hstack([zero, d, -v[:, None] * d])])
        m = np.linalg.svd(a)[2][-1].reshape(3, 3)
        if (m @ d[0])[2] < 0:
            m = -m
        self.m, self.width, self.height = m, width, height
        self.eye = origins.mean(axis=0)
        q = d @ m.T
        with np.errstate(divide="ignore", invalid="ignore"):
            err = np.hypot(q[:, 0] / q[:, 2] - u, q[:, 1] / q[:, 2] - v) * max(width, height)
        spread = float(np.ptp(origins, axis=0).max())
        #: whether the camera rays are a pinhole's (one eye, directions through a plane): else no tree is drawn
        self.ok = bool(np.all(q[:, 2] > 0) and np.nanmax(err) < 0.05 and spread <= 1e-9 * (1 + np.abs(self.eye).max()))

    def clip_matrix(self) -> np.ndarray:
        """The pinhole as a 4 × 4 from world points to clip space, as a GL camera's projection · view: x and y over
        [-1, 1] across the image (y up), w the depth along the view axis."""
        m = self.m / np.linalg.norm(self.m[2])
        rows = np.stack([2.0 * m[0] - m[2], m[2] - 2.0 * m[1], m[2], m[2]])
        return np.c_[rows, -rows @ self.eye]

    def segment(self, a: np.ndarray, b: np.ndarray) -> tuple[tuple[float, float], tuple[float, float]] | None:
        """The part of segment a-b in front of the eye, in image pixels (x right, y down), clipped near the image."""
        qa, qb = self.m @ (a - self.eye), self.m @ (b - self.eye)
        eps = 1e-9 * max(np.abs(qa).max(), np.abs(qb).max(), 1e-300)
        if qa[2] < eps and qb[2] < eps:
            return None
        if qa[2] < eps:
            qa = qa + (eps - qa[2]) / (qb[2] - qa[2]) * (qb - qa)
        elif qb[2] < eps:
            qb = qb + (eps - qb[2]) / (qa[2] - qb[2]) * (qa - qb)
        scale = np.array([self.width, self.height])
        return clip_to_image(qa[:2] / qa[2] * scale, qb[:2] / qb[2] * scale, self.width, self.height)

    def point(self, p: np.ndarray) -> tuple[float, float] | None:
        """World point ``p`` in image pixels (x right, y down), or None when it is not in front of the eye."""
        q = self.m @ (np.asarray(p, float) - self.eye)
        return (q[0] / q[2] * self.width, q[1] / q[2] * self.height) if q[2] > 0 else None


def clip_to_image(a: np.ndarray, b: np.ndarray, width: int,
                  height: int) -> tuple[tuple[float, float], tuple[float, float]] | None:
    """Liang-Barsky: segment a-b cut to a margin around the image (Pillow draws nothing sensible far outside it)."""
    lo, hi = np.array([-2.0 * width, -2.0 * height]), np.array([3.0 * width, 3.0 * height])
    t0, t1, d = 0.0, 1.0, b - a
    for axis in range(2):
        for p, q in ((-d[axis], a[axis] - lo[axis]), (d[axis], hi[axis] - a[axis])):
            if p == 0:
                if q < 0:
                    return None
                continue
            t = q / p
            if p < 0:
                t0 = max(t0, t)
            else:
                t1 = min(t1, t)
    if t0 > t1:
        return None
    s, e = a + t0 * d, a + t1 * d
    return (float(s[0]), float(s[1])), (float(e[0]), float(e[1]))

