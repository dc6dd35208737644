"""Independent truths for stage 5's tests. Never shipped to students.

The path tracer is judged against stage 4: radiosity solves the same diffuse light transport by other means (form
factors from hemicubes, then shooting), and a path tracer's mean converges to the same light, up to radiosity's
own discretisation (a constant radiosity per patch). The sampling tasks are judged against closed forms.
"""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from cs451.patches import patch_areas
from cs451.scene import parse_scene


def radiosity_radiance(p: dict) -> dict[str, np.ndarray]:
    """Each asked-for surface's radiance by stage 4's reference: B/π averaged over the surface's patches by area."""
    return {"radiance": _radiosity(_key(p["scene"]), tuple(p["polygons"]))}


def _key(scene: dict) -> str:
    import json
    return json.dumps(scene, sort_keys=True)


@lru_cache(maxsize=8)
def _radiosity(scene_json: str, polygons: tuple[int, ...]) -> np.ndarray:
    import json
    from cs451.impl import earlier_stage_impl, load_impl
    from cs451.stages import get_stage
    stage = get_stage("radiosity")
    module = stage.render.__module__
    radiosity = __import__(module, fromlist=["make_patches"])
    scene = parse_scene(json.loads(scene_json), "<truth>")
    impl = load_impl(earlier_stage_impl("radiosity"), "radiosity")
    opts = stage.options(scene, patch_size=RADIOSITY_PATCH, resolution=RADIOSITY_RESOLUTION, tolerance=1e-6,
                         max_shots=1_000_000)
    patches = radiosity.make_patches(scene, impl, opts.patch_size)
    solution = radiosity.solve(patches, impl, opts)
    areas = patch_areas(patches.quads)
    out = []
    for k in polygons:
        mine = patches.parent == k
        out.append((solution.radiosity[mine] * areas[mine, None]).sum(axis=0) / areas[mine].sum() / math.pi)
    return np.array(out)


#: stage 4's settings for the truth: patches of 25 scene units (a Cornell box wall is ~22 × 22 patches), hemicubes of
#: resolution 256, shot to 1e-6 of the emitted power
RADIOSITY_PATCH = 25.0
RADIOSITY_RESOLUTION = 256


def _seen(scene, x: np.ndarray, y: np.ndarray) -> bool:
    """Whether the segment x-y crosses none of the scene's polygons (its two ends' own surfaces aside), by each
    polygon's plane and its edges (the polygons are convex)."""
    from cs451.patches import patch_normals
    from cs451.patching import radiosity_surfaces
    quads, _, _, _ = radiosity_surfaces(scene)
    for q, n in zip(quads, patch_normals(quads)):
        t = _crossing(q, n, x, y - x)
        if t is not None and 1e-9 < t < 1.0 - 1e-7:
            return False
    return True


def _crossing(q: np.ndarray, n: np.ndarray, o: np.ndarray, d: np.ndarray) -> float | None:
    """Where the line o + t·d meets the convex quad q (unit normal n), by its plane and its edges; None if it misses."""
    denominator = float(n @ d)
    if denominator == 0.0:
        return None
    t = float(n @ (q[0] - o)) / denominator
    hit = o + t * d
    return t if all(float(np.cross(q[(k + 1) % 4] - q[k], hit - q[k]) @ n) >= 0 for k in range(4)) else None


def _samples(p: dict) -> tuple:
    from cs451.stages.pathtrace import paths
    scene = parse_scene(p["scene"], "<truth>")
    samples = int(p.get("samples", 1))
    rows = [paths.repeated(np.asarray(p[k], dtype=np.float64), samples) for k in ("points", "normals", "albedo")]
    return scene, paths.build(scene), rows, paths.uniforms(p.get("seed", 0), len(rows[0]), 2)


def _direct_value(scene, ps, x: np.ndarray, n: np.ndarray, rho: np.ndarray, a: float, b: float
                  ) -> tuple[np.ndarray, bool]:
    """One light sample's value by P2's formula, long hand, and whether the point and the light face each other."""
    y = ps.light_corner + a * ps.light_u + b * ps.light_v
    d = y - x
    r = math.sqrt(d @ d)
    w = d / r
    cos_x, cos_l = float(n @ w), float(-(w @ ps.light_normal))
    if not (cos_x > 0 and cos_l > 0):
        return np.zeros(3), False
    if not _seen(scene, x, y):
        return np.zeros(3), True
    return ps.light_radiance * rho / math.pi * (cos_x * cos_l / (r * r) * ps.light_area), True


