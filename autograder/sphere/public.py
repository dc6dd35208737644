"""Stage 1 public tests: students run these with ``cs451 grade sphere``.

Points per task (the rubric in assignments/01-sphere/README.md):
S1 10, S2 10, S3 20, S4 25, S5 15, S6 10, S7 10; hidden.py holds the rest of each task's points.
Every case a hidden test checks (directional and attenuated lights, an infinite viewer, a minimised
window, the limits of + and -) has a public test too, and a coarse sphere tells a Phong shader that
renormalises the interpolated normal from one that does not.
"""
from __future__ import annotations

import copy
import json

from cs451.compare import ImageTolerance
from cs451.grading.checks import all_of, array_close, image_matches, sub
from cs451.grading.spec import Test, truth

from cs451.scene import BUNDLED_DIR

from autograder.sphere import checks, truth as truths

#: Tolerance of the image tests: the measured margin is in the kit README ("Tolerances").
IMAGE = ImageTolerance()  # the kit's margin, measured in the README ("Tolerances")
MATRIX_TOL = "entries within 1e-6 relative, 1e-9 absolute"
#: Time limits per test: generous for clear numpy code (the reference takes under 0.2 s for each).
QUICK, RENDER = 10.0, 30.0

SPHERE_SCENE = json.loads((BUNDLED_DIR / "sphere.json").read_text())


def scene_variant(**changes) -> dict:
    """The handout's scene with top-level fields replaced (a deep copy)."""
    scene = copy.deepcopy(SPHERE_SCENE)
    scene.update(copy.deepcopy(changes))
    return scene


def perspective_test(name, points, **params) -> Test:
    return Test(name, "S1", points, "perspective", params, array_close("matrix", what="the matrix"),
                MATRIX_TOL, expected="none", truth=truth(truths.perspective), timeout=QUICK)


def look_at_test(name, points, **params) -> Test:
    return Test(name, "S2", points, "look_at", params, array_close("matrix", what="the matrix"),
                MATRIX_TOL, expected="none", truth=truth(truths.look_at), timeout=QUICK)


MESH_CHECKS = all_of([("vertex and triangle counts", sub(checks.mesh_counts)),
                      ("unit outward normals", sub(checks.mesh_normals)),
                      ("glutSolidSphere's vertices", sub(checks.mesh_vertices)),
                      ("closed, counter-clockwise surface", sub(checks.mesh_closed)),
                      ("no zero-area triangles", sub(checks.mesh_no_degenerate))],
                     require=["vertex and triangle counts"])


def mesh_test(name, points, **params) -> Test:
    return Test(name, "S3", points, "sphere_mesh", params, MESH_CHECKS,
                "positions within 1e-6·radius of freeglut's; normals unit within 1e-5", expected="none",
                truth=truth(truths.sphere_mesh), timeout=QUICK)


def shader_test(name, task, points, scene, size) -> Test:
    shading = "gouraud" if task == "S4" else "phong"
    return Test(name, task, points, "render", {"scene": scene, "size": list(size), "shading": shading},
                image_matches(IMAGE), IMAGE.describe(), given="parts", timeout=RENDER)


RESHAPE_CHECKS = all_of([("viewport covers the window", sub(checks.reshape_viewport)),
                         ("aspect ratio kept", sub(checks.reshape_aspect)),
                         ("vertical field of view kept", sub(checks.reshape_fovy))],
                        earn_with=["viewport covers the window", "vertical field of view kept"])


def reshape_test(name, points, **params) -> Test:
    params.setdefault("camera", SPHERE_SCENE["camera"])
    return Test(name, "S6", points, "reshape", params, RESHAPE_CHECKS,
                "viewport exact; aspect and field of view within 1e-6 relative", expected="none",
                given="reshape_parts", truth=truth(truths.reshape), timeout=QUICK)


def keys_test(name, points, presses) -> Test:
    """One sub-check per press that changes the state; presses that change nothing are checked but earn nothing alone."""
    changing = [i for i, (key, state) in enumerate(presses) if truths.key_truth(key, state) != state]
    parts = [(f"press {i + 1} ({key!r})", sub(checks.key_press, index=i)) for i, (key, _) in enumerate(presses)]
    return Test(name, "S7", points, "handle_key", {"presses": presses},
                all_of(parts, earn_with=[parts[i][0] for i in changing]), "exact", expected="none",
                truth=truth(truths.keys), timeout=QUICK)


