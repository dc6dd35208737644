"""Stage 2 hidden tests: cameras, scales and scenes the handout does not show. Not shipped to students."""
from __future__ import annotations

import numpy as np

from autograder.whitted.public import (CORNELL, WHITTED, bundled, camera_test, counter_test, depth_test, fresnel_test,
                                       hits_test, image_test, mirror_rays, reflect_test, refract_test, shading_test,
                                       shadow_test, sphere_test, triangle_test, two_mirrors, watertight_test, bvh_test,
                                       SHADOW_SCENE)
from autograder.whitted import variants
from cs451.grading.spec import variant

RNG = np.random.default_rng(4242)


def _unit(v):
    v = np.asarray(v, float)
    return (v / np.linalg.norm(v, axis=-1, keepdims=True)).tolist()


# a 1e-3 sphere 1e4 away: the textbook quadratic cancels here (Ray Tracing Gems ch. 7)
FAR_CENTER = np.array([1e4, 2e3, -3e3])
_aim = FAR_CENTER + RNG.uniform(-1.2e-3, 1.2e-3, (40, 3))
FAR_RAYS = {"origins": [[0, 0, 0]] * 40, "directions": _aim.tolist()}

# grazing and degenerate triangles, tiny and huge coordinates
_tri_o = RNG.uniform(-1, 1, (30, 3)) + [0, 0, 3]
_tri_t = RNG.uniform(-0.2, 1.2, (30, 2))
TRI_RANDOM = {"origins": _tri_o.tolist(),
              "directions": (np.c_[_tri_t, np.zeros(30)] - _tri_o).tolist(),
              "v0": [[0, 0, 0]] * 30, "v1": [[1, 0, 0]] * 30, "v2": [[0, 1, 0]] * 30}
TRI_DEGENERATE = {"origins": [[0.5, 0.1, 1], [0.5, 0.0, 1], [0.2, 0.2, 1]], "directions": [[0, 0, -1]] * 3,
                  "v0": [[0, 0, 0], [0, 0, 0], [0, 0, 0]], "v1": [[1, 0, 0], [1, 0, 0], [0, 0, 0]],
                  "v2": [[2, 0, 0], [2, 0, 0], [0, 0, 0]]}
SCALE = 1e5
TRI_HUGE = {k: (np.asarray(v) * (SCALE if k != "directions" else 1)).tolist() for k, v in TRI_RANDOM.items()}

# the rippled torus's own triangles as boxes: 55,296 of them
TORUS = bundled("rippled-torus")

# mixed rays in the Whitted scene: from outside, from inside the glass sphere, grazing the mirror sphere
_o = np.r_[RNG.uniform(-3, 3, (150, 3)) + [0, 2, 4], np.tile([[-0.55, 0.85, 0.9]], (50, 1))]
_d = _unit(RNG.normal(size=(200, 3)))
WHITTED_RAYS = {"origins": _o.tolist(), "directions": _d}

SHADOW_RANDOM = {"origins": (RNG.uniform(-3, 3, (60, 3)) + [0, -1, 0]).tolist(),
                 "targets": (RNG.uniform(-3, 3, (60, 3)) + [0, 4, 0]).tolist()}

VANISH = bundled("whitted", materials={**WHITTED["materials"],
                                       "air": {"ambient": [0, 0, 0], "diffuse": [0, 0, 0], "transmittance": [1, 1, 1],
                                               "ior": 1.0, "fresnel": True}},
                 objects=WHITTED["objects"][:2] + [{**WHITTED["objects"][2], "material": "air"}])

