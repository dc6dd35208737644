"""Helpers of the stages' variants (``autograder/<stage>/variants.py``): fresh numbers of the same kind.

Like the variants, this never ships to students. Every helper draws from the generator it is
given, so a fresh case depends on the kit's secret and the test alone.
"""
from __future__ import annotations

from typing import Any

import numpy as np


def num(x: float, digits: int = 4) -> float:
    """A float rounded for a readable description (and exact in JSON)."""
    return round(float(x), digits)


def scaled(values: Any, rng: np.random.Generator, lo: float = 0.6, hi: float = 1.5, digits: int = 4) -> Any:
    """Each number times its own factor in [lo, hi]: zeros stay zero and signs stay (a mirror stays a mirror)."""
    arr = np.asarray(values, float)
    return np.round(arr * rng.uniform(lo, hi, arr.shape), digits).tolist()


def colour(c: list, rng: np.random.Generator, lo: float = 0.15, hi: float = 0.95) -> list:
    """A fresh colour of as many channels, each in [lo, hi]."""
    return np.round(rng.uniform(lo, hi, len(c)), 3).tolist()


def dimmed(c: list, rng: np.random.Generator, lo: float = 0.6, hi: float = 1.0) -> list:
    """A light's colour scaled per channel, at most 1."""
    return np.round(np.clip(np.asarray(c, float) * rng.uniform(lo, hi, len(c)), 0, 1), 3).tolist()


def rotation(rng: np.random.Generator) -> np.ndarray:
    """A uniformly random rotation matrix (3 × 3)."""
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def rotation_about(axis: Any, angle: float) -> np.ndarray:
    """The rotation by ``angle`` radians about ``axis`` (Rodrigues)."""
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


class Similarity:
    """x ↦ s·R·x + t: keeps every incidence (a hit stays a hit, a grazing ray grazes, a degenerate triangle stays
    degenerate) while changing every number."""

    def __init__(self, rng: np.random.Generator, scale: tuple[float, float] = (0.7, 1.4), shift: float = 2.0):
        self.R = rotation(rng)
        self.s = float(rng.uniform(*scale))
        self.t = rng.uniform(-shift, shift, 3)

    def point(self, p: Any) -> list:
        return (self.s * np.asarray(p, float) @ self.R.T + self.t).tolist()

    def vector(self, v: Any) -> list:
        return (np.asarray(v, float) @ self.R.T).tolist()

    def length(self, x: float) -> float:
        return self.s * float(x)


def fresh_box(scene: dict, rng: np.random.Generator) -> dict:
    """A scene with the same objects (the Cornell box's walls and blocks, Whitted's spheres): its area lights moved a
    little across their plane and recoloured, point lights moved a little, every coloured material's diffuse colour
    fresh (below 0.9), the camera moved a little."""
    import copy
    scene = copy.deepcopy(scene)
    for light in scene["lights"]:
        if light.get("type") == "area":
            u, v = np.asarray(light["edge_u"], float), np.asarray(light["edge_v"], float)
            light["corner"] = np.round(np.asarray(light["corner"], float) + rng.uniform(-0.35, 0.35) * u
                                       + rng.uniform(-0.35, 0.35) * v, 3).tolist()
            light["radiance"] = np.round(np.asarray(light["radiance"], float) * rng.uniform(0.6, 1.4, 3), 3).tolist()
        elif "position" in light:
            light["position"] = np.round(np.asarray(light["position"], float) + rng.uniform(-0.1, 0.1, 3)
                                         * np.linalg.norm(light["position"]), 4).tolist()
    for material in scene["materials"].values():
        if max(material.get("diffuse", [0.0])) >= 0.1:     # coloured surfaces; a mirror or glass stays as it is
            material["diffuse"] = colour(material["diffuse"], rng, 0.05, 0.85)
    cam = scene["camera"]
    eye, center = np.asarray(cam["eye"], float), np.asarray(cam["center"], float)
    reach = 0.05 * float(np.linalg.norm(eye - center))
    cam["eye"] = np.round(eye + rng.uniform(-reach, reach, 3), 3).tolist()
    return scene


def box_description(scene: dict) -> str:
    """What :func:`fresh_box` changed, in a line."""
    lights = "; ".join(f"light at {light.get('corner', light.get('position'))}"
                       + (f" of radiance {light['radiance']}" if "radiance" in light else "") for light in scene["lights"])
    colours = ", ".join(f"{name} {m['diffuse']}" for name, m in scene["materials"].items() if "diffuse" in m)
    return f"{lights}; colours {colours}; eye {scene['camera']['eye']}"
