"""Stage 1 public tests: students run these with ``cs451 grade sphere``.

Points per task (the rubric in assignments/01-sphere/README.md):
S1 10, S2 10, S3 10, S4 15, S5 20, S6 15, S7 10, S8 10; hidden.py holds the rest of each task's points.
Every case a hidden test checks (directional and attenuated lights, an infinite viewer, a minimised
window, the limits of + and -) has a public test too, and a coarse sphere tells a Phong shader that
renormalises the interpolated normal from one that does not.
"""
from __future__ import annotations

import copy
import json

from cs451.compare import ImageTolerance
from cs451.grading.checks import all_of, array_close, image_matches, sub
from cs451.grading.spec import Test, truth, variant

from cs451.scene import BUNDLED_DIR, load_scene
from cs451.stages.sphere import drawing_calls
from cs451.stages.sphere import tolerances as TOL

from autograder.sphere import checks, truth as truths, variants

#: Tolerance of the image tests: the measured margin is in docs/tolerances.md.
IMAGE = ImageTolerance()  # the kit's margin, measured in docs/tolerances.md
MATRIX_TOL = f"entries within {TOL.MATRIX_RTOL} relative, {TOL.MATRIX_ATOL} absolute"
#: the matrix tests' comparison
MATRIX = dict(rtol=TOL.MATRIX_RTOL, atol=TOL.MATRIX_ATOL)
#: Time limits per test: generous for clear numpy code (the reference takes under 0.2 s for each).
QUICK, RENDER = 10.0, 30.0

SPHERE_SCENE = json.loads((BUNDLED_DIR / "sphere.json").read_text())


def scene_variant(**changes) -> dict:
    """The handout's scene with top-level fields replaced (a deep copy)."""
    scene = copy.deepcopy(SPHERE_SCENE)
    scene.update(copy.deepcopy(changes))
    return scene


def stereo_test(name, points, **params) -> Test:
    return Test(name, "S9", points, "stereo_projection", params, array_close("matrices", what="the two matrices", **MATRIX),
                MATRIX_TOL, expected="none", truth=truth(truths.stereo_pair), timeout=QUICK,
                vary=variant(variants.stereo_pair))


def parallax_test(name, points, **params) -> Test:
    return Test(name, "S9", points, "stereo_projection", params,
                all_of([("zero parallax on the convergence plane", sub(checks.stereo_zero_parallax))]),
                f"both images of a point on the convergence plane within {TOL.MATRIX_RTOL} (NDC)",
                expected="none", timeout=QUICK, vary=variant(variants.stereo_pair))


def perspective_test(name, points, **params) -> Test:
    return Test(name, "S1", points, "perspective", params, array_close("matrix", what="the matrix", **MATRIX),
                MATRIX_TOL, expected="none", truth=truth(truths.perspective), timeout=QUICK,
                vary=variant(variants.perspective))


def look_at_test(name, points, **params) -> Test:
    return Test(name, "S2", points, "look_at", params, array_close("matrix", what="the matrix", **MATRIX),
                MATRIX_TOL, expected="none", truth=truth(truths.look_at), timeout=QUICK,
                vary=variant(variants.look_at))


MESH_CHECKS = all_of([("vertex and triangle counts", sub(checks.mesh_counts)),
                      ("unit outward normals", sub(checks.mesh_normals)),
                      ("glutSolidSphere's vertices", sub(checks.mesh_vertices)),
                      ("closed, counter-clockwise surface", sub(checks.mesh_closed)),
                      ("no zero-area triangles", sub(checks.mesh_no_degenerate))],
                     require=["vertex and triangle counts"])


#: The handout's view matrix, gluLookAt((0, 0, 8), origin, y up): a translation by -8 along z.
HANDOUT_VIEW = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, -8.0], [0.0, 0.0, 0.0, 1.0]]


def model_view_test(name, points, calls, view=HANDOUT_VIEW) -> Test:
    return Test(name, "S3", points, "model_view_matrices", {"view": view, "calls": calls},
                array_close("matrices", what="the matrices at the draws", plural=True, **MATRIX), MATRIX_TOL, expected="none",
                truth=truth(truths.model_view_matrices), timeout=QUICK, vary=variant(variants.model_view_matrices))


