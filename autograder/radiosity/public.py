"""Stage 4 public tests: students run these with ``cs451 grade radiosity``.

Points per task (the rubric in assignments/04-radiosity/README.md):
R1 15, R2 15, R3 35, R4 10, R5 25 in all; hidden.py holds part of each task's points.

Scene tests get their patches and form factors from the reference run of the probe
``system`` (stage 3's trusted hemicube engine), so a bug in R1 or in stage 3 costs nothing
elsewhere. R3's tests run the submission's own R2 inside its loop, and the image tests its
R3, R4 and R5 (tests/test_radiosity_grading.py checks which tasks a broken function costs).
"""
from __future__ import annotations

import copy
import json

import numpy as np

from cs451.compare import ImageTolerance
from cs451.grading.checks import all_of, image_matches
from cs451.grading.spec import Test, Verdict
from cs451.patches import patch_areas, patch_normals
from cs451.scene import BUNDLED_DIR, load_scene
from cs451.stages.radiosity import scene_polygons

from autograder.radiosity import truth

IMAGE = ImageTolerance(threshold=0.016, max_bad_fraction=0.01, shift=1)
#: Time limits: generous for clear numpy code (the reference takes under 2 s for each).
QUICK, SOLVE, RENDER = 20.0, 60.0, 90.0

CORNELL = json.loads((BUNDLED_DIR / "cornell-box.json").read_text())
FURNACE = json.loads((BUNDLED_DIR / "furnace.json").read_text())
ROOM = json.loads((BUNDLED_DIR / "room.json").read_text())


def lists(a) -> list:
    return np.asarray(a, dtype=np.float64).tolist()


def scene_quads(name: str, count: int | None = None) -> list:
    quads, _, _, _ = scene_polygons(load_scene(name))
    return lists(quads[:count])


#: Three patches worked by hand in the handout: an emitter (patch 0) over two receivers, A_i F_ij = A_j F_ji.
HAND = {
    "F": [[0.0, 0.3, 0.2], [0.6, 0.0, 0.1], [0.2, 0.05, 0.0]],
    "areas": [2.0, 1.0, 2.0],
    "reflectance": [[0.0, 0.0, 0.0], [0.5, 0.4, 0.3], [0.8, 0.2, 0.6]],
    "emission": [[10.0, 5.0, 2.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]],
}


