"""Stage 3 public tests: students run these with ``cs451 grade hemicube``.

Points per task (the rubric in assignments/03-hemicube/README.md):
H1 15, H2 15, H3 10, H4 20, H5 25, H6 15; hidden.py holds part of each task's points.
Tables, views and projections are checked against the formulas they are defined by
(truth.py); rows against closed-form form factors (Howell C-11, C-14, the coaxial
disk) and a closed cube; the item buffer against the reference's image, drawn
with trusted views and projections so that only the shaders are judged.
"""
from __future__ import annotations

import json

import numpy as np

from cs451.compare import ImageTolerance
from cs451.grading.checks import all_of, array_close, image_matches
from cs451.grading.spec import Test
from cs451.patches import scene_polygons
from cs451.scene import BUNDLED_DIR, parse_scene

from autograder.hemicube import truth

#: The item buffer is exact integers; a few pixels on patch edges may differ between rasterisers.
IMAGE = ImageTolerance(threshold=0.016, max_bad_fraction=0.01, shift=1)
MATRIX_TOL = "entries within 1e-9 relative, 1e-12 absolute"
#: Time limits: generous for clear numpy code (the reference takes well under a second for each).
QUICK, RENDER = 10.0, 60.0

CORNELL = json.loads((BUNDLED_DIR / "cornell-box.json").read_text())
CORNELL_QUADS = scene_polygons(parse_scene(CORNELL, "cornell-box"))[0].tolist()


def _table_matches(key, closed_form):
    """A sub-check: the table ``key`` equals its closed form cell by cell, else the first bad cell."""
    def check(out, params):
        got, want = np.asarray(out[key]), closed_form(params["resolution"])
        if got.shape != want.shape:
            return f"shape {got.shape}, expected {want.shape}"
        if not np.allclose(got, want, rtol=1e-9, atol=1e-15):
            k = np.unravel_index(np.argmax(np.abs(got - want)), want.shape)
            return f"cell [row {k[0]}, column {k[1]}] is {got[k]:.6g}, expected {want[k]:.6g}"
        return None
    return check


def tables_test(name, points, resolution, hidden=False) -> Test:
    top = _table_matches("top", truth.delta_top)
    side = _table_matches("side", truth.delta_side)

    def closure(out, params):
        total = float(np.sum(out["top"]) + 4 * np.sum(out["side"]))
        r = params["resolution"]
        bound = 0.6 / r ** 2 + 1e-9     # the midpoint rule's error: 0.0021 at r = 16 (truth: exact cells sum to 1)
        return None if abs(total - 1) <= bound else f"top + 4 sides sum to {total:.6f}, expected 1 within {bound:.2g}"

    return Test(name, "H1", points, "tables", {"resolution": resolution},
                all_of([("top face", top), ("side face", side), ("sum", closure)]),
                "each cell within 1e-9 relative of its formula; the cells sum to 1 within 0.6/r²", expected="none",
                hidden=hidden, timeout=QUICK)


def views_test(name, points, center, normal, up, hidden=False) -> Test:
    return Test(name, "H2", points, "views", {"center": center, "normal": normal, "up": up},
                array_close("views", truth.views, rtol=1e-9, atol=1e-12, what="the five view matrices"),
                MATRIX_TOL, expected="none", hidden=hidden, timeout=QUICK)


def projections_test(name, points, near, far, hidden=False) -> Test:
    return Test(name, "H3", points, "projections", {"near": near, "far": far},
                array_close("projections", truth.projections, rtol=1e-9, atol=1e-12, what="the two projections"),
                MATRIX_TOL, expected="none", hidden=hidden, timeout=QUICK)


def item_buffer_test(name, points, quads, patch, resolution, hidden=False) -> Test:
    return Test(name, "H4", points, "item_buffer", {"quads": quads, "patch": patch, "resolution": resolution},
                image_matches(IMAGE), IMAGE.describe(), given="item_buffer_parts", hidden=hidden, timeout=RENDER)