def scene_calls(name: str) -> list:
    """The calls with which the kit places a bundled scene's spheres (``drawing_calls``), as lists."""
    return [list(c) for c in drawing_calls(load_scene(name))]


def mesh_test(name, points, **params) -> Test:
    return Test(name, "S4", points, "sphere_mesh", params, MESH_CHECKS,
                f"positions within {TOL.POSITION}·radius of freeglut's; normals unit within {TOL.UNIT}", expected="none",
                truth=truth(truths.sphere_mesh), timeout=QUICK, vary=variant(variants.sphere_mesh))


def shader_test(name, task, points, scene, size) -> Test:
    shading = "gouraud" if task == "S5" else "phong"
    return Test(name, task, points, "render", {"scene": scene, "size": list(size), "shading": shading},
                image_matches(IMAGE), IMAGE.describe(), given="parts", timeout=RENDER, vary=variant(variants.render))


RESHAPE_CHECKS = all_of([("viewport covers the window", sub(checks.reshape_viewport)),
                         ("aspect ratio kept", sub(checks.reshape_aspect)),
                         ("vertical field of view kept", sub(checks.reshape_fovy))],
                        earn_with=["viewport covers the window", "vertical field of view kept"])


def reshape_test(name, points, **params) -> Test:
    params.setdefault("camera", SPHERE_SCENE["camera"])
    return Test(name, "S7", points, "reshape", params, RESHAPE_CHECKS,
                f"viewport exact; aspect and field of view within {TOL.PROJECTION} relative", expected="none",
                given="reshape_parts", truth=truth(truths.reshape), timeout=QUICK, vary=variant(variants.reshape))


def keys_test(name, points, presses) -> Test:
    """One sub-check per press that changes the state; presses that change nothing are checked but earn nothing alone."""
    changing = [i for i, (key, state) in enumerate(presses) if truths.key_truth(key, state) != state]
    parts = [(f"press {i + 1} ({key!r})", sub(checks.key_press, index=i)) for i, (key, _) in enumerate(presses)]
    return Test(name, "S8", points, "handle_key", {"presses": presses},
                all_of(parts, earn_with=[parts[i][0] for i in changing]), "exact", expected="none",
                truth=truth(truths.keys), timeout=QUICK, vary=variant(variants.handle_key))


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
#: far shorter than 1, so a Phong shader that does not renormalise it (handout §S6) is visibly darker.
COARSE_CLOSE = scene_variant(
    camera={"eye": [0, 0, 3.5], "center": [0, 0, 0], "up": [0, 1, 0], "fovy": 45, "near": 0.5, "far": 20},
    lights=[{"type": "point", "position": [0.5, 0.7, 2.5], "diffuse": [0.9, 0.9, 0.9], "specular": [0.5, 0.5, 0.5]}],
    materials={"green": {"diffuse": [0.3, 0.9, 0.5], "specular": [0.6, 0.6, 0.6], "shininess": 30}},
    objects=[{"type": "sphere", "radius": 1, "material": "green", "slices": 8, "stacks": 6}])

#: An infinite viewer (local_viewer false) close to the sphere with a wide view: the half vector, built from
#: (0, 0, 1) instead of the direction to each point, moves the highlight (OpenGL 2.1 §2.14.1).
CLOSE_INFINITE_VIEWER = scene_variant(
    camera={"eye": [0, 0, 2.6], "center": [0, 0, 0], "up": [0, 1, 0], "fovy": 60, "near": 0.5, "far": 20},
    lights=[{"type": "directional", "direction": [-1, -0.7, -0.6], "diffuse": [0.8, 0.8, 0.8], "specular": [1, 1, 1]}],
    materials={"green": {"diffuse": [0.2, 0.5, 0.3], "specular": [0.9, 0.9, 0.9], "shininess": 20}},
    options={"sphere": {"local_viewer": False}})

#: Shininess 0: (n·h)^0 is 1 wherever the light reaches (n·l > 0), n·h = 0 included, where GLSL's pow(0, 0) is
#: undefined; the specular colour is added there in full.
SHININESS_ZERO = scene_variant(
    materials={"green": {"diffuse": [0.3, 0.6, 0.4], "specular": [0.35, 0.3, 0.25], "shininess": 0}})

