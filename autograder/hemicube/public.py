"""Stage 3 public tests: students run these with ``cs451 grade hemicube``.

Points per task (the rubric in assignments/03-hemicube/README.md):
H1 15, H2 15, H3 10, H4 20, H5 25, H6 15; hidden.py holds part of each task's points.
Every case a hidden test checks (a rotated up vector, a back face, patches no cell sees, a
repeated corner) has a public test too.
Tables, views and projections are checked against the formulas they are defined by
(truths.py); rows against closed-form form factors (Howell C-11, C-14, the coaxial
disk) and a closed cube; the item buffer against the reference's image, drawn
with trusted views and projections so that only the shaders are judged.
"""
from __future__ import annotations

import json

import numpy as np

from cs451.compare import ImageTolerance
from cs451.grading.checks import all_of, array_close, image_matches, sub
from cs451.grading.spec import Test, truth, variant
from cs451.stages.hemicube import tolerances as TOL
from cs451.patches import scene_polygons
from cs451.scene import BUNDLED_DIR, parse_scene

from autograder.hemicube import checks, truth as truths, variants

#: The item buffer is exact integers; a few pixels on patch edges may differ between rasterisers.
IMAGE = ImageTolerance()  # the kit's margin, measured in docs/tolerances.md
MATRIX_TOL = f"entries within {TOL.FLOAT64_RTOL} relative, {TOL.FLOAT64_ATOL} absolute"
#: how the closed-form tests compare
FLOAT64 = dict(rtol=TOL.FLOAT64_RTOL, atol=TOL.FLOAT64_ATOL)
#: Time limits: generous for clear numpy code (the reference takes well under a second for each).
QUICK, RENDER = 10.0, 60.0

CORNELL = json.loads((BUNDLED_DIR / "cornell-box.json").read_text())
CORNELL_QUADS = scene_polygons(parse_scene(CORNELL, "cornell-box"))[0].tolist()


def tables_test(name, points, resolution) -> Test:
    return Test(name, "H1", points, "tables", {"resolution": resolution},
                all_of([("top face", sub(checks.table_cells, key="top")), ("side face", sub(checks.table_cells, key="side")),
                        ("sum", sub(checks.table_sum))], earn_with=["top face", "side face"]),
                f"each cell within {TOL.FLOAT64_RTOL} relative of its formula; the cells sum to 1 within 0.6/r²", expected="none",
                truth=truth(truths.tables), timeout=QUICK, vary=variant(variants.tables))


def tetrahedron_test(name, points, resolution) -> Test:
    return Test(name, "H7", points, "tetrahedron", {"resolution": resolution},
                all_of([("the face", sub(checks.table_cells, key="face")), ("three faces sum to 1", sub(checks.tetrahedron_sum))],
                       earn_with=["the face"]),
                f"each cell within {TOL.FLOAT64_RTOL} relative of cos θ·cos θ'/(πr²)·ΔA; three faces sum to 1 within 0.25/r²",
                expected="none", truth=truth(truths.tetrahedron_face), timeout=QUICK, vary=variant(variants.tetrahedron))


def views_test(name, points, center, normal, up) -> Test:
    return Test(name, "H2", points, "views", {"center": center, "normal": normal, "up": up},
                array_close("views", **FLOAT64, what="the five view matrices", plural=True),
                MATRIX_TOL, expected="none", truth=truth(truths.views), timeout=QUICK, vary=variant(variants.views))


def projections_test(name, points, near, far) -> Test:
    return Test(name, "H3", points, "projections", {"near": near, "far": far},
                array_close("projections", **FLOAT64, what="the two projections", plural=True),
                MATRIX_TOL, expected="none", truth=truth(truths.projections), timeout=QUICK,
                vary=variant(variants.projections))


def item_buffer_test(name, points, quads, patch, resolution) -> Test:
    return Test(name, "H4", points, "item_buffer", {"quads": quads, "patch": patch, "resolution": resolution},
                image_matches(IMAGE), IMAGE.describe(), given="item_buffer_parts", timeout=RENDER,
                vary=variant(variants.item_buffer))


