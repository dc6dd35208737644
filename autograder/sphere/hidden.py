"""Stage 1 hidden tests: other sizes, materials and lights than the handout shows. Not shipped to students."""
from __future__ import annotations

from autograder.sphere.public import (START, SPHERE_SCENE, keys_test, look_at_test, mesh_test, model_view_test,
                                      perspective_test, reshape_test, scene_variant, shader_test)

SHINY_RED = scene_variant(
    materials={"red": {"ambient": [0.3, 0.05, 0.05], "diffuse": [0.8, 0.1, 0.1], "specular": [0.9, 0.9, 0.9],
                       "shininess": 12, "emission": [0.05, 0.0, 0.0]}},
    objects=[{"type": "sphere", "radius": 1, "material": "red", "slices": 24, "stacks": 18}])

TWO_LIGHTS = scene_variant(
    ambient=[0.05, 0.05, 0.1],
    lights=[{"type": "point", "position": [-4, 3, 2], "diffuse": [0.2, 0.4, 1.0], "specular": [1, 1, 1],
             "attenuation": [0.5, 0.05, 0.01]},
            {"type": "directional", "direction": [1, -0.5, -0.3], "diffuse": [1.0, 0.7, 0.3], "specular": [0.5, 0.5, 0.5],
             "ambient": [0.1, 0.1, 0.1]}],
    materials={"white": {"diffuse": [0.9, 0.9, 0.9], "specular": [0.6, 0.6, 0.6], "shininess": 80}},
    objects=[{"type": "sphere", "radius": 1, "material": "white"},
             {"type": "sphere", "radius": 0.5, "center": [1.4, 0.6, -1], "material": "white", "slices": 16, "stacks": 12}])

SHININESS_ZERO_RED = scene_variant(
    materials={"red": {"diffuse": [0.7, 0.2, 0.2], "specular": [0.3, 0.3, 0.3], "shininess": 0}},
    objects=[{"type": "sphere", "radius": 1, "material": "red", "slices": 20, "stacks": 14}])

FAR_VIEWER = scene_variant(
    camera={"eye": [2, 3, 7], "center": [0, 0, 0], "up": [0, 1, 0], "fovy": 35, "near": 1, "far": 50},
    options={"sphere": {"local_viewer": False}},
    materials={"green": {"diffuse": [0.3, 0.9, 0.5], "specular": [0.7, 0.7, 0.7], "shininess": 30}})

#: A robot arm as the red book draws one: each joint rotates, then moves to its segment's middle to draw it,
#: pushing around the segment's own scale so that it does not carry on down the arm.
ARM_CALLS = [["translate", -1, 0, 0]]
for angle, axis, length in ((40, (0, 0, 1), 2.0), (-65, (0, 0, 1), 1.5), (30, (1, 0.2, 0), 0.8)):
    ARM_CALLS += [["rotate", angle, *axis], ["translate", length / 2, 0, 0], ["push"], ["scale", length, 0.4, 0.3],
                  ["draw"], ["pop"], ["translate", length / 2, 0, 0]]
ARM_CALLS.append(["draw"])

#: A view matrix that is not a plain translation (gluLookAt((3, 4, 5), (1, -1, 0.5), y up), its entries as repr prints them).
OBLIQUE_VIEW = [[0.9138115486202572, 0.0, -0.4061384660534476, -0.7107423155935334],
                [-0.2893616759292293, 0.701702064128381, -0.6510637708407659, 1.3165956254779938],
                [0.2849881999516386, 0.7124704998790965, 0.6412234498911868, -6.910963848827236],
                [0.0, 0.0, 0.0, 1.0]]

TESTS = [
    perspective_test("S1 perspective: narrow, tall window", 4, fovy=12.5, aspect=0.4, near=0.01, far=1e4),
    look_at_test("S2 look_at: looking down with a tilted up vector", 4,
                 eye=[0, 10, 0.1], center=[0, 0, 0], up=[1, 1, 0]),
    model_view_test("S3 model_view_matrices: an arm of three joints, another view", 2, ARM_CALLS, view=OBLIQUE_VIEW),
    model_view_test("S3 model_view_matrices: a full turn, a mirror, nested pushes", 1, [
        ["push"], ["rotate", 360, 0, 1, 0], ["draw"], ["scale", -1, 1, 1], ["push"], ["rotate", 45, 1, 0, 0], ["draw"],
        ["pop"], ["translate", 0.5, 0.5, 0.5], ["draw"], ["pop"], ["rotate", 0, 3, 4, 0], ["draw"]]),
    mesh_test("S4 sphere_mesh: radius 0.5, 50 slices, 3 stacks", 4, radius=0.5, slices=50, stacks=3),
    shader_test("S5 Gouraud: shiny red sphere with emission, 256×256", "S5", 2, SHINY_RED, (256, 256)),
    shader_test("S5 Gouraud: two lights, attenuation, two spheres, 200×400", "S5", 2, TWO_LIGHTS, (200, 400)),
    shader_test("S6 Phong: shiny red sphere, 256×256", "S6", 1, SHINY_RED, (256, 256)),
    shader_test("S6 Phong: shininess 0, 180×240", "S6", 1, SHININESS_ZERO_RED, (180, 240)),
    shader_test("S6 Phong: infinite viewer, oblique camera, 300×200", "S6", 2, FAR_VIEWER, (300, 200)),
    reshape_test("S7 reshape: a minimised window (height 0), another width", 1, width=640, height=0),
    reshape_test("S7 reshape: a tall, narrow window", 1, width=240, height=800),
    keys_test("S8 handle_key: Q, escape, + and - within their limits", 2, presses=[
        ["Q", START], ["escape", {**START, "shading": "phong"}], ["+", START], ["+", {**START, "slices": 200, "stacks": 256}],
        ["-", START], ["-", {**START, "slices": 5, "stacks": 4}]]),
]
