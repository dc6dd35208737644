"""A scene made ready for radiosity: its polygons with reflectance and emission, subdivided into checked patches.

Units: an area light of radiance L is a Lambertian emitter of radiosity B_e = π·L; a
polygon's material ``emission`` is its emitted radiosity. Subdividing is task R1, so it
comes in as a callable (the stage's checked call of a submission's ``subdivide``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field as dc_field
from typing import Any, Callable

import numpy as np

from .errors import InputError


@dataclass
class Patches:
    """The scene after subdivision: one row per patch."""
    quads: np.ndarray          # (m, 4, 3)
    parent: np.ndarray         # (m,) int: the polygon each patch came from
    areas: np.ndarray          # (m,)
    reflectance: np.ndarray    # (m, 3)
    emission: np.ndarray       # (m, 3) emitted radiosity
    polygons: np.ndarray       # (n, 4, 3): the polygons before subdivision
    labels: list[str] = dc_field(default_factory=list)  # per polygon: "objects[3]" or "lights[0]", for messages

    def __len__(self) -> int:
        return len(self.quads)


def radiosity_surfaces(scene: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[str]]:
    """What radiosity solves over: the scene's patches (:func:`cs451.patches.scene_polygons`) with a reflectance,
    an emitted radiosity and a label each: (quads, reflectance, emission, labels).

    Area lights become emitters of radiosity π·radiance that reflect nothing.
    """
    from .patches import scene_polygons as polygons_of
    from .scene import AreaLight, Polygon

    quads, names, emission = polygons_of(scene)
    labels = []
    for k, obj in enumerate(scene.objects):
        if isinstance(obj, Polygon):
            fan = len(obj.vertices) - 2 if len(obj.vertices) > 4 else 1     # polygons of 5+ corners become fans
            labels += [f"objects[{k}]"] * fan
    lights = [k for k, light in enumerate(scene.lights) if isinstance(light, AreaLight)]
    labels += [f"lights[{k}]" for k in lights]
    n_lights = len(lights)
    reflectance = np.array([scene.material(name).diffuse for name in names], dtype=np.float64).reshape(-1, 3)
    emission = np.array(emission, dtype=np.float64)
    if n_lights:
        reflectance[-n_lights:] = 0.0
        emission[-n_lights:] *= math.pi    # a Lambertian emitter of radiance L has radiosity πL
    return quads, reflectance, emission, labels


def is_closed(polygons: np.ndarray) -> bool:
    """Whether the polygons enclose space: every edge is shared by exactly two polygons (corners snapped)."""
    q = np.asarray(polygons, dtype=np.float64)
    scale = max(float(np.ptp(q.reshape(-1, 3), axis=0).max()), 1e-300)
    snapped = np.round(q / (1e-6 * scale)).astype(np.int64)
    counts: dict[tuple, int] = {}
    for poly in snapped.tolist():
        for a, b in zip(poly, poly[1:] + poly[:1]):
            if a != b:                                      # the repeated corner of a triangle is no edge
                key = (min(tuple(a), tuple(b)), max(tuple(a), tuple(b)))
                counts[key] = counts.get(key, 0) + 1
    return bool(counts) and all(c == 2 for c in counts.values())


def check_patches(p: Patches, where: str) -> None:
    """Refuse input with no solution or no meaning, with one line naming the polygon."""
    def polygon_of(patch: int) -> str:
        k = int(p.parent[patch])
        return p.labels[k] if k < len(p.labels) else f"polygon {k}"

    for name, arr in (("reflectance", p.reflectance), ("emission", p.emission), ("areas", p.areas)):
        if not np.isfinite(arr).all():
            bad = int(np.flatnonzero(~np.isfinite(arr.reshape(len(arr), -1)).all(axis=1))[0])
            raise InputError(where, polygon_of(bad), f"{name} is NaN or infinite")
    if (p.emission < 0).any():
        bad = int(np.flatnonzero((p.emission < 0).any(axis=1))[0])
        raise InputError(where, polygon_of(bad), f"negative emission {tuple(p.emission[bad])}: light cannot be absorbed by emitting")
    if (p.reflectance < 0).any() or (p.reflectance > 1).any():
        bad = int(np.flatnonzero(((p.reflectance < 0) | (p.reflectance > 1)).any(axis=1))[0])
        raise InputError(where, polygon_of(bad), f"reflectance {tuple(p.reflectance[bad])} must lie in [0, 1] (1 only where light can escape)")
    scale = float(np.ptp(p.quads.reshape(-1, 3), axis=0).max()) if len(p.quads) else 1.0
    tiny = p.areas <= 1e-12 * scale * scale
    if tiny.any():
        bad = int(np.flatnonzero(tiny)[0])
        raise InputError(where, polygon_of(bad), f"patch {bad} has zero area")
    for c, colour in enumerate("red green blue".split()):
        if np.all(p.reflectance[:, c] >= 1.0) and is_closed(p.polygons):
            raise InputError(where, "materials", f"every surface reflects all {colour} light (albedo >= 1) in a closed "
                             "scene: the light grows without bound and the radiosity equation has no solution")


def make_patches(scene: Any, subdivide: Callable[[np.ndarray, float], tuple[np.ndarray, np.ndarray]],
                 patch_size: float) -> Patches:
    """The scene's polygons, subdivided by ``subdivide`` (a stage-4 implementation's R1, checked), with colours."""
    from .patches import patch_areas

    quads, reflectance, emission, labels = radiosity_surfaces(scene)
    patches, parent = subdivide(quads, patch_size)
    p = Patches(patches, parent, patch_areas(patches), reflectance[parent], emission[parent], quads, labels)
    check_patches(p, scene.label)
    return p