def random_items(resolution: int, n: int, seed: int) -> dict:
    """Item buffers with random ids (0 = nothing) and the true tables: the row is then a known sum."""
    rng = np.random.default_rng(seed)
    r = resolution
    return {"top_items": rng.integers(0, n + 1, (r, r)).tolist(),
            "side_items": rng.integers(0, n + 1, (4, r // 2, r)).tolist(),
            "top_weights": truth.delta_top(r).tolist(), "side_weights": truth.delta_side(r).tolist(), "n_patches": n}


def row_sum_test(name, points, resolution, n, seed, hidden=False) -> Test:
    return Test(name, "H5", points, "row_from_items", random_items(resolution, n, seed),
                array_close("row", truth.row_from_items, rtol=1e-9, atol=1e-12, what="the row"),
                "each entry within 1e-9 relative of the sum of its cells' weights", expected="none", hidden=hidden,
                timeout=QUICK)


def known_row_test(name, task, points, quads, row, entries, want, rtol, resolution=128, proximity="none",
                   hidden=False, what="F", rotate=False) -> Test:
    """Row ``row`` of the form-factor matrix of ``quads``, summed over ``entries`` (lists of receivers), against ``want``."""
    def check(out, params):
        got = np.asarray(out["rows"], dtype=np.float64)
        if got.shape != (1, len(params["quads"])):
            return f"rows have shape {got.shape}, expected (1, {len(params['quads'])})"
        problems = []
        for label, js, value in zip(what if isinstance(what, list) else [what] * len(entries), entries, want):
            g = float(got[0, js].sum())
            if not abs(g - value) <= rtol * abs(value):
                problems.append(f"{label} = {g:.5f}, expected {value:.5f} (within {rtol:.1%})")
        return "; ".join(problems) or None

    return Test(name, task, points, "rows",
                {"quads": quads, "rows": [row], "resolution": resolution, "rotate": rotate, "proximity": proximity},
                all_of([("row", check)]), f"within {rtol:.1%} of the closed form", expected="none", hidden=hidden,
                timeout=RENDER)


def closure_test(name, points, k, resolution, hidden=False) -> Test:
    def check(out, params):
        sums = np.asarray(out["rows"], dtype=np.float64).sum(axis=1)
        bad = np.abs(sums - 1) > 0.005
        return None if not bad.any() else f"row sums {sums.min():.4f} .. {sums.max():.4f}, expected 1 within 0.5%"
    quads = truth.cube(k)
    return Test(name, "H5", points, "rows",
                {"quads": quads, "rows": list(range(len(quads))), "resolution": resolution, "rotate": True},
                all_of([("closure", check)]), "every row sums to 1 within 0.5%", expected="none", hidden=hidden,
                timeout=RENDER)


def contour_test(name, points, point, normal, polygon, hidden=False) -> Test:
    return Test(name, "H6", points, "contour", {"point": point, "normal": normal, "polygon": polygon},
                array_close("F", lambda p: np.array(truth.contour(p["point"], p["normal"], p["polygon"])),
                            rtol=1e-9, atol=1e-12, what="F"),
                "within 1e-9 relative of Lambert's formula", expected="none", hidden=hidden, timeout=QUICK)


UNIT_SQUARE_ABOVE = truth.square(0, 0, 1, 1, False)

TESTS = [
    tables_test("H1 delta form factors: resolution 8", 4, 8),
    tables_test("H1 delta form factors: resolution 64", 4, 64),
    views_test("H2 views: a floor patch at the origin", 4, [0, 0, 0], [0, 0, 1], [0, 1, 0]),
    views_test("H2 views: a wall patch in the Cornell box", 4, [556, 274.4, 279.6], [-1, 0, 0], [0, 0, 1]),
    projections_test("H3 projections: near 0.01, far 100", 5, 0.01, 100),
    item_buffer_test("H4 item buffer: the Cornell box from the floor, resolution 64", 8, CORNELL_QUADS, 0, 64),
    item_buffer_test("H4 item buffer: the Cornell box from the short block's top, resolution 128", 6, CORNELL_QUADS, 5, 128),
    row_sum_test("H5 row: random item buffers, resolution 16, 7 patches", 4, 16, 7, 1),
    known_row_test("H5 row: 0.2 squares one apart, rotated hemicube (Howell C-11)", "H5", 4,
                   truth.opposed_squares(0.2, 1.0), 0, [[1]], [truth.howell_c11(0.2, 0.2, 1.0)], 0.03, rotate=True),
    known_row_test("H5 row: a point under a coaxial disk (256-gon)", "H5", 4,
                   truth.small_patch_under_disk(0.01, 1.0, 1.0, 256), 0, [list(range(1, 257))],
                   [truth.polygon_disk(1.0, 1.0, 256)], 0.002),
    closure_test("H5 row: a closed cube, 2 × 2 patches a face, rows sum to 1", 3, 2, 64),
    contour_test("H6 point to polygon: a unit square one above a point", 4, [0.5, 0.5, 0], [0, 0, 1], UNIT_SQUARE_ABOVE),
    known_row_test("H6 proximity fix: unit squares one apart (Howell C-11, F = 0.19982)", "H6", 3,
                   truth.opposed_squares(1.0, 1.0), 0, [[1]], [truth.howell_c11(1, 1, 1)], 0.002, proximity="contour"),
    known_row_test("H6 proximity fix: unit squares at right angles (Howell C-14, F = 0.20004)", "H6", 3,
                   truth.perpendicular_squares(1.0, 1.0), 0, [[1]], [truth.howell_c14(1, 1, 1)], 0.002, proximity="contour"),
]
