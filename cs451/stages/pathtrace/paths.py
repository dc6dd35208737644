"""Stage 5's scaffolding: a scene as the arrays a path tracer reads (:class:`PathScene`), and the samples a render
takes. Holds no task's answer: the tracer, its sampling, its light sampling and its roulette are the student's
(tasks P1-P4), and so are the camera rays and the ray casting (given in the stage's starter, not here).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...errors import KitError
from ...patches import patch_normals, patch_triangles
from ...patching import radiosity_surfaces
from ...scene import AreaLight, Polygon, Scene

#: what a tracer counts, by kind of ray
COUNTERS = ("camera", "bounce", "shadow")


@dataclass
class PathScene:
    """A diffuse scene lit by one rectangular area light, as arrays. Triangles are numbered as the scene's polygons
    (two a quad, fans for more corners), the light's two last."""
    v0: np.ndarray                 # (m, 3) triangle corners
    v1: np.ndarray
    v2: np.ndarray
    normal: np.ndarray             # (m, 3) unit: the polygon's front (its corners counter-clockwise seen from it)
    albedo: np.ndarray             # (m, 3) diffuse reflectance ρ in [0, 1]; 0 on the light
    emitter: np.ndarray            # (m,) bool: the light's triangles
    light_corner: np.ndarray       # (3,)
    light_u: np.ndarray            # (3,) edge vectors: the light is corner + a·u + b·v, a, b in [0, 1]
    light_v: np.ndarray
    light_normal: np.ndarray       # (3,) unit, u × v: the side it emits on
    light_area: float
    light_radiance: np.ndarray     # (3,) L_e, the same in every direction of the front side
    size: float                    # the scene's extent (the diagonal of its box)
    max_depth: int = 32            # the most bounces of a path
    roulette_depth: int = 3        # Russian roulette from this bounce on
    counters: dict[str, int] = field(default_factory=lambda: {k: 0 for k in COUNTERS})

    @property
    def n_triangles(self) -> int:
        """How many triangles the scene has, the light's included (a ray caster sizes its chunks by it)."""
        return len(self.v0)


def check_lighting(scene: Scene) -> None:
    """Refuse in one line a scene this stage cannot render right: no area light or two, a polygon that emits, or one
    whose material has a specular term (the tracer's surfaces are diffuse; stage 4 draws the highlight)."""
    lights = [k for k, light in enumerate(scene.lights) if isinstance(light, AreaLight)]
    if len(lights) != 1:
        raise KitError(f"{scene.label}: lights: stage 5 samples one area light, and this scene has {len(lights)}")
    for k, obj in enumerate(scene.objects):
        if not isinstance(obj, Polygon):
            continue                  # not a kind this stage draws: radiosity_surfaces refuses it by name
        if any(c > 0 for c in scene.material(obj.material).emission):
            raise KitError(f"{scene.label}: objects[{k}]: material {obj.material!r} emits; stage 5's only emitter is "
                           f"the area light (next-event estimation samples it)")
        material = scene.material(obj.material)
        if material.shininess > 0 and any(c > 0 for c in material.specular):
            raise KitError(f"{scene.label}: objects[{k}]: material {obj.material!r} is glossy (specular, shininess "
                           f"{material.shininess:g}); stage 5 traces diffuse surfaces only")


def build(scene: Scene, max_depth: int = 32, roulette_depth: int = 3) -> PathScene:
    """The scene's polygons and its one area light as a :class:`PathScene` (:func:`check_lighting` first)."""
    check_lighting(scene)
    lights = [k for k, light in enumerate(scene.lights) if isinstance(light, AreaLight)]
    quads, reflectance, _, _ = radiosity_surfaces(scene)
    tris, ids = patch_triangles(quads)
    light = scene.lights[lights[0]]
    corner, u, v = (np.asarray(x, dtype=np.float64) for x in (light.corner, light.edge_u, light.edge_v))
    cross = np.cross(u, v)
    lo, hi = tris.reshape(-1, 3).min(axis=0), tris.reshape(-1, 3).max(axis=0)
    n_light = int(np.sum(ids == len(quads) - 1))
    return PathScene(v0=tris[:, 0].copy(), v1=tris[:, 1].copy(), v2=tris[:, 2].copy(),
                     normal=patch_normals(quads)[ids], albedo=reflectance[ids],
                     emitter=np.r_[np.zeros(len(ids) - n_light, bool), np.ones(n_light, bool)],
                     light_corner=corner, light_u=u, light_v=v, light_normal=cross / np.linalg.norm(cross),
                     light_area=float(np.linalg.norm(cross)), light_radiance=np.asarray(light.radiance, dtype=np.float64),
                     size=float(np.linalg.norm(hi - lo)), max_depth=max_depth, roulette_depth=roulette_depth)


def polygon_of_triangles(scene: Scene) -> np.ndarray:
    """For each triangle of :func:`build`, the number of the quad it came from (radiosity's surfaces' order)."""
    quads, _, _, _ = radiosity_surfaces(scene)
    return patch_triangles(quads)[1]


def points_on_polygons(scene: Scene, polygons: list[int], samples: int,
                       rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """``samples`` uniform random points on each of these surfaces (numbered as :func:`radiosity_surfaces` numbers
    them: a polygon's quads, then the lights), with its front normal: (len(polygons)·samples, 3) each."""
    quads, _, _, _ = radiosity_surfaces(scene)
    if any(not 0 <= k < len(quads) for k in polygons):
        raise KitError(f"{scene.label}: polygons: numbers from 0 to {len(quads) - 1}, got {polygons}")
    tris, ids = patch_triangles(quads)
    normals = patch_normals(quads)
    points, out_normals = [], []
    for k in polygons:
        mine = tris[ids == k]
        area = 0.5 * np.linalg.norm(np.cross(mine[:, 1] - mine[:, 0], mine[:, 2] - mine[:, 0]), axis=1)
        pick = rng.choice(len(mine), samples, p=area / area.sum())
        a, b = rng.random(samples), rng.random(samples)
        flip = a + b > 1
        a, b = np.where(flip, 1 - a, a), np.where(flip, 1 - b, b)
        t = mine[pick]
        points.append(t[:, 0] + a[:, None] * (t[:, 1] - t[:, 0]) + b[:, None] * (t[:, 2] - t[:, 0]))
        out_normals.append(np.broadcast_to(normals[k], (samples, 3)))
    return np.concatenate(points), np.concatenate(out_normals)


def repeated(rows: np.ndarray, times: int) -> np.ndarray:
    """Each row ``times`` times in a row: the points or normals of a probe that samples each many times."""
    return np.repeat(np.asarray(rows, dtype=np.float64), int(times), axis=0)


def uniforms(seed: int, n: int, k: int) -> np.ndarray:
    """The uniform numbers in [0, 1) a probe hands a task, (n, k), from ``seed``: the truth draws the same."""
    return np.random.default_rng(int(seed)).random((int(n), int(k)))