START = {"running": True, "shading": "gouraud", "slices": 32, "stacks": 32}

#: A directional light and an attenuated point light in world space, an infinite viewer, emission: every term
#: of the lighting equation the handout's scene leaves at its default.
LIGHTS_AND_VIEWER = scene_variant(
    ambient=[0.08, 0.08, 0.08],
    lights=[{"type": "directional", "direction": [-0.6, -0.4, -1], "diffuse": [0.5, 0.6, 0.9], "specular": [0.6, 0.6, 0.6],
             "ambient": [0.05, 0.05, 0.05]},
            {"type": "point", "position": [3, 2, 3], "diffuse": [1.0, 0.8, 0.5], "specular": [1, 1, 1],
             "attenuation": [0.4, 0.08, 0.02]}],
    materials={"green": {"diffuse": [0.3, 0.9, 0.5], "specular": [0.7, 0.7, 0.7], "shininess": 25,
                         "emission": [0.04, 0.02, 0.0]}},
    options={"sphere": {"local_viewer": False}})

#: Few, large triangles seen close up under a close light: between two vertices the interpolated normal is
#: far shorter than 1, so a Phong shader that does not renormalise it (handout §S5) is visibly darker.
COARSE_CLOSE = scene_variant(
    camera={"eye": [0, 0, 3.5], "center": [0, 0, 0], "up": [0, 1, 0], "fovy": 45, "near": 0.5, "far": 20},
    lights=[{"type": "point", "position": [0.5, 0.7, 2.5], "diffuse": [0.9, 0.9, 0.9], "specular": [0.5, 0.5, 0.5]}],
    materials={"green": {"diffuse": [0.3, 0.9, 0.5], "specular": [0.6, 0.6, 0.6], "shininess": 30}},
    objects=[{"type": "sphere", "radius": 1, "material": "green", "slices": 8, "stacks": 6}])

TESTS = [
    perspective_test("S1 perspective: the handout's 30°, square window", 3, fovy=30, aspect=1.0, near=2, far=100),
    perspective_test("S1 perspective: 60°, wide window", 3, fovy=60, aspect=16 / 9, near=0.5, far=50),
    look_at_test("S2 look_at: the handout's camera", 3, eye=[0, 0, 8], center=[0, 0, 0], up=[0, 1, 0]),
    look_at_test("S2 look_at: an oblique camera", 3, eye=[3, 4, 5], center=[1, -1, 0.5], up=[0, 1, 0]),
    mesh_test("S3 sphere_mesh: glutSolidSphere(1, 32, 32)", 8, radius=1.0, slices=32, stacks=32),
    mesh_test("S3 sphere_mesh: a coarse sphere, radius 2, 8 slices, 5 stacks", 6, radius=2.0, slices=8, stacks=5),
    shader_test("S4 Gouraud: the handout's sphere, 500×500", "S4", 10, SPHERE_SCENE, (500, 500)),
    shader_test("S4 Gouraud: a 320×240 window", "S4", 5, SPHERE_SCENE, (320, 240)),
    shader_test("S4 Gouraud: a directional and an attenuated point light, an infinite viewer, emission, 240×240", "S4",
                5, LIGHTS_AND_VIEWER, (240, 240)),
    shader_test("S5 Phong: the handout's sphere, 500×500", "S5", 8, SPHERE_SCENE, (500, 500)),
    shader_test("S5 Phong: a coarse sphere (8 × 6) close up, under a close light, 256×256", "S5", 3, COARSE_CLOSE,
                (256, 256)),
    reshape_test("S6 reshape: the handout's square window", 3, width=500, height=500),
    reshape_test("S6 reshape: a wide window keeps the sphere round", 3, width=800, height=300),
    reshape_test("S6 reshape: a window minimised to height 0", 2, width=500, height=0),
    keys_test("S7 handle_key: q quits, s switches shading", 5,
              [["q", START], ["s", START], ["s", {**START, "shading": "phong"}], ["x", START]]),
    keys_test("S7 handle_key: + and - stop at 256 and 4", 3,
              [["+", START], ["+", {**START, "slices": 256, "stacks": 256}], ["-", START],
               ["-", {**START, "slices": 4, "stacks": 4}]]),
]
