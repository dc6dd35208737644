"""Stage 3 hidden tests: other resolutions, orientations and configurations than the public ones. Not shipped to students."""
from __future__ import annotations

import numpy as np

from cs451.stages.hemicube import tolerances as TOL

from autograder.hemicube import truth as truths
from autograder.hemicube.public import (CORNELL_QUADS, closure_test, contour_test, item_buffer_test, known_row_test,
                                        projections_test, row_sum_test, tables_test, views_test)

_n = np.array([1.0, 2.0, 2.0]) / 3
_u = np.cross(_n, [0, 0, 1.0])
_u /= np.linalg.norm(_u)
TILTED = dict(center=[0.3, -1.2, 4.0], normal=_n.tolist(), up=_u.tolist())

_tri = [[0.2, -0.3, 1.5], [-0.4, 0.5, 0.8], [0.6, 0.9, 2.0]]

#: A tilted parallelogram turned away from the shooter, in front of a wall that faces it.
TILTED_BACK_FACE = [truths.square(0, 0, 0, 1, True), [[0.1, 0.3, 0.4], [0.9, 0.1, 0.6], [0.8, 0.8, 0.9], [0.0, 1.0, 0.7]],
                    truths.square(-2, -2, 2.0, 5, False)]

TESTS = [
    tables_test("H1 delta form factors: resolution 2", 3, 2),
    tables_test("H1 delta form factors: resolution 250", 4, 250),
    views_test("H2 views: the light, facing down", 2, [278, 548.7, 279.5], [0, -1, 0], [1, 0, 0]),
    views_test("H2 views: a tilted patch", 2, **TILTED),
    projections_test("H3 projections: near 1e-4, far 3000", 5, 1e-4, 3000),
    item_buffer_test("H4 item buffer: the Cornell box from the tall block's side, resolution 64", 4, CORNELL_QUADS, 12, 64),
    item_buffer_test("H4 item buffer: a tilted patch seen from behind, resolution 32", 2, TILTED_BACK_FACE, 0, 32),
    row_sum_test("H5 row: random item buffers, resolution 32, one patch", 2, 32, 1, 2),
    row_sum_test("H5 row: random item buffers, resolution 8, 300 patches (some never seen)", 2, 8, 300, 3),
    known_row_test("H5 row: a point under a wide, low disk (64-gon)", "H5", 2,
                   truths.small_patch_under_disk(0.01, 3.0, 0.7, 64), 0, [list(range(1, 65))],
                   [truths.polygon_disk(3.0, 0.7, 64)], TOL.KNOWN_ROW),
    closure_test("H5 row: a closed cube, 3 × 3 patches a face, rotated hemicubes", 2, 3, 48),
    contour_test("H6 point to polygon: a tilted triangle", 1, [0.1, 0.1, 0.0], [0, 0, 1], _tri),
    contour_test("H6 point to polygon: a triangle stored as a quad (repeated corner)", 1, [0.1, 0.1, 0.0], [0, 0, 1],
                 _tri + [_tri[-1]]),
    known_row_test("H6 proximity fix: a 1 × 0.5 floor and a 1 × 2 wall sharing an edge (Howell C-14)", "H6", 1,
                   [truths.square(0, 0, 0, 1, True)[:1] + [[0.5, 0, 0], [0.5, 1, 0], [0, 1, 0]],
                    [[0, 0, 0], [0, 1, 0], [0, 1, 2], [0, 0, 2]]],
                   0, [[1]], [truths.howell_c14(1.0, 0.5, 2.0)], TOL.SHARED_EDGE),
]
