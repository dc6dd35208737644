"""Stage 4's checks: they compare a submission's arrays with the truths' (``expected``) and compute no answer.

Shipped to students with the public tests. The shooting loop is judged by what
it must produce *and* by how it got there: a converged answer alone (which a
direct solve also gives) earns nothing unless the number of shots is that of a
progressive refinement, as the reference's run of the same test counts them.
"""
from __future__ import annotations

import numpy as np

from cs451.grading.checks import output
from cs451.grading.spec import Verdict
from cs451.stages.radiosity import tolerances as TOL
from cs451.patches import patch_areas, patch_normals


def _patches(out, p):
    patches = output(out, "patches", (None, 4, 3), "patches")
    parent = output(out, "parent", (len(patches),), "parent")
    if len(parent) and (parent.min() < 0 or parent.max() >= len(p["quads"]) or not np.all(parent == np.round(parent))):
        raise ValueError(f"parent must hold indices of the {len(p['quads'])} quads")
    return patches, parent.astype(np.int64)


def subdivide_exact(out, expected, p):
    want, parent_want = np.asarray(expected["patches"], float), np.asarray(expected["parent"])
    patches, parent = _patches(out, p)
    if patches.shape != want.shape:
        return f"{len(patches)} patches, expected {len(want)} (nu × nv per quad, handout §R1)"
    if not np.array_equal(parent, parent_want):
        return "parent is not the index of each patch's quad, in order"
    err = np.abs(patches - want).max() / max(np.abs(want).max(), 1.0)
    return None if err <= TOL.FLOAT64_RTOL else f"corners differ from the bilinear grid by {err:.2e} (relative)"


def subdivide_area(out, expected, p):
    patches, parent = _patches(out, p)
    if len(patches) > 4 * len(expected["patches"]) + 16:
        return f"{len(patches)} patches, far more than the {len(expected['patches'])} needed"
    got = np.bincount(parent, weights=patch_areas(patches), minlength=len(p["quads"]))
    want = patch_areas(np.asarray(p["quads"]))
    err = np.abs(got / want - 1).max()
    return None if err <= TOL.AREA else f"the patches of a quad cover {err:.2%} more or less than the quad"


def subdivide_edges(out, expected, p):
    q, _ = _patches(out, p)
    longest = np.linalg.norm(q - np.roll(q, -1, axis=1), axis=2).max() if len(q) else 0.0
    if not len(q):
        return "no patches"
    return None if p["max_edge"] <= 0 or longest <= p["max_edge"] * (1 + TOL.EDGE_SLACK) else \
        f"an edge is {longest:.4g} long, longer than max_edge {p['max_edge']}"


def subdivide_facing(out, expected, p):
    patches, parent = _patches(out, p)
    got = patch_normals(patches)
    want = patch_normals(np.asarray(p["quads"]))[parent]
    worst = float((got * want).sum(axis=1).min()) if len(got) else -1.0
    return None if worst > 0.999 else "a patch faces away from its quad (corners not counter-clockwise)"


def shot_matches(out, expected, p) -> Verdict:
    n = len(p["areas"])
    B, dB = output(out, "radiosity", (n, 3), "radiosity"), output(out, "unshot", (n, 3), "unshot")
    ok_b = np.allclose(B, expected["radiosity"], rtol=TOL.FLOAT64_RTOL, atol=TOL.FLOAT64_ATOL)
    ok_d = np.allclose(dB, expected["unshot"], rtol=TOL.FLOAT64_RTOL, atol=TOL.FLOAT64_ATOL)
    if ok_b and ok_d:
        return Verdict(1.0, "B and ΔB match the hand-worked shot")
    what = [name for name, ok in (("radiosity", ok_b), ("unshot", ok_d)) if not ok]
    return Verdict(0.5 if len(what) == 1 else 0.0, f"{' and '.join(what)} differ from the hand-worked shot "
                   f"(ΔRad_j = ρ_j ΔB_i F_ij A_i / A_j, then ΔB_i = 0)")


def _same_loop(out, expected, p) -> Verdict | None:
    """None when the order of shots and B, ΔB after them are the loop's worked by hand; else the verdict."""
    n = len(p["areas"])
    order = [int(i) for i in np.asarray(expected["order"]).ravel()]
    got = [int(i) for i in output(out, "order", (None,), "order")]
    if got != order:
        first = next((k for k, (a, b) in enumerate(zip(got, order)) if a != b), min(len(got), len(order)))
        return Verdict(0.0, f"shot order differs from shot {first + 1} on: {got[:first + 3]}… expected "
                       f"{order[:first + 3]}… ({len(got)} shots, expected {len(order)})")
    B, dB = output(out, "radiosity", (n, 3), "radiosity"), output(out, "unshot", (n, 3), "unshot")
    if not (np.allclose(B, expected["radiosity"], rtol=TOL.LOOP_RTOL, atol=TOL.FLOAT64_ATOL)
            and np.allclose(dB, expected["unshot"], rtol=TOL.LOOP_RTOL, atol=TOL.FLOAT64_ATOL)):
        return Verdict(0.5, "the order of shots is right but B or ΔB are not")
    return None


