"""R6 in the engine: a change of colours or lights solved again renders no hemicube (notes §2.2)."""
from __future__ import annotations

import numpy as np

from cs451.impl import load_impl, resolve_impl
from cs451.scene import load_scene
from cs451.stages import radiosity as R


def _solve(ref, patches, reflectance, emission, known, rows=None):
    rows = rows or R.hemicube_formfactors(patches.quads, 32, "none", batch=R.ROWS_PER_BATCH)
    before = rows.counters["hemicubes_rendered"]
    sol = R.solve_progressive(ref, rows, patches.areas, reflectance, emission, 1e-4, 0, 1.0, use_ambient=False,
                              known=known)
    return sol, rows.counters["hemicubes_rendered"] - before, rows


def test01_a_recoloured_light_and_a_repainted_wall_are_solved_with_the_rows_already_known():
    ref = load_impl(resolve_impl("reference", "radiosity"), "radiosity")
    patches = R.make_patches(load_scene("cornell-box"), ref, 200.0)
    known: dict = {}
    first, hemicubes, rows = _solve(ref, patches, patches.reflectance, patches.emission, known)
    assert hemicubes > 0 and set(known) == set(first.order)
    painted = patches.reflectance[:, ::-1].copy()
    fresh, fresh_hemicubes, _ = _solve(ref, patches, painted, patches.emission * [1.0, 0.5, 0.2], None)
    again, again_hemicubes, _ = _solve(ref, patches, painted, patches.emission * [1.0, 0.5, 0.2], known, rows)
    assert fresh_hemicubes > 0 and again_hemicubes == 0
    assert again.counters["rows_requested"] == len(set(again.order) - set(first.order))
    assert np.allclose(again.radiosity, fresh.radiosity, rtol=1e-4, atol=1e-9)
    assert not np.allclose(again.radiosity, first.radiosity, rtol=1e-2)      # the change did change the answer


def test02_a_patch_that_shoots_for_the_first_time_has_its_row_computed_once_and_kept():
    ref = load_impl(resolve_impl("reference", "radiosity"), "radiosity")
    patches = R.make_patches(load_scene("cornell-box"), ref, 200.0)
    black = patches.reflectance.copy()
    dark = int(np.argmin(np.where(patches.emission.sum(axis=1) > 0, np.inf, black.sum(axis=1))))
    black[dark] = 0.0
    known: dict = {}
    first, _, rows = _solve(ref, patches, black, patches.emission, known)
    assert dark not in known
    white = black.copy()
    white[dark] = 0.9
    again, hemicubes, _ = _solve(ref, patches, white, patches.emission, known, rows)
    assert dark in again.order and dark in known
    assert again.counters["rows_requested"] == len(set(again.order) - set(first.order)) >= 1


def test03_the_check_gives_part_marks_and_says_why_when_the_loop_itself_is_wrong():
    """R6's check on answers a student might give: R3's order with wrong values, a wrong order, the right answer."""
    from autograder.radiosity import checks, public, truth
    test = next(t for t in public.TESTS if t.task == "R6")
    p, want = test.params, truth.resolved(test.params)
    right = {**want, "known_after": np.array(sorted(set(p["known_rows"]) | set(want["rows_asked"].tolist()))),
             "known_rows_right": np.array(True)}
    assert checks.solve_again_matches(right, want, p).fraction == 1.0
    values = checks.solve_again_matches({**right, "radiosity": want["radiosity"] * 2}, want, p)
    assert values.fraction == 0.25 and "R6 solves as R3 does" in values.message
    order = checks.solve_again_matches({**right, "order": want["order"][::-1]}, want, p)
    assert order.fraction == 0.0 and "shot order differs" in order.message