_g = np.asarray(_unit(RNG.normal(size=(30, 3)) + [0, 0, -1]))
TESTS = [
    camera_test("W1 camera_rays: an oblique camera, 9×5, fovy 75°", 2,
                camera={"eye": [3, -2, 7], "center": [-1, 0.5, 0], "up": [0.2, 1, 0], "fovy": 75}, width=9, height=5),
    sphere_test("W2 intersect_sphere: tangent rays of a sphere off the origin, one at its own origin", 1,
                center=[1, 2, 3], radius=2.0, origins=[[1, 4, -2], [3, 2, 3], [1, 2, -5]],
                directions=[[0, 0, 1], [0, 1, 0], [0, 0, 2]], vary=variant(variants.sphere_exact)),
    sphere_test("W2 intersect_sphere: a 1e-3 sphere 1e4 away (no cancellation)", 1,
                center=FAR_CENTER.tolist(), radius=1e-3, **FAR_RAYS),
    triangle_test("W3 intersect_triangle: 30 random rays, degenerate triangles", 1,
                  **{k: TRI_RANDOM[k] + TRI_DEGENERATE[k] for k in TRI_RANDOM}),
    triangle_test("W3 intersect_triangle: coordinates of 1e5", 1, **TRI_HUGE),
    watertight_test("W3 intersect_triangle: no gaps in a tiny fan (1e-4) seen from afar", 1,
                    center=[3e-5, -2e-5, 2.0],
                    fan=[[1e-4 * np.cos(a), 1e-4 * np.sin(a), 0.0] for a in np.linspace(0, 2 * np.pi, 9)[:-1]]),
    bvh_test("W4 build_bvh: the 55,296 triangles of the rippled torus", 3, scene=TORUS),
    hits_test("W5 closest_hit: 200 rays in Whitted's scene, 50 from inside the glass", 1, WHITTED,
              rays=WHITTED_RAYS),
    hits_test("W5 closest_hit: the rippled torus through the reference's hierarchy, 48×36", 2, TORUS, size=(48, 36)),
    shading_test("W6 local_shading: lights behind, grazing (one exactly: n·l = 0), shininess 0", 3,
                 normals=[[0, 0, 1]] * 5, to_eye=[[0, 0, 1]] * 5,
                 to_light=_unit([[0, 0, -1], [1, 0, 1e-9], [1, 0, 1], [0, 1, 1], [1, 0, 0]]),
                 light_diffuse=[[1, 0.5, 0.2]] * 5, light_specular=[[0.3, 0.3, 0.3]] * 5,
                 diffuse=[[0.5, 0.5, 0.5]] * 5, specular=[[1, 1, 1]] * 5, shininess=[10.0, 10.0, 0.0, 64.0, 10.0]),
    shadow_test("W7 shadow_transmission: 60 random segments", 2, SHADOW_SCENE, **SHADOW_RANDOM),
    reflect_test("W8 reflect: random normals", 2, directions=_g.tolist(),
                 normals=_unit(-_g + RNG.normal(size=(30, 3)) * 0.3)),
    refract_test("W9 refract: out of glass, total internal reflection, η = 1 (two rays grazing: sin²θt = 1 exactly)", 1,
                 directions=_g.tolist() * 2 + [[0, 1, 0], [-0.8, 0.6, 0]], normals=[[0, 0, 1]] * 62,
                 eta=[1.5] * 30 + [1.0] * 32),
    fresnel_test("W10 fresnel: water to air (η = 1.33), past the critical angle", 1,
                 cos_i=np.linspace(0, 1, 21).tolist(), eta=1.33),
    image_test("W11 trace: the Cornell box with a mirror and a glass sphere, 64×64", 2, bundled("cornell-spheres"),
               (64, 64)),
    image_test("W11 trace: the Cornell box with a mirror and a glass sphere at depth 1, 48×48", 1,
               bundled("cornell-spheres", options={"whitted": {"max_depth": 1, "min_weight": 0.01, "spp": 1}}), (48, 48)),
    image_test("W11 trace: a glass sphere of index 1 vanishes, 64×48", 2, VANISH, (64, 48)),
    image_test("W11 trace: the rippled torus, 64×48", 1, TORUS, (64, 48)),
    counter_test("W11 trace: the depth limit between two mirrors (r = 0.8, cut-off 0.01, depth 4)", 1,
                 two_mirrors(0.8, 0.01, 4), (12, 8), {"camera": 1, "reflection": mirror_rays(0.8, 0.01, 4)}),
]