def random_system(n: int, seed: int, closed: bool = False) -> dict:
    """A reciprocal system (A_i F_ij = A_j F_ji) with a few coloured emitters, as JSON lists."""
    rng = np.random.default_rng(seed)
    A = rng.uniform(0.5, 2.0, n)
    S = rng.uniform(0, 1, (n, n)) ** 3
    S = (S + S.T) / 2
    np.fill_diagonal(S, 0)
    F = S / A[:, None]
    F /= F.sum(axis=1).max() * (1.0 if closed else 1.1)
    rho = rng.uniform(0.1, 0.9, (n, 3))
    E = np.where(rng.random((n, 1)) < 0.2, rng.uniform(0, 4, (n, 3)), 0.0)
    E[n // 2] = [2.0, 1.0, 3.0]
    return {"F": lists(F), "areas": lists(A), "reflectance": lists(rho), "emission": lists(E)}


def furnace_cube(albedo: float, emission: float = 1.0) -> dict:
    """The furnace with one patch per face and Howell's exact form factors."""
    quads = np.asarray(scene_quads("furnace"))
    return {"F": lists(truth.cube_formfactors(patch_normals(quads))), "areas": lists(patch_areas(quads)),
            "reflectance": [[albedo] * 3] * 6, "emission": [[emission] * 3] * 6}


def scene_variant(base: dict, radiosity: dict | None = None, **changes) -> dict:
    scene = copy.deepcopy(base)
    scene.update(copy.deepcopy(changes))
    if radiosity is not None:
        scene.setdefault("options", {})["radiosity"] = radiosity
    return scene


# --- checks ------------------------------------------------------------------------

def subdivide_checks():
    def exact(out, p):
        want, parent = truth.subdivide_by_hand(p["quads"], p["max_edge"])
        got = np.asarray(out["patches"], dtype=float)
        if got.shape != want.shape:
            return f"{len(got)} patches, expected {len(want)} (nu × nv per quad, handout §R1)"
        if not np.array_equal(np.asarray(out["parent"]), parent):
            return "parent is not the index of each patch's quad, in order"
        err = np.abs(got - want).max() / max(np.abs(want).max(), 1.0)
        return None if err <= 1e-9 else f"corners differ from the bilinear grid by {err:.2e} (relative)"

    def area(out, p):
        got = np.bincount(np.asarray(out["parent"]), weights=patch_areas(out["patches"]), minlength=len(p["quads"]))
        want = patch_areas(np.asarray(p["quads"]))
        err = np.abs(got / want - 1).max()
        return None if err <= 1e-5 else f"the patches of a quad cover {err:.2%} more or less than the quad"

    def edges(out, p):
        q = np.asarray(out["patches"], dtype=float)
        longest = np.linalg.norm(q - np.roll(q, -1, axis=1), axis=2).max() if len(q) else 0.0
        return None if p["max_edge"] <= 0 or longest <= p["max_edge"] * (1 + 1e-9) else \
            f"an edge is {longest:.4g} long, longer than max_edge {p['max_edge']}"

    def facing(out, p):
        got = patch_normals(out["patches"])
        want = patch_normals(np.asarray(p["quads"]))[np.asarray(out["parent"])]
        worst = float((got * want).sum(axis=1).min())
        return None if worst > 0.999 else "a patch faces away from its quad (corners not counter-clockwise)"

    return all_of([("the grid of the handout", exact), ("area kept", area), ("edge lengths", edges), ("orientation", facing)])


def shoot_check():
    def check(out, expected, p):
        B, dB = truth.shoot_by_hand(p["i"], p["F"], p["areas"], p["reflectance"], p["radiosity"], p["unshot"])
        ok_b = np.allclose(out["radiosity"], B, rtol=1e-9, atol=1e-12)
        ok_d = np.allclose(out["unshot"], dB, rtol=1e-9, atol=1e-12)
        if ok_b and ok_d:
            return Verdict(1.0, "B and ΔB match the hand-worked shot")
        what = [n for n, ok in (("radiosity", ok_b), ("unshot", ok_d)) if not ok]
        return Verdict(0.5 if len(what) == 1 else 0.0, f"{' and '.join(what)} differ from the hand-worked shot "
                       f"(ΔRad_j = ρ_j ΔB_i F_ij A_i / A_j, then ΔB_i = 0)")
    return check


def by_hand_check():
    """Order of shots and B, ΔB after them, against the loop worked by hand (linear search, no heap)."""
    def check(out, expected, p):
        B, dB, order = truth.progressive_by_hand(p["F"], p["areas"], p["reflectance"], p["emission"], p["tolerance"],
                                                 p["max_shots"], p.get("overshoot", 1.0))
        got = [int(i) for i in np.asarray(out["order"]).ravel()]
        if got != order:
            first = next((k for k, (a, b) in enumerate(zip(got, order)) if a != b), min(len(got), len(order)))
            return Verdict(0.0, f"shot order differs from shot {first + 1} on: {got[:first + 3]}… expected "
                           f"{order[:first + 3]}… ({len(got)} shots, expected {len(order)})")
        if not (np.allclose(out["radiosity"], B, rtol=1e-8, atol=1e-12) and np.allclose(out["unshot"], dB, rtol=1e-8, atol=1e-12)):
            return Verdict(0.5, "the order of shots is right but B or ΔB are not")
        return Verdict(1.0, f"{len(order)} shots in the right order with the right B and ΔB")
    return check


def furnace_check(albedo: float, emission: float = 1.0):
    def check(out, expected, p):
        want = truth.furnace(emission, albedo)
        err = float(np.abs(np.asarray(out["radiosity"]) / want - 1).max())
        if not np.isfinite(err):
            return Verdict(0.0, "radiosity is not finite")
        detail = {"relative_error": err}
        if err <= 2 * p["tolerance"]:
            return Verdict(1.0, f"B = E/(1 − ρ) = {want:g} within {err:.1e}", detail=detail)
        return Verdict(0.0, f"B should be E/(1 − ρ) = {want:g} everywhere; off by up to {err:.2%}", detail=detail)
    return check


def direct_check(within: float):
    """Converged to the direct solve of the same form factors, and no rows fetched for patches that never shoot."""
    def converged(out, expected, p):
        want = np.asarray(expected["direct"])
        got = np.asarray(out["radiosity"])
        err = float(np.abs(got - want).sum() / np.abs(want).sum())
        rows, shooters = int(out["rows_computed"]), len(set(np.asarray(out["order"]).ravel().tolist()))
        detail = {"relative_error": err, "rows_computed": rows, "shooters": shooters}
        if not err <= within:
            return Verdict(0.0, f"differs from the direct solve of (I − ρF)B = E by {err:.2%} (allowed {within:.1%})", detail=detail)
        if rows > shooters:
            return Verdict(0.5, f"converged, but fetched {rows} rows for {shooters} shooters (fetch a row only to shoot)", detail=detail)
        return Verdict(1.0, f"within {err:.1e} of the direct solve; {rows} rows for {shooters} shooters", detail=detail)
    return converged


def ambient_check():
    def check(out, expected, p):
        want = truth.ambient_by_hand(p["areas"], p["reflectance"], p["unshot"])
        got = np.asarray(out["ambient"], dtype=float)
        if np.allclose(got, want, rtol=1e-9, atol=1e-12):
            return Verdict(1.0, "ambient matches")
        return Verdict(0.0, f"ambient is {np.round(got, 6).tolist()}, expected {np.round(want, 6).tolist()} "
                       "(R · ΣΔB A / ΣA, R = 1/(1 − ρ_avg))")
    return check


def vertex_checks():
    def corners(out, p):
        got = np.asarray(out["positions"])[np.asarray(out["corners"])]
        return None if np.allclose(got, p["quads"], atol=1e-9) else "positions[corners] are not the patches' corners"

    def colours(out, p):
        got = np.asarray(out["colors"])[np.asarray(out["corners"])]
        want = truth.corner_colors_by_hand(p["quads"], p["parent"], np.asarray(p["radiosity"]))
        if np.allclose(got, want, rtol=1e-9, atol=1e-12):
            return None
        return "a vertex's colour is not the average of the patches of its polygon that meet there"

    def shared(out, p):
        q = np.asarray(p["quads"])
        keys = {(int(par), *np.round(c / 1e-6).astype(int).tolist()) for quad, par in zip(q, p["parent"]) for c in quad}
        n = len(np.asarray(out["positions"]))
        return None if n == len(keys) else f"{n} vertices, expected {len(keys)} (one per point per polygon)"

    return all_of([("corners", corners), ("colours", colours), ("shared vertices", shared)])


# --- tests --------------------------------------------------------------------------

def subdivide_test(name, points, quads, max_edge, hidden=False) -> Test:
    return Test(name, "R1", points, "subdivide", {"quads": quads, "max_edge": max_edge}, subdivide_checks(),
                "corners within 1e-9 (relative) of the bilinear grid; areas within 1e-5", expected="none",
                hidden=hidden, timeout=QUICK)


def shoot_test(name, points, system, i, radiosity=None, unshot=None, hidden=False) -> Test:
    params = {"i": i, **{k: system[k] for k in ("F", "areas", "reflectance")},
              "radiosity": radiosity or system["emission"], "unshot": unshot or system["emission"]}
    return Test(name, "R2", points, "shoot", params, shoot_check(), "1e-9 relative", expected="none",
                hidden=hidden, timeout=QUICK)


def by_hand_test(name, points, system, max_shots, tolerance=0.0, overshoot=1.0, hidden=False) -> Test:
    params = {**system, "tolerance": tolerance, "max_shots": max_shots, "overshoot": overshoot}
    return Test(name, "R3", points, "progressive", params, by_hand_check(), "same shots in the same order; B, ΔB within 1e-8",
                expected="none", hidden=hidden, timeout=SOLVE)


def furnace_test(name, points, albedo, tolerance, overshoot=1.0, hidden=False) -> Test:
    params = {**furnace_cube(albedo), "tolerance": tolerance, "max_shots": 100_000, "overshoot": overshoot}
    return Test(name, "R3", points, "progressive", params, furnace_check(albedo),
                "E/(1 − ρ) within twice the tolerance", expected="none", hidden=hidden, timeout=SOLVE)


def scene_solve_test(name, points, scene, patch_size, tolerance=1e-5, within=1e-3, hidden=False) -> Test:
    params = {"scene": scene, "patch_size": patch_size, "resolution": 32, "tolerance": tolerance, "max_shots": 200_000}
    return Test(name, "R3", points, "progressive", params, direct_check(within),
                f"within {within:.1%} of the direct solve (sum of |differences|)", given="system", hidden=hidden,
                timeout=SOLVE)


def ambient_test(name, points, areas, reflectance, unshot, hidden=False) -> Test:
    return Test(name, "R4", points, "ambient", {"areas": areas, "reflectance": reflectance, "unshot": unshot},
                ambient_check(), "1e-9 relative", expected="none", hidden=hidden, timeout=QUICK)


def vertex_test(name, points, quads, parent, radiosity, hidden=False) -> Test:
    return Test(name, "R5", points, "vertex_colors", {"quads": quads, "parent": parent, "radiosity": radiosity},
                vertex_checks(), "colours within 1e-9", expected="none", hidden=hidden, timeout=QUICK)


def render_test(name, points, scene, size, patch_size, hidden=False) -> Test:
    params = {"scene": scene, "size": list(size), "patch_size": patch_size, "resolution": 32, "tolerance": 1e-3}
    return Test(name, "R5", points, "render", params, image_matches(IMAGE), IMAGE.describe(), given="system",
                hidden=hidden, timeout=RENDER)


def _grid_patches() -> tuple[list, list, list]:
    quads = np.asarray(scene_quads("furnace", 3))
    patches, parent = truth.subdivide_by_hand(quads, 0.34)
    radiosity = np.random.default_rng(5).uniform(0.0, 2.0, (len(patches), 3))
    return lists(patches), parent.tolist(), lists(radiosity)


GRID = _grid_patches()

TESTS = [
    subdivide_test("R1 subdivide: the Cornell box at 100 mm", 6, scene_quads("cornell-box"), 100.0),
    subdivide_test("R1 subdivide: a triangle and a quad", 4,
                   [[[0, 0, 0], [4, 0, 0], [0, 3, 0], [0, 3, 0]], [[0, 0, 1], [2, 0, 1], [2, 0.5, 1], [0, 1, 1]]], 1.0),
    shoot_test("R2 shoot: the hand-worked emitter shoots", 5, HAND, 0),
    shoot_test("R2 shoot: a receiver shoots back, B and ΔB already set", 5, HAND, 1,
               radiosity=[[10.0, 5.0, 2.0], [3.0, 1.2, 0.36], [1.6, 0.2, 0.24]],
               unshot=[[0.0, 0.0, 0.0], [3.0, 1.2, 0.36], [1.6, 0.2, 0.24]]),
    by_hand_test("R3 progressive_refinement: the hand-worked scene, 3 shots", 6, HAND, 3),
    by_hand_test("R3 progressive_refinement: the hand-worked scene to 1e-6", 5, HAND, 10_000, tolerance=1e-6),
    furnace_test("R3 progressive_refinement: the furnace, ρ = 0.9", 6, 0.9, 1e-4),
    scene_solve_test("R3 progressive_refinement: the Cornell box converges to the direct solve", 8, CORNELL, 140.0),
    ambient_test("R4 ambient_term: the hand-worked scene after one shot", 6, HAND["areas"], HAND["reflectance"],
                 [[0.0, 0.0, 0.0], [3.0, 1.2, 0.36], [1.6, 0.2, 0.24]]),
    vertex_test("R5 vertex_colors: three walls of the furnace, 3 × 3 patches each", 6, *GRID),
    render_test("R5 render: the Cornell box", 8, CORNELL, (128, 128), 100.0),
]