def loop_matches(out, expected, p) -> Verdict:
    """Order of shots and B, ΔB after them, against the loop worked by hand (linear search, no heap)."""
    wrong = _same_loop(out, expected, p)
    if wrong:
        return wrong
    order = [int(i) for i in np.asarray(expected["order"]).ravel()]
    B = output(out, "radiosity", (len(p["areas"]), 3), "radiosity")
    fetched = _rows_fetched(out, len(order)) or _on_shot_reported(out, order, B)
    if fetched:
        return Verdict(0.5, f"B and ΔB are right, but {fetched}")
    return Verdict(1.0, f"{len(order)} shots in the right order with the right B and ΔB")


def largest_first_matches(out, expected, p) -> Verdict:
    """R7: the paper's order of shots, and B, ΔB after them, against its loop worked by hand."""
    wrong = _same_loop(out, expected, p)
    if wrong:
        return wrong
    order = [int(i) for i in np.asarray(expected["order"]).ravel()]
    unreported = _on_shot_reported(out, order, output(out, "radiosity", (len(p["areas"]), 3), "radiosity"))
    if unreported:
        return Verdict(0.5, f"B and ΔB are right, but {unreported}")
    return Verdict(1.0, f"{len(order)} shots, each from the largest key")


def solve_again_matches(out, expected, p) -> Verdict:
    """R6: R3's result, computing only the rows not known (each once, none known again), and keeping them."""
    wrong = _same_loop(out, expected, p)
    if wrong:
        return Verdict(wrong.fraction * 0.5, f"{wrong.message} (R6 solves as R3 does)")
    want = [int(i) for i in np.asarray(expected["rows_asked"]).ravel()]
    asked = [int(i) for i in output(out, "rows_asked", (None,), "rows_asked")]
    if asked != want:
        again = sorted({i for i in asked if i in set(int(k) for k in p["known_rows"]) or asked.count(i) > 1})
        return Verdict(0.25, f"B and ΔB are right, but row() computed rows {asked[:8]}{'…' if len(asked) > 8 else ''} "
                       f"where only {want[:8]}{'…' if len(want) > 8 else ''} were not known"
                       + (f" (known or already computed: {again[:8]})" if again else "")
                       + "; take a row from known when it is there, and compute each other one once")
    kept = [int(i) for i in output(out, "known_after", (None,), "known_after")]
    should = sorted({int(i) for i in p["known_rows"]} | set(want))
    if sorted(kept) != should or not bool(output(out, "known_rows_right", (), "known_rows_right")):
        return Verdict(0.5, f"B, ΔB and the rows computed are right, but known holds rows {sorted(kept)[:8]} "
                       f"afterwards where it should hold {should[:8]} (add each computed row under int(i), as row() "
                       f"returned it, so a later solve finds it)")
    return Verdict(1.0, f"{len(np.asarray(expected['order']).ravel())} shots as R3 takes them, {len(want)} rows "
                   f"computed, {len(p['known_rows'])} reused")


def _rows_fetched(out, shots: int) -> str | None:
    """A row of form factors is the costly thing (a hemicube each): asked for once per shot, none past the stop."""
    asked = int(output(out, "rows_requested", (), "rows_requested"))
    if asked != shots:
        return (f"row() was called {asked} times for {shots} shots (ask for a patch's row when it shoots, once, "
                f"and stop before asking for the next)")
    return None


def _on_shot_reported(out, order: list[int], radiosity: np.ndarray) -> str | None:
    """``on_shot(shots, i, radiosity, unshot)`` after every shot, as the contract says (the demo draws with it)."""
    calls = output(out, "on_shot_calls", (None, 2), "on_shot_calls").astype(np.int64).tolist()
    want = [[k, i] for k, i in enumerate(order, 1)]
    if calls != want:
        return (f"on_shot was called {len(calls)} times for {len(order)} shots"
                + (f" (first calls as (shots, i): {calls[:3]}, expected {want[:3]})" if calls else "")
                + "; call on_shot(shots, i, radiosity, unshot) after every shot")
    last = output(out, "on_shot_last", radiosity.shape, "on_shot_last")
    if order and not np.array_equal(last, radiosity):
        return "the radiosity on_shot saw after the last shot is not the one returned (pass the state after the shot)"
    return None