TESTS = [
    perspective_test("S1 perspective: the handout's 30°, square window", 3, fovy=30, aspect=1.0, near=2, far=100),
    perspective_test("S1 perspective: 60°, wide window", 3, fovy=60, aspect=16 / 9, near=0.5, far=50),
    look_at_test("S2 look_at: the handout's camera", 3, eye=[0, 0, 8], center=[0, 0, 0], up=[0, 1, 0]),
    look_at_test("S2 look_at: an oblique camera", 3, eye=[3, 4, 5], center=[1, -1, 0.5], up=[0, 1, 0]),
    model_view_test("S3 model_view_matrices: the handout's sphere, one draw on the view", 1, [["draw"]]),
    model_view_test("S3 model_view_matrices: glTranslate", 1, [["translate", 1.5, -2, 0.25], ["draw"]]),
    model_view_test("S3 model_view_matrices: glRotate about an axis that is not unit length", 1,
                    [["rotate", -75, 1, 2, 2], ["draw"]]),
    model_view_test("S3 model_view_matrices: glScale", 1, [["scale", 2, 0.5, -1], ["draw"]]),
    model_view_test("S3 model_view_matrices: the last call is the first applied", 1,
                    [["translate", 2, 0, 0], ["rotate", 90, 0, 1, 0], ["scale", 1, 3, 1], ["draw"]]),
    model_view_test("S3 model_view_matrices: push and pop", 1,
                    [["rotate", 30, 0, 0, 1], ["push"], ["translate", 0, 2, 0], ["draw"], ["push"], ["scale", 2, 2, 2],
                     ["draw"], ["pop"], ["draw"], ["pop"], ["draw"]]),
    model_view_test("S3 model_view_matrices: the orrery's calls", 1, scene_calls("orrery")),
    mesh_test("S4 sphere_mesh: glutSolidSphere(1, 32, 32)", 6, radius=1.0, slices=32, stacks=32),
    mesh_test("S4 sphere_mesh: a coarse sphere, radius 2, 8 slices, 5 stacks", 5, radius=2.0, slices=8, stacks=5),
    shader_test("S5 Gouraud: the handout's sphere, 500×500", "S5", 7, SPHERE_SCENE, (500, 500)),
    shader_test("S5 Gouraud: a 320×240 window", "S5", 3, SPHERE_SCENE, (320, 240)),
    shader_test("S5 Gouraud: a directional and an attenuated point light, an infinite viewer, emission, 240×240", "S5",
                4, LIGHTS_AND_VIEWER, (240, 240)),
    shader_test("S6 Phong: the handout's sphere, 500×500", "S6", 6, SPHERE_SCENE, (500, 500)),
    shader_test("S5 Gouraud: shininess 0, the specular colour wherever the light reaches, 200×200", "S5", 2,
                SHININESS_ZERO, (200, 200)),
    shader_test("S6 Phong: a coarse sphere (8 × 6) close up, under a close light, 256×256", "S6", 3, COARSE_CLOSE,
                (256, 256)),
    shader_test("S6 Phong: an infinite viewer (local_viewer false) close up, wide view, 240×240", "S6", 2,
                CLOSE_INFINITE_VIEWER, (240, 240)),
    reshape_test("S7 reshape: the handout's square window", 3, width=500, height=500),
    reshape_test("S7 reshape: a wide window keeps the sphere round", 3, width=800, height=300),
    reshape_test("S7 reshape: a window minimised to height 0", 2, width=500, height=0),
    keys_test("S8 handle_key: q quits, s switches shading", 5,
              [["q", START], ["s", START], ["s", {**START, "shading": "phong"}], ["x", START]]),
    keys_test("S8 handle_key: + and - stop at 256 and 4", 3,
              [["+", START], ["+", {**START, "slices": 256, "stacks": 256}], ["-", START],
               ["-", {**START, "slices": 4, "stacks": 4}]]),
    stereo_test("S9 stereo_projection (optional): both eyes against pyrender's off-centre camera", 3, fovy=40,
                aspect=1.5, near=0.5, far=50, separation=0.3, convergence=4.0),
    parallax_test("S9 stereo_projection (optional): the two images agree on the convergence plane", 2, fovy=60,
                  aspect=1.0, near=1.0, far=100, separation=0.065, convergence=2.5),
]
