"""Stage 4 hidden tests: not shipped to students; run by the instructor's grader (``--public-only`` skips them)."""
from __future__ import annotations

import numpy as np

from autograder.radiosity import truth as truths
from autograder.radiosity.public import (fan_patches, far_grid, solve_again_test, CORNELL, ROOM, by_hand_test, furnace_test, lists, random_system, render_test,
                                         scene_quads, scene_solve_test, scene_variant, shoot_test, subdivide_test,
                                         vertex_test, ambient_test)

RANDOM = random_system(8, seed=11)
CLOSED = random_system(7, seed=4, closed=True)
_rng = np.random.default_rng(21)
_B = _rng.uniform(0, 3, (8, 3))
_dB = _B * _rng.uniform(0, 1, (8, 3))


def _triangle_patches():
    tri = np.array([[[0, 0, 0], [2, 0, 0], [0, 2, 0], [0, 2, 0]], [[0, 0, 0], [0, 2, 0], [0, 2, 2], [0, 0, 2]]], float)
    patches, parent = truths.subdivide_by_hand(tri, 0.7)
    return lists(patches), parent.tolist(), lists(np.random.default_rng(2).uniform(0, 1, (len(patches), 3)))


BLUE_LIGHT = scene_variant(CORNELL, lights=[{**CORNELL["lights"][0], "radiance": [4.0, 8.0, 17.0]}])
SMALL_ROOM = scene_variant(ROOM, radiosity={"patch_size": 1.0})

TESTS = [
    subdivide_test("R1 subdivide: a negative max_edge keeps the quads", 1, scene_quads("cornell-box", 5), -1.0),
    subdivide_test("R1 subdivide: the room's long walls at 0.7 m", 3, scene_quads("room", 6), 0.7),
    shoot_test("R2 shoot: a random reciprocal system, patch 3", 5, RANDOM, 3, radiosity=lists(_B), unshot=lists(_dB)),
    by_hand_test("R3 progressive_refinement: a closed random system, overshooting 1.5", 3, CLOSED, 100_000,
                 tolerance=1e-6, overshoot=1.5),
    furnace_test("R3 progressive_refinement: the furnace, ρ = 0.99, overshooting 1.5", 2, 0.99, 1e-4, overshoot=1.5),
    scene_solve_test("R3 progressive_refinement: a coarse room converges to the direct solve", 2, SMALL_ROOM, 1.0),
    ambient_test("R4 ambient_term: a random system", 2, RANDOM["areas"], RANDOM["reflectance"], lists(_dB)),
    vertex_test("R5 vertex_colors: triangles and a quad", 1, *_triangle_patches()),
    vertex_test("R5 vertex_colors: an octagon fanned into triangles", 1, *fan_patches(8, 2.0, 20.0),
                lists(np.random.default_rng(12).uniform(0, 1, (6, 3))), "fan"),
    render_test("R5 render: the Cornell box under a blue light", 2, BLUE_LIGHT, (96, 96), 120.0),
    vertex_test("R5 vertex_colors: a square 3 wide cut 3 × 3, -2^37 from the origin along y", 1,
                *far_grid(3.0, 3, -2.0 ** 37, 1, np.random.default_rng(15)), "far"),
    render_test("R5 render: a coarse room", 2, SMALL_ROOM, (120, 90), 1.0),
    solve_again_test("R6 solve_again: a closed system recoloured, every row known: none computed", 1,
                 random_system(8, seed=31, closed=True), "all"),
    solve_again_test("R6 solve_again: nothing known, overshooting 1.7: each shooter's row computed once", 1,
                 random_system(6, seed=32), "none", overshoot=1.7),
]