def _shots_like_reference(out, expected, low: float = 1 / (1 + TOL.SHOTS), high: float = 1 + TOL.SHOTS) -> str | None:
    """A progressive refinement shoots about as often as the reference's does on the same system."""
    got = len(output(out, "order", (None,), "order"))
    want = len(np.asarray(expected["order"]).ravel())
    if not low * want <= got <= high * want:
        return (f"{got} shots, where progressive refinement takes about {want} on this system "
                f"(shoot one patch at a time, until the unshot energy is below the tolerance)")
    return None


def furnace_uniform(out, expected, p, want: float) -> Verdict:
    """B = E/(1 − ρ) on every patch, reached by shooting."""
    n = len(p["areas"])
    B = output(out, "radiosity", (n, 3), "radiosity")
    err = float(np.abs(B / want - 1).max())
    if not np.isfinite(err):
        return Verdict(0.0, "radiosity is not finite")
    detail = {"relative_error": err}
    if err > 2 * p["tolerance"]:
        return Verdict(0.0, f"B should be E/(1 − ρ) = {want:g} everywhere; off by up to {err:.2%}", detail=detail)
    shots = _shots_like_reference(out, expected)
    if shots:
        return Verdict(0.0, f"B = {want:g}, but {shots}", detail=detail)
    return Verdict(1.0, f"B = E/(1 − ρ) = {want:g} within {err:.1e}", detail=detail)


def converged_to_direct(out, expected, p, within: float) -> Verdict:
    """Converged to the direct solve of the same form factors by shooting, fetching rows only for shooters."""
    want = np.asarray(expected["direct"], float)
    got = output(out, "radiosity", want.shape, "radiosity")
    err = float(np.abs(got - want).sum() / np.abs(want).sum())
    order = output(out, "order", (None,), "order")
    rows, shooters = int(output(out, "rows_computed", (), "rows_computed")), len(set(order.astype(np.int64).tolist()))
    detail = {"relative_error": err, "rows_computed": rows, "shooters": shooters}
    if not err <= within:
        return Verdict(0.0, f"differs from the direct solve of (I − ρF)B = E by {err:.2%} (allowed {within:.1%})", detail=detail)
    shots = _shots_like_reference(out, expected)
    if shots:
        return Verdict(0.0, f"converged, but {shots}", detail=detail)
    if rows > shooters:
        return Verdict(0.5, f"converged, but fetched {rows} rows for {shooters} shooters (fetch a row only to shoot)", detail=detail)
    fetched = _rows_fetched(out, len(order))
    if fetched:
        return Verdict(0.5, f"converged, but {fetched}", detail=detail)
    return Verdict(1.0, f"within {err:.1e} of the direct solve; {rows} rows for {shooters} shooters", detail=detail)


def ambient_matches(out, expected, p) -> Verdict:
    want = np.asarray(expected["value"], float)
    got = output(out, "ambient", want.shape, "ambient")
    if np.allclose(got, want, rtol=TOL.FLOAT64_RTOL, atol=TOL.FLOAT64_ATOL):
        return Verdict(1.0, "ambient matches")
    return Verdict(0.0, f"ambient is {np.round(got, 6).tolist()}, expected {np.round(want, 6).tolist()} "
                   "(R · ΣΔB A / ΣA, R = 1/(1 − ρ_avg))")


def _vertices(out, p):
    m = len(p["quads"])
    positions = output(out, "positions", (None, 3), "positions")
    corners = output(out, "corners", (m, 4), "corners")
    if len(positions) > 4 * m or (corners.size and (corners.min() < 0 or corners.max() >= len(positions))):
        raise ValueError("corners must index positions")
    colors = output(out, "colors", (len(positions), 3), "colors")
    return positions, corners.astype(np.int64), colors


def vertex_corners(out, expected, p):
    positions, corners, _ = _vertices(out, p)
    return None if np.allclose(positions[corners], p["quads"], atol=TOL.CORNER_ATOL) else "positions[corners] are not the patches' corners"


def vertex_colours(out, expected, p):
    positions, corners, colors = _vertices(out, p)
    if np.allclose(colors[corners], expected["corner_colors"], rtol=TOL.FLOAT64_RTOL, atol=TOL.FLOAT64_ATOL):
        return None
    return "a vertex's colour is not the average of the patches of its polygon that meet there"


def vertex_shared(out, expected, p):
    positions, _, _ = _vertices(out, p)
    n, want = len(positions), int(expected["vertex_count"])
    return None if n == want else f"{n} vertices, expected {want} (one per point per polygon)"
