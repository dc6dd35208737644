"""Stage 5 public tests: students run these with ``cs451 grade pathtrace``.

Points per task (the rubric in assignments/05-pathtrace/README.md): P1 25, P2 25, P3 15, P4 35 in all; hidden.py
holds part of each task's points. A task whose answer is one number per set of random numbers (a light sample's
value, the roulette's rule, a ray meeting the light) is checked exactly for the same numbers; a distribution
(cosine sampling) and a mean (the direct light over the light, the path tracer's radiance) statistically, so that
a correct solution fails one test in about 200,000 (tolerances.SIGMAS) and the fresh cases draw new numbers.
P4 is judged against stage 4: radiosity's solution of the same Cornell box.
"""
from __future__ import annotations

import copy
import json

import numpy as np

from cs451.grading.spec import Test, check, truth, variant
from cs451.scene import BUNDLED_DIR
from cs451.stages.pathtrace import tolerances as TOL

from autograder.pathtrace import checks, truth as truths, variants

#: Time limits: generous for clear numpy code (the reference takes under 3 s for each).
QUICK, PATHS = 20.0, 120.0

CORNELL = json.loads((BUNDLED_DIR / "cornell-box.json").read_text())
#: the Cornell box's surfaces as stage 4 numbers them: its 15 polygons (the light, 15, is left out)
CORNELL_SURFACES = list(range(15))


def open_scene(blocker: bool = True, albedo: float = 0.5) -> dict:
    """A floor 2 × 2 under a 0.5 × 0.5 area light one unit up (facing down), and a small blocker between them."""
    floor = [[-1, 0, -1], [-1, 0, 1], [1, 0, 1], [1, 0, -1]]
    box = [[0.3, 0.5, -0.25], [0.3, 0.5, 0.25], [0.8, 0.5, 0.25], [0.8, 0.5, -0.25]]
    return {"name": "open", "image": {"width": 32, "height": 32},
            "camera": {"eye": [0, 0.5, 3], "center": [0, 0.5, 0], "up": [0, 1, 0], "fovy": 50},
            "materials": {"grey": {"diffuse": [albedo, albedo, albedo]}},
            "objects": [{"type": "polygon", "vertices": floor, "material": "grey"}]
                       + ([{"type": "polygon", "vertices": box, "material": "grey"}] if blocker else []),
            "lights": [{"type": "area", "corner": [-0.25, 1, -0.25], "edge_u": [0.5, 0, 0], "edge_v": [0, 0, 0.5],
                        "radiance": [4, 3, 2]}]}


#: the open scene's light and nothing else: its two triangles are the scene's first (a hit on triangle 0 is a hit)
LIGHT_ALONE = {**open_scene(blocker=False), "objects": []}


def _unit(v) -> list:
    v = np.asarray(v, float)
    return (v / np.linalg.norm(v, axis=-1, keepdims=True)).tolist()


def hemisphere_test(name, points, normals, samples, seed, near_poles: bool = False) -> Test:
    return Test(name, "P1", points, "cosine_sample", {"normals": normals, "samples": samples, "seed": seed},
                check(checks.directions_unit), f"unit within {TOL.UNIT}, about the normal, repeatable", expected="none",
                timeout=QUICK, vary=variant(variants.normals, near_poles=near_poles), edge_case=True)   # the normal itself passes: counts beside P1's others


def cosine_test(name, points, normals, samples, seed) -> Test:
    return Test(name, "P1", points, "cosine_sample", {"normals": normals, "samples": samples, "seed": seed},
                check(checks.cosine_distributed), f"cos²θ and φ uniform (χ² test, fails a correct answer with "
                f"probability {TOL.SIGMAS})", expected="none", timeout=QUICK, vary=variant(variants.normals))


def direct_test(name, points_, scene, points, normals, albedo, seed) -> Test:
    params = {"scene": scene, "points": points, "normals": normals, "albedo": albedo, "samples": 1, "seed": seed}
    return Test(name, "P2", points_, "direct_light", params, check(checks.samples_match),
                f"each sample within {TOL.FLOAT64} of L_e·ρ/π·cos θ·cos θ_L/r²·A where seen, 0 elsewhere",
                expected="none", truth=truth(truths.direct_sample), timeout=QUICK, vary=variant(variants.points))