def random_items(resolution: int, n: int, seed: int, unseen: int = 0) -> dict:
    """Item buffers with random ids (0 = nothing) and the true tables: the row is then a known sum.

    ``unseen``: the last this many patches appear in no cell (their entries must still be there, as 0).
    """
    rng = np.random.default_rng(seed)
    r = resolution
    return {"top_items": rng.integers(0, n + 1 - unseen, (r, r)).tolist(),
            "side_items": rng.integers(0, n + 1 - unseen, (4, r // 2, r)).tolist(),
            "top_weights": truths.delta_top(r).tolist(), "side_weights": truths.delta_side(r).tolist(), "n_patches": n}


def row_sum_test(name, points, resolution, n, seed, unseen=0) -> Test:
    return Test(name, "H5", points, "row_from_items", random_items(resolution, n, seed, unseen),
                array_close("row", **FLOAT64, what="the row"),
                f"each entry within {TOL.FLOAT64_RTOL} relative of the sum of its cells' weights", expected="none",
                truth=truth(truths.row_from_items), timeout=QUICK, vary=variant(variants.row_from_items, unseen=unseen > 0))


#: Row tests judge one task each: H5 sums the reference's item buffers (its H1 to H4), H6 fixes the reference's rows.
ROW_PROBE = {"H5": "rows_from_buffers", "H6": "proximity_rows"}


def known_row_test(name, task, points, quads, row, entries, want, rtol, resolution=128, what="F", rotate=False) -> Test:
    """Row ``row`` of the form-factor matrix of ``quads``, summed over ``entries`` (lists of receivers), against ``want``.

    H5: the submission sums the trusted item buffers of the row's hemicube; H6: the submission's proximity
    fix runs on the trusted hemicube row. Either way no other task of the submission runs.
    """
    labels = what if isinstance(what, list) else [what] * len(entries)
    kind = "disk" if len(quads) > 2 else "c14" if all(v[0] == 0 for v in quads[1]) else "c11"   # the fresh case's kind
    return Test(name, task, points, ROW_PROBE[task],
                {"quads": quads, "rows": [row], "resolution": resolution, "rotate": rotate},
                all_of([("row", sub(checks.known_row, entries=entries, want=[float(w) for w in want], labels=labels,
                                    rtol=rtol))]),
                f"within {rtol:.1%} of the closed form", expected="none", given="hemicube_buffers", timeout=RENDER,
                vary=variant(variants.known_row, kind=kind, task=task, rtol=rtol))


def closure_test(name, points, k, resolution) -> Test:
    quads = truths.cube(k)
    return Test(name, "H5", points, ROW_PROBE["H5"],
                {"quads": quads, "rows": list(range(len(quads))), "resolution": resolution, "rotate": True},
                all_of([("closure", sub(checks.row_closure)), ("the reference's rows", sub(checks.rows_like_reference))],
                       earn_with=["the reference's rows"]),
                f"every row sums to 1 within {TOL.CLOSURE:.1%}, entries within {TOL.ROW_ATOL:g} of the reference's hemicubes",
                given="hemicube_buffers", timeout=RENDER, vary=variant(variants.closure))


def contour_test(name, points, point, normal, polygon) -> Test:
    return Test(name, "H6", points, "contour", {"point": point, "normal": normal, "polygon": polygon},
                array_close("F", **FLOAT64, what="F"),
                f"within {TOL.FLOAT64_RTOL} relative of Lambert's formula", expected="none", truth=truth(truths.contour_value),
                timeout=QUICK, vary=variant(variants.contour))


UNIT_SQUARE_ABOVE = truths.square(0, 0, 1, 1, False)

#: A wall patch whose hemicube is turned about its normal (the kit's up vector with rotate=True is not an axis).
_turn = np.radians(35.0)
ROTATED_WALL = dict(center=[0.0, 1.5, 2.0], normal=[0.0, -1.0, 0.0],
                    up=[float(np.cos(_turn)), 0.0, float(np.sin(_turn))])

#: A small square above the shooter turned away from it (its back faces down), under a large one facing down:
#: the back face must hide the large square behind it and receive nothing.
BACK_FACE = [truths.square(0, 0, 0, 1, True), truths.square(0.2, 0.2, 0.5, 0.6, True),
             truths.square(-1, -1, 1.5, 3, False)]

#: A triangle stored as a quad: its last corner repeats the third (an edge of zero length).
TRIANGLE_AS_QUAD = [[-0.3, 0.2, 1.2], [0.8, -0.1, 0.9], [0.1, 0.7, 1.6], [0.1, 0.7, 1.6]]

TESTS = [
    tables_test("H1 delta form factors: resolution 8", 4, 8),
    tables_test("H1 delta form factors: resolution 64", 4, 64),
    views_test("H2 views: a floor patch at the origin", 4, [0, 0, 0], [0, 0, 1], [0, 1, 0]),
    views_test("H2 views: a wall patch in the Cornell box", 4, [556, 274.4, 279.6], [-1, 0, 0], [0, 0, 1]),
    views_test("H2 views: a hemicube turned 35° about its normal (up not an axis)", 3, **ROTATED_WALL),
    projections_test("H3 projections: near 0.01, far 100", 5, 0.01, 100),
    item_buffer_test("H4 item buffer: the Cornell box from the floor, resolution 64", 6, CORNELL_QUADS, 0, 64),
    item_buffer_test("H4 item buffer: the Cornell box from the short block's top, resolution 128", 5, CORNELL_QUADS, 5, 128),
    item_buffer_test("H4 item buffer: a patch seen from behind hides the one behind it, resolution 64", 3, BACK_FACE, 0, 64),
    row_sum_test("H5 row: random item buffers, resolution 16, 7 patches", 4, 16, 7, 1),
    row_sum_test("H5 row: random item buffers, resolution 4, 60 patches (the last 10 never seen)", 2, 4, 60, 4,
                 unseen=10),
    known_row_test("H5 row: 0.2 squares one apart, rotated hemicube (Howell C-11)", "H5", 4,
                   truths.opposed_squares(0.2, 1.0), 0, [[1]], [truths.howell_c11(0.2, 0.2, 1.0)], TOL.SMALL_SQUARES, rotate=True),
    known_row_test("H5 row: a point under a coaxial disk (256-gon)", "H5", 4,
                   truths.small_patch_under_disk(0.01, 1.0, 1.0, 256), 0, [list(range(1, 257))],
                   [truths.polygon_disk(1.0, 1.0, 256)], TOL.KNOWN_ROW),
    closure_test("H5 row: a closed cube, 2 × 2 patches a face, rows sum to 1", 3, 2, 64),
    contour_test("H6 point to polygon: a unit square one above a point", 4, [0.5, 0.5, 0], [0, 0, 1], UNIT_SQUARE_ABOVE),
    contour_test("H6 point to polygon: a triangle stored as a quad (repeated corner)", 2, [0.0, 0.1, 0.0], [0, 0, 1],
                 TRIANGLE_AS_QUAD),
    known_row_test("H6 proximity fix: unit squares one apart (Howell C-11, F = 0.19982)", "H6", 3,
                   truths.opposed_squares(1.0, 1.0), 0, [[1]], [truths.howell_c11(1, 1, 1)], TOL.KNOWN_ROW),
    known_row_test("H6 proximity fix: unit squares at right angles (Howell C-14, F = 0.20004)", "H6", 3,
                   truths.perpendicular_squares(1.0, 1.0), 0, [[1]], [truths.howell_c14(1, 1, 1)], TOL.KNOWN_ROW),
    tetrahedron_test("H7 cubic tetrahedron (optional): resolution 8", 3, 8),
    tetrahedron_test("H7 cubic tetrahedron (optional): resolution 64", 2, 64),
]