def direct_sample(p: dict) -> dict[str, np.ndarray]:
    """P2's estimate for each sample as the formula gives it, in long hand, with visibility by the polygons' planes;
    and how many samples face the light (one shadow ray each)."""
    scene, ps, (points, normals, albedo), u = _samples(p)
    out, lit = [], 0
    for x, n, rho, (a, b) in zip(points, normals, albedo, u):
        value, faces = _direct_value(scene, ps, x, n, rho, a, b)
        out.append(value)
        lit += faces
    return {"radiance": np.array(out), "lit": np.array(lit)}


def stratified_direct(p: dict) -> dict[str, np.ndarray]:
    """P5: per point, the mean of P2's formula over the cells of a k × k grid, cell (a, b) sampled at
    ((a + jitter)/k, (b + jitter)/k) with the probe's jitter."""
    from cs451.stages.pathtrace import paths
    scene = parse_scene(p["scene"], "<truth>")
    ps, k = paths.build(scene), int(p["strata"])
    points, normals, albedo = (np.asarray(p[key], dtype=np.float64) for key in ("points", "normals", "albedo"))
    jitter = paths.uniforms(p.get("seed", 0), len(points) * k * k, 2).reshape(len(points), k, k, 2)
    out = []
    for i, (x, n, rho) in enumerate(zip(points, normals, albedo)):
        total = np.zeros(3)
        for a in range(k):
            for b in range(k):
                total += _direct_value(scene, ps, x, n, rho, (a + jitter[i, a, b, 0]) / k, (b + jitter[i, a, b, 1]) / k)[0]
        out.append(total / (k * k))
    return {"radiance": np.array(out)}


def lambert_irradiance(p: dict) -> dict[str, np.ndarray]:
    """The direct light a point reflects, exactly: L_e·ρ times the point-to-rectangle form factor, by Lambert's
    contour formula F = 1/(2π) Σ β_i (n · ĝ_i) over the light's edges (the whole light seen, in front of the point)."""
    from cs451.stages.pathtrace import paths
    ps = paths.build(parse_scene(p["scene"], "<truth>"))
    corners = [ps.light_corner, ps.light_corner + ps.light_u, ps.light_corner + ps.light_u + ps.light_v,
               ps.light_corner + ps.light_v]
    out = []
    for x, n, rho in zip(*(np.asarray(p[k], dtype=np.float64) for k in ("points", "normals", "albedo"))):
        f = 0.0
        for a, b in zip(corners, corners[1:] + corners[:1]):
            ra, rb = a - x, b - x
            g = np.cross(ra, rb)
            beta = math.atan2(np.linalg.norm(g), ra @ rb)
            f += beta * (n @ g) / np.linalg.norm(g)
        f = abs(f) / (2 * math.pi)
        out.append(ps.light_radiance * rho * f)
    return {"radiance": np.array(out)}


def roulette_rule(p: dict) -> dict[str, np.ndarray]:
    """P3's rule as the handout states it: on with probability p = min(1, max β), weight β/p; else ended, weight 0."""
    beta, u = np.asarray(p["weights"], float), np.asarray(p["u"], float)
    prob = np.minimum(1.0, beta.max(axis=1))
    alive = u < prob
    return {"alive": alive, "weights": np.where(alive[:, None], beta / np.where(prob > 0, prob, 1.0)[:, None], 0.0)}


def light_seen(p: dict) -> dict[str, np.ndarray]:
    """For rays that meet the light or nothing first: L_e where the light's front is met, 0 on its back or a miss."""
    from cs451.patches import patch_normals
    from cs451.patching import radiosity_surfaces
    scene = parse_scene(p["scene"], "<truth>")
    quads, _, _, labels = radiosity_surfaces(scene)
    normals = patch_normals(quads)
    light = next(k for k, light in enumerate(scene.lights))
    out = []
    for o, d in zip(np.asarray(p["origins"], float), np.asarray(p["directions"], float)):
        nearest, which = math.inf, None
        for k, (q, n) in enumerate(zip(quads, normals)):
            t = _crossing(q, n, o, d)
            if t is not None and 0 < t < nearest:
                nearest, which = t, k
        if which is not None and labels[which] != f"lights[{light}]":
            raise ValueError(f"a ray meets {labels[which]} first: the test must aim at the light or at nothing")
        front = which is not None and float(normals[which] @ d) < 0
        out.append(np.asarray(scene.lights[light].radiance, float) if front else np.zeros(3))
    return {"radiance": np.array(out)}