def stratified_test(name, points_, scene, points, normals, albedo, strata, seed) -> Test:
    params = {"scene": scene, "points": points, "normals": normals, "albedo": albedo, "strata": strata, "seed": seed}
    return Test(name, "P5", points_, "stratified", params, check(checks.samples_match),
                f"each point within {TOL.FLOAT64} of the mean of P2's formula over its cells", expected="none",
                truth=truth(truths.stratified_direct), timeout=QUICK, depends_on=("P2",), vary=variant(variants.points))


def shadow_count_test(name, points_, scene, points, normals, albedo, seed) -> Test:
    params = {"scene": scene, "points": points, "normals": normals, "albedo": albedo, "samples": 1, "seed": seed}
    return Test(name, "P2", points_, "direct_light", params, check(checks.shadow_rays_where_lit),
                "one shadow ray per sample where the surface and the light face each other, none elsewhere",
                expected="none", truth=truth(truths.direct_sample), timeout=QUICK, vary=variant(variants.points))


def lambert_test(name, points_, scene, points, normals, albedo, samples, seed) -> Test:
    params = {"scene": scene, "points": points, "normals": normals, "albedo": albedo, "samples": samples, "seed": seed}
    return Test(name, "P2", points_, "direct_light", params, check(checks.mean_matches, samples=samples),
                "the mean of the samples within its statistical error of ρ·L_e·F (Lambert's contour formula)",
                expected="none", truth=truth(truths.lambert_irradiance), timeout=QUICK, vary=variant(variants.points))


def roulette_test(name, points, weights, u) -> Test:
    return Test(name, "P3", points, "roulette", {"weights": weights, "u": u}, check(checks.roulette_matches),
                f"alive exactly where u < min(1, max β); weights β/p within {TOL.FLOAT64}, 0 for the ended",
                expected="none", truth=truth(truths.roulette_rule), timeout=QUICK, vary=variant(variants.weights))


def light_rays_test(name, points, scene, origins, directions) -> Test:
    return Test(name, "P4", points, "rays", {"scene": scene, "origins": origins, "directions": directions},
                check(checks.rays_match), "L_e on the light's front, 0 on its back and on a miss, exactly",
                expected="none", truth=truth(truths.light_seen), timeout=QUICK, vary=variant(variants.light_rays))


def lone_paths_test(name, points, scene, origins, directions) -> Test:
    return Test(name, "P4", points, "rays", {"scene": scene, "origins": origins, "directions": directions, "seed": 9,
                                             "one_at_a_time": True},
                check(checks.lone_paths_lit), "each path, traced alone, brings some light (its first bounce sees the light)",
                expected="none", timeout=QUICK, vary=variant(variants.lone_paths))


def roulette_count_test(name, points, scene, samples, seed) -> Test:
    params = {"scene": scene, "polygons": CORNELL_SURFACES, "samples": samples, "seed": seed, "roulette_depth": 1,
              "max_depth": 2}
    return Test(name, "P4", points, "polygon_radiance", params, check(checks.roulette_thins),
                f"bounce rays at most a + a² + {TOL.ROULETTE_SLACK:g} per path, a the largest albedo",
                expected="none", timeout=PATHS, depends_on=("P1", "P2", "P3"), vary=variant(variants.seed),
                edge_case=True)   # casting no bounce ray at all also stays under the bound: counts beside P4's others


def dark_box() -> dict:
    """The Cornell box with every albedo a tenth of its own: from bounce 1, the roulette ends nine paths in ten."""
    scene = copy.deepcopy(CORNELL)
    for material in scene["materials"].values():
        material["diffuse"] = [round(c / 10, 4) for c in material["diffuse"]]
    return scene


def radiosity_test(name, points, scene, samples, seed) -> Test:
    params = {"scene": scene, "polygons": CORNELL_SURFACES, "samples": samples, "seed": seed}
    return Test(name, "P4", points, "polygon_radiance", params, check(checks.like_radiosity),
                f"each surface's mean radiance within its statistical error (probability {TOL.SIGMAS} of a false "
                f"alarm) plus {TOL.RADIOSITY_BIAS:.0%} of stage 4's radiosity",
                expected="none", truth=truth(truths.radiosity_radiance), timeout=PATHS,
                depends_on=("P1", "P2", "P3"), vary=variant(variants.seed))


_rng = np.random.default_rng(5)
FLOOR_POINTS = np.c_[_rng.uniform(-0.9, 0.9, 40), np.zeros(40), _rng.uniform(-0.9, 0.9, 40)].round(4).tolist()
UP = [[0, 1, 0]] * 40
GREY = [[0.5, 0.5, 0.5]] * 40
WEIGHTS = np.r_[_rng.uniform(0, 1, (30, 3)), _rng.uniform(0.5, 2, (6, 3)), np.zeros((2, 3)),
                [[1e-3, 0, 0], [1.0, 1.0, 1.0], [0.25, 0.1, 0.0]]].round(6).tolist()
