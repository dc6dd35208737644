"""Stage 5's fresh cases: each public test's case with new numbers of the same kind. Not shipped to students.

Every fresh case also draws a fresh seed, so the statistical tests see new random numbers: a solution cannot be
tuned to the shipped seed's samples.
"""
from __future__ import annotations

import numpy as np

from cs451.grading.spec import Case


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _seed(rng: np.random.Generator) -> int:
    return int(rng.integers(1, 2 ** 31))


def normals(p: dict, rng: np.random.Generator, near_poles: bool = False) -> Case:
    """As many fresh unit normals (one of them straight down), a fresh seed; with ``near_poles``, normals within
    1e-7 to 1e-6 of +z and -z (n_z 1e-15 to 1e-12 from ±1, kept by the rounding), where a frame built about
    the normal loses its precision if it divides by 1 - |n_z|."""
    if near_poles:
        k = len(p["normals"])
        tilt = rng.uniform(0.5, 1, (k, 2)) * rng.choice([-1, 1], (k, 2)) * 10.0 ** rng.uniform(-7, -6, (k, 1))
        n = _unit(np.c_[tilt, np.where(np.arange(k) % 2 == 0, 1.0, -1.0)])
        return Case({**p, "normals": np.round(n, 15).tolist(), "seed": _seed(rng)},
                    f"{k} fresh normals within 1e-6 of +z and -z")
    n = _unit(rng.normal(size=(len(p["normals"]), 3)))
    n[0] = [0.0, 0.0, -1.0] if len(n) > 1 else n[0]
    return Case({**p, "normals": np.round(n, 12).tolist(), "seed": _seed(rng)}, f"{len(n)} fresh normals")


def points(p: dict, rng: np.random.Generator) -> Case:
    """As many fresh points on the floor (x, z in [-0.9, 0.9]), fresh colours, a fresh seed; normals as they were.
    A point at the light's height (the light edge-on to it) stays where it is."""
    k = len(p["points"])
    x = np.c_[rng.uniform(-0.9, 0.9, k), np.zeros(k), rng.uniform(-0.9, 0.9, k)]
    edge_on = np.asarray(p["points"], float)[:, 1] != 0.0
    x[edge_on] = np.asarray(p["points"], float)[edge_on]
    albedo = rng.uniform(0.1, 0.95, (k, 3))
    return Case({**p, "points": np.round(x, 4).tolist(), "albedo": np.round(albedo, 3).tolist(), "seed": _seed(rng)},
                f"{k} fresh points and colours on the floor")


def weights(p: dict, rng: np.random.Generator) -> Case:
    """Fresh weights of the same kinds (most below 1, some above, two zero) and fresh numbers u."""
    k = len(p["weights"])
    beta = rng.uniform(0, 1, (k, 3))
    beta[: k // 6] *= 2.5
    beta[-2:] = 0.0
    u = np.round(rng.random(k), 6)
    tie = np.round(rng.uniform(0.1, 0.9), 6)          # one path draws u = p exactly: it ends
    beta[-3], u[-3] = [tie, np.round(tie * rng.uniform(0, 1), 6), 0.0], tie
    return Case({"weights": np.round(beta, 6).tolist(), "u": u.tolist()},
                f"{k} fresh weights and uniform numbers, one with u = p")


def light_rays(p: dict, rng: np.random.Generator) -> Case:
    """Fresh rays of the same three kinds: up into the light's front, down onto its back, and into nothing."""
    def at(y, spread):
        return np.c_[rng.uniform(-spread, spread, 2), [y, y], rng.uniform(-spread, spread, 2)]
    up = _unit(np.c_[rng.uniform(-0.05, 0.05, 2), [1, 1], rng.uniform(-0.05, 0.05, 2)])
    origins = np.r_[at(0.9, 0.15), at(1.4, 0.15), [[0, 1.5, 0], [-2, 0.5, 0]]]
    directions = np.r_[up, -up, [[0, 1, 0], [-1, 0, 0]]]
    return Case({**p, "origins": np.round(origins, 6).tolist(), "directions": np.round(directions, 12).tolist()},
                "fresh rays to the light's front, onto its back and into nothing")


def lone_paths(p: dict, rng: np.random.Generator) -> Case:
    """As many fresh rays straight down onto the floor under the light (x, z within 0.2 of its centre)."""
    k = len(p["origins"])
    origins = np.c_[rng.uniform(-0.2, 0.2, k), np.full(k, 0.5), rng.uniform(-0.2, 0.2, k)]
    return Case({**p, "origins": np.round(origins, 4).tolist(), "seed": _seed(rng)},
                f"{k} fresh rays down onto the floor under the light, one call each")


def seed(p: dict, rng: np.random.Generator) -> Case:
    """The same surfaces with a fresh seed: new points on them and new paths."""
    return Case({**p, "seed": _seed(rng)}, "new random points and paths")