#: the last path draws u = p exactly: it ends (it goes on where u < p)
ROULETTE_U = _rng.random(len(WEIGHTS) - 1).round(6).tolist() + [0.25]
#: points at the light's height (y = 1) facing it sideways: the light is edge-on (cos θ_L = 0), so no shadow ray
EDGE_ON = ([[0.6, 1.0, 0.0], [-0.6, 1.0, 0.1], [0.0, 1.0, 0.7], [0.1, 1.0, -0.8]],
           [[-1, 0, 0], [1, 0, 0], [0, 0, -1], [0, 0, 1]])
NORMALS = _unit([[0, 0, 1], [0, 0, -1], [1, 0, 0], [0, -1, 0], [0.3, -0.5, 0.8], [-0.6, 0.7, -0.2]])

TESTS = [
    hemisphere_test("P1 cosine_sample: unit directions about six normals, repeatable", 4, NORMALS, 500, 1),
    cosine_test("P1 cosine_sample: cos θ/π about +z", 8, [[0, 0, 1]], 40_000, 2),
    cosine_test("P1 cosine_sample: cos θ/π about tilted and downward normals", 6, NORMALS[1:], 20_000, 3),
    hemisphere_test("P1 cosine_sample: unit directions about normals a hair (ten millionths of a radian) off +z and -z", 2,
                    _unit([[1e-7, 3e-8, 1.0], [-2e-7, 1e-7, -1.0]]), 500, 8, near_poles=True),
    direct_test("P2 direct_light: each sample by its formula, some behind a blocker", 8, open_scene(), FLOOR_POINTS,
                UP, GREY, 4),
    shadow_count_test("P2 direct_light: a shadow ray only where the surface faces the light (not where it is edge-on)",
                      4, open_scene(), FLOOR_POINTS[:20] * 2 + EDGE_ON[0], UP[:20] + [[0, -1, 0]] * 20 + EDGE_ON[1],
                      GREY[:4] * 11, 5),
    lambert_test("P2 direct_light: the mean is the direct light (Lambert's formula)", 8, open_scene(blocker=False),
                 [[0, 0, 0], [0.7, 0, 0.2], [-0.9, 0, -0.9]], [[0, 1, 0]] * 3, [[0.5, 0.5, 0.5]] * 3, 20_000, 6),
    roulette_test("P3 roulette: on with p = min(1, max β), weighed by 1/p", 10, WEIGHTS, ROULETTE_U),
    light_rays_test("P4 radiance: the light alone, rays into both halves of its front", 1, LIGHT_ALONE,
                    [[-0.2, 0.5, -0.1], [0.2, 0.5, 0.1], [0.1, 0.5, -0.2], [-0.1, 0.5, 0.2]], [[0, 1, 0]] * 4),
    lone_paths_test("P4 radiance: one path at a time onto the floor under the light", 1, open_scene(blocker=False),
                    [[x, 0.5, z] for x, z in ((0.0, 0.0), (0.1, -0.1), (-0.15, 0.05))], [[0, -1, 0]] * 3),
    roulette_count_test("P4 radiance: roulette from bounce 1 in a dark box: few paths go on", 2, dark_box(), 1000, 8),
    light_rays_test("P4 radiance: the light's front, its back, and nothing", 3, open_scene(),
                    [[0, 0.9, 0], [0.1, 0.95, -0.1], [0, 1.5, 0], [0.1, 1.2, 0.1], [0, 1.5, 0], [-2, 0.5, 0]],
                    _unit([[0, 1, 0], [0, 1, 0.2], [0, -1, 0], [0.1, -1, 0], [0, 1, 0], [-1, 0, 0]])),
    radiosity_test("P4 radiance: the Cornell box, surface by surface, against radiosity", 18, CORNELL, 8000, 7),
    stratified_test("P5 stratified_direct_light (optional): 4 × 4 cells, points in and out of a blocker's shadow", 3,
                    open_scene(), FLOOR_POINTS[:12], UP[:12], GREY[:12], 4, 9),
    stratified_test("P5 stratified_direct_light (optional): 3 × 3 cells, the light seen whole", 2,
                    open_scene(blocker=False), FLOOR_POINTS[12:20], UP[:8], GREY[:8], 3, 10),
]
