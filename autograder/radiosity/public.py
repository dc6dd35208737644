"""Stage 4 public tests: students run these with ``cs451 grade radiosity``.

Points per task (the rubric in assignments/04-radiosity/README.md):
R1 15, R2 15, R3 35, R4 10, R5 25 in all; hidden.py holds part of each task's points.
Every case a hidden test checks (max_edge 0, overshooting, a triangle's repeated corner) has a
public test too.

Scene tests get their patches and form factors from the reference run of the probe
``system`` (stage 3's trusted hemicube engine), so a bug in R1 or in stage 3 costs nothing
elsewhere; the image tests also get the values the reference's R3 and R4 display
(``solved_system``), so they judge R5 alone. R3's tests run the submission's own R2 inside
its loop, and say so when they fail (tests/radiosity/test_radiosity_grading.py checks which tasks a
broken function costs).
"""
from __future__ import annotations

import copy
import json

import numpy as np

from cs451.compare import ImageTolerance
from cs451.grading.checks import all_of, image_matches, sub
from cs451.grading.spec import Test, check, truth, variant
from cs451.stages.radiosity import tolerances as TOL
from cs451.patches import patch_areas, patch_normals
from cs451.scene import BUNDLED_DIR, load_scene
from cs451.patching import radiosity_surfaces

from autograder.radiosity import checks, truth as truths, variants

IMAGE = ImageTolerance()  # the kit's margin, measured in docs/tolerances.md
#: Time limits: generous for clear numpy code (the reference takes under 2 s for each).
QUICK, SOLVE, RENDER = 20.0, 60.0, 90.0

CORNELL = json.loads((BUNDLED_DIR / "cornell-box.json").read_text())
FURNACE = json.loads((BUNDLED_DIR / "furnace.json").read_text())
ROOM = json.loads((BUNDLED_DIR / "room.json").read_text())


def lists(a) -> list:
    return np.asarray(a, dtype=np.float64).tolist()


def scene_quads(name: str, count: int | None = None) -> list:
    quads, _, _, _ = radiosity_surfaces(load_scene(name))
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


#: Six patches where the notes' sweeps (§2.5) and "always the current maximum" part ways at the fifth shot.
SIX = random_system(6, seed=7)
#: Five patches, nothing leaving: the tolerance is reached in the middle of a sweep.
CLOSED_FIVE = random_system(5, seed=5, closed=True)


def furnace_cube(albedo: float, emission: float = 1.0) -> dict:
    """The furnace with one patch per face and Howell's exact form factors."""
    quads = np.asarray(scene_quads("furnace"))
    return {"F": lists(truths.cube_formfactors(patch_normals(quads))), "areas": lists(patch_areas(quads)),
            "reflectance": [[albedo] * 3] * 6, "emission": [[emission] * 3] * 6}


def scene_variant(base: dict, radiosity: dict | None = None, **changes) -> dict:
    scene = copy.deepcopy(base)
    scene.update(copy.deepcopy(changes))
    if radiosity is not None:
        scene.setdefault("options", {})["radiosity"] = radiosity
    return scene


# --- tests --------------------------------------------------------------------------

SUBDIVIDE_CHECKS = all_of([("the grid of the handout", sub(checks.subdivide_exact)), ("area kept", sub(checks.subdivide_area)),
                           ("edge lengths", sub(checks.subdivide_edges)), ("orientation", sub(checks.subdivide_facing))],
                          earn_with=["the grid of the handout", "edge lengths"])


def subdivide_test(name, points, quads, max_edge) -> Test:
    return Test(name, "R1", points, "subdivide", {"quads": quads, "max_edge": max_edge}, SUBDIVIDE_CHECKS,
                f"corners within {TOL.FLOAT64_RTOL} (relative) of the bilinear grid; areas within {TOL.AREA}", expected="none",
                truth=truth(truths.subdivision), edge_case=max_edge <= 0, timeout=QUICK, vary=variant(variants.subdivide))


def shoot_test(name, points, system, i, radiosity=None, unshot=None) -> Test:
    params = {"i": i, **{k: system[k] for k in ("F", "areas", "reflectance")},
              "radiosity": radiosity or system["emission"], "unshot": unshot or system["emission"]}
    return Test(name, "R2", points, "shoot", params, check(checks.shot_matches), f"{TOL.FLOAT64_RTOL} relative", expected="none",
                truth=truth(truths.shot), timeout=QUICK, vary=variant(variants.shoot))


def by_hand_test(name, points, system, max_shots, tolerance=0.0, overshoot=1.0) -> Test:
    params = {**system, "tolerance": tolerance, "max_shots": max_shots, "overshoot": overshoot}
    return Test(name, "R3", points, "progressive", params, check(checks.loop_matches),
                f"same shots in the same order; B, ΔB within {TOL.LOOP_RTOL}", expected="none", truth=truth(truths.shooting_loop),
                timeout=SOLVE, depends_on=("R2",), vary=variant(variants.progressive))


def largest_first_test(name, points, system, max_shots, tolerance=0.0, overshoot=1.0, vary=None) -> Test:
    params = {**system, "tolerance": tolerance, "max_shots": max_shots, "overshoot": overshoot}
    return Test(name, "R7", points, "largest_first", params, check(checks.largest_first_matches),
                f"same shots in the same order; B, ΔB within {TOL.LOOP_RTOL}", expected="none",
                truth=truth(truths.largest_first), timeout=SOLVE, depends_on=("R2",),
                vary=vary or variant(variants.largest_first))


def absorbing(system: dict) -> dict:
    """The system with nothing reflecting (ρ = 0): once each emitter has shot, every key is exactly 0."""
    return {**system, "reflectance": [[0.0, 0.0, 0.0]] * len(system["areas"])}


def solve_again_case(system: dict, known: str, overshoot: float = 1.0, tolerance: float = 1e-4) -> dict:
    """R6's parameters from a system, by what the earlier solve left in ``known``: "all" (every row: the light is
    recoloured, so no row may be computed), "painted" (the rows of the shooters of a solve in which the darkest
    non-emitting patch was black; now it is white and shoots, so its row is new) or "none" (nothing: each shooter's
    row is computed once, however often it shoots)."""
    n, params = len(system["areas"]), {"tolerance": tolerance, "max_shots": 100_000, "overshoot": overshoot}
    if known == "all":
        emission = (np.asarray(system["emission"]) * [0.25, 1.0, 2.5]).tolist()
        return {**system, **params, "emission": emission, "known_rows": list(range(n))}
    if known == "painted":
        E, rho = np.asarray(system["emission"]), np.array(system["reflectance"])
        k = int(np.argmin(np.where(E.sum(axis=1) > 0, np.inf, rho.sum(axis=1))))
        rho[k] = 0.0
        before = truths.shooting_loop({**system, **params, "reflectance": lists(rho)})["order"].tolist()
        rho[k] = 0.95
        return {**system, **params, "reflectance": lists(rho), "known_rows": sorted(set(before))}
    return {**system, **params, "known_rows": []}


def solve_again_test(name, points, system, known: str, overshoot: float = 1.0) -> Test:
    return Test(name, "R6", points, "solve_again", solve_again_case(system, known, overshoot), check(checks.solve_again_matches),
                f"R3's shots, B and ΔB within {TOL.LOOP_RTOL}; row() only for rows not known, each once; known kept",
                expected="none", truth=truth(truths.resolved), timeout=SOLVE, depends_on=("R3",),
                vary=variant(variants.solve_again, known=known))


def furnace_test(name, points, albedo, tolerance, overshoot=1.0) -> Test:
    params = {**furnace_cube(albedo), "tolerance": tolerance, "max_shots": 100_000, "overshoot": overshoot}
    return Test(name, "R3", points, "progressive", params, check(checks.furnace_uniform, want=truths.furnace(1.0, albedo)),
                f"E/(1 − ρ) within twice the tolerance, in as many shots as the reference (± {TOL.SHOTS:.0%})", timeout=SOLVE,
                depends_on=("R2",), vary=variant(variants.furnace))


def scene_solve_test(name, points, scene, patch_size, tolerance=1e-5, within=TOL.DIRECT_SOLVE) -> Test:
    params = {"scene": scene, "patch_size": patch_size, "resolution": 32, "tolerance": tolerance, "max_shots": 200_000}
    return Test(name, "R3", points, "progressive", params, check(checks.converged_to_direct, within=within),
                f"within {within:.1%} of the direct solve (sum of |differences|), in as many shots as the reference (± {TOL.SHOTS:.0%})",
                given="system", timeout=SOLVE, depends_on=("R2",), vary=variant(variants.box_scene))


def ambient_test(name, points, areas, reflectance, unshot) -> Test:
    return Test(name, "R4", points, "ambient", {"areas": areas, "reflectance": reflectance, "unshot": unshot},
                check(checks.ambient_matches), f"{TOL.FLOAT64_RTOL} relative", expected="none", truth=truth(truths.ambient),
                timeout=QUICK, vary=variant(variants.ambient))


VERTEX_CHECKS = all_of([("corners", sub(checks.vertex_corners)), ("colours", sub(checks.vertex_colours)),
                        ("shared vertices", sub(checks.vertex_shared))], earn_with=["colours"])


def vertex_test(name, points, quads, parent, radiosity, kind="triangle") -> Test:
    """``kind``: "grid" (walls of the furnace), "triangle" (a triangle beside a quad), "fan" (a fanned polygon) or
    "noisy" (corners apart by rounding noise), for the fresh case."""
    return Test(name, "R5", points, "vertex_colors", {"quads": quads, "parent": parent, "radiosity": radiosity},
                VERTEX_CHECKS, f"colours within {TOL.FLOAT64_RTOL}", expected="none", truth=truth(truths.vertex_colours), timeout=QUICK,
                vary=variant(variants.vertex_colors, kind=kind))


def render_test(name, points, scene, size, patch_size) -> Test:
    params = {"scene": scene, "size": list(size), "patch_size": patch_size, "resolution": 32, "tolerance": 1e-3}
    return Test(name, "R5", points, "render", params, image_matches(IMAGE), IMAGE.describe(), given="solved_system",
                timeout=RENDER, vary=variant(variants.box_scene))


def _grid_patches() -> tuple[list, list, list]:
    quads = np.asarray(scene_quads("furnace", 3))
    patches, parent = truths.subdivide_by_hand(quads, 0.34)
    radiosity = np.random.default_rng(5).uniform(0.0, 2.0, (len(patches), 3))
    return lists(patches), parent.tolist(), lists(radiosity)


GRID = _grid_patches()


def fan_patches(sides: int, radius: float, turn: float = 0.0) -> tuple[list, list]:
    """A regular polygon fanned from its first corner into triangles, each stored as a quad repeating its last
    corner, as the kit stores a polygon of more than four corners: the corner a triangle repeats is the next
    triangle's second, so a vertex colour that counts a patch once per corner weighs it twice there."""
    angles = np.radians(turn) + 2 * np.pi * np.arange(sides) / sides
    v = np.column_stack([radius * np.cos(angles), radius * np.sin(angles), np.zeros(sides)])
    quads = [[v[0], v[k], v[k + 1], v[k + 1]] for k in range(1, sides - 1)]
    return lists(np.array(quads)), [0] * len(quads)


def noisy_grid(size: float, cuts: int, rng: np.random.Generator) -> tuple[list, list, list]:
    """One square polygon ``size`` wide cut into cuts × cuts patches whose shared corners differ by rounding noise
    (about 1e-13 of the size, as corners computed from different patches do): one vertex each by the contract's
    1e-9·S. Drawn again until no shared corner's copies straddle a cell of the 1e-9·S grid the handout suggests
    snapping to, so that the snapping it suggests gives the contract's answer."""
    t = np.linspace(0.0, size, cuts + 1)
    patches = [[[t[a], t[b], 0.0], [t[a + 1], t[b], 0.0], [t[a + 1], t[b + 1], 0.0], [t[a], t[b + 1], 0.0]]
               for a in range(cuts) for b in range(cuts)]
    clean = np.array(patches)
    while True:
        noisy = clean + rng.normal(scale=1e-13 * size, size=clean.shape) * [1, 1, 0]
        cells = np.round((noisy - noisy.reshape(-1, 3).min(axis=0)) / (1e-9 * size))
        same = np.all(np.abs(clean[:, :, None, None] - clean[None, None]) == 0, axis=-1)   # (m, 4, m, 4)
        if np.all(~same | np.all(cells[:, :, None, None] == cells[None, None], axis=-1)):
            break
    colours = rng.uniform(0, 1, (len(patches), 3))
    return lists(noisy), [0] * len(patches), lists(colours)


def far_grid(size: float, cuts: int, offset: float, axis: int, rng: np.random.Generator) -> tuple[list, list, list]:
    """A square ``size`` wide cut into cuts × cuts patches, ``offset`` from the origin along ``axis``: which corners
    are one vertex must not depend on where the model sits (keys taken from the coordinates themselves, not from
    the model's own corner, pass 2^63 there; a scale taken across a point's coordinates is the offset)."""
    t = np.linspace(0.0, size, cuts + 1)
    flat = np.array([[[t[a], t[b], 0.0], [t[a + 1], t[b], 0.0], [t[a + 1], t[b + 1], 0.0], [t[a], t[b + 1], 0.0]]
                     for a in range(cuts) for b in range(cuts)])
    flat = np.roll(flat, axis, axis=-1)      # the square in the plane of the two other axes, shifted along ``axis``
    flat[..., axis] += offset
    return lists(flat), [0] * len(flat), lists(rng.uniform(0, 1, (len(flat), 3)))


def _triangle_beside_quad() -> tuple[list, list, list]:
    """A triangle (its last corner repeated) cut into patches beside a quad: a repeated corner is one vertex."""
    polygons = np.array([[[0, 0, 0], [1.5, 0, 0], [0, 1.5, 0], [0, 1.5, 0]], [[1.5, 0, 0], [1.5, 1.5, 0], [0, 1.5, 0],
                                                                           [0, 1.5, 0]]], float)
    patches, parent = truths.subdivide_by_hand(polygons, 0.8)
    return lists(patches), parent.tolist(), lists(np.random.default_rng(8).uniform(0, 1, (len(patches), 3)))


#: The hand-worked scene after its first shot with overshooting ω = 1.5: patch 0 keeps ΔB = (1 − ω)·E, negative.
OVERSHOT = [[-5.0, -2.5, -1.0], [4.5, 1.8, 0.54], [2.4, 0.3, 0.36]]

TESTS = [
    subdivide_test("R1 subdivide: the Cornell box at 100 mm", 5, scene_quads("cornell-box"), 100.0),
    subdivide_test("R1 subdivide: a triangle and a quad", 4,
                   [[[0, 0, 0], [4, 0, 0], [0, 3, 0], [0, 3, 0]], [[0, 0, 1], [2, 0, 1], [2, 0.5, 1], [0, 1, 1]]], 1.0),
    subdivide_test("R1 subdivide: max_edge 0 keeps the quads", 1, scene_quads("furnace"), 0.0),
    subdivide_test("R1 subdivide: a negative max_edge keeps the quads too", 1, scene_quads("room", 4), -0.5),
    shoot_test("R2 shoot: the hand-worked emitter shoots", 5, HAND, 0),
    shoot_test("R2 shoot: a receiver shoots back, B and ΔB already set", 5, HAND, 1,
               radiosity=[[10.0, 5.0, 2.0], [3.0, 1.2, 0.36], [1.6, 0.2, 0.24]],
               unshot=[[0.0, 0.0, 0.0], [3.0, 1.2, 0.36], [1.6, 0.2, 0.24]]),
    by_hand_test("R3 progressive_refinement: the hand-worked scene, 4 shots (patch 1 shoots twice)", 4, HAND, 4),
    by_hand_test("R3 progressive_refinement: the hand-worked scene to 1e-6", 4, HAND, 10_000, tolerance=1e-6),
    by_hand_test("R3 progressive_refinement: six patches, 14 shots, each sweep in the order of its keys at its start",
                 2, SIX, 14),
    by_hand_test("R3 progressive_refinement: the hand-worked scene overshooting (ω = 1.5), 6 shots", 3, HAND, 6,
                 overshoot=1.5),
    by_hand_test("R3 progressive_refinement: a closed random system to 1e-4, which stops in the middle of a sweep "
                 "(the unshot energy checked before every shot, not only as a sweep starts)", 3, CLOSED_FIVE, 100_000,
                 tolerance=1e-4),
    furnace_test("R3 progressive_refinement: the furnace, ρ = 0.9", 3, 0.9, 1e-4),
    scene_solve_test("R3 progressive_refinement: the Cornell box converges to the direct solve", 4, CORNELL, 140.0),
    ambient_test("R4 ambient_term: the hand-worked scene after one shot", 6, HAND["areas"], HAND["reflectance"],
                 [[0.0, 0.0, 0.0], [3.0, 1.2, 0.36], [1.6, 0.2, 0.24]]),
    ambient_test("R4 ambient_term: after an overshot shot (a negative ΔB counts with its sign)", 2, HAND["areas"],
                 HAND["reflectance"], OVERSHOT),
    vertex_test("R5 vertex_colors: three walls of the furnace, 3 × 3 patches each", 2, *GRID, "grid"),
    vertex_test("R5 vertex_colors: a square 1 wide cut 2 × 2, 2^34 from the origin along x", 1,
                *far_grid(1.0, 2, 2.0 ** 34, 0, np.random.default_rng(14)), "far"),
    vertex_test("R5 vertex_colors: a triangle (repeated corner) beside a quad", 1, *_triangle_beside_quad(), "triangle"),
    vertex_test("R5 vertex_colors: a floor 1,000 wide cut 3 × 3, shared corners apart by rounding noise", 1,
                *noisy_grid(1000.0, 3, np.random.default_rng(13)), "noisy"),
    vertex_test("R5 vertex_colors: a hexagon fanned into triangles, each repeating a corner the next one shares", 3,
                *fan_patches(6, 1.0), lists(np.random.default_rng(9).uniform(0, 1, (4, 3))), "fan"),
    render_test("R5 render: the Cornell box", 5, CORNELL, (128, 128), 100.0),
    solve_again_test("R6 solve_again: the light recoloured, every row known from the earlier solve: none computed", 4,
                 random_system(6, seed=21), "all"),
    solve_again_test("R6 solve_again: a black patch painted white: only rows not known are computed", 2,
                 random_system(7, seed=22), "painted"),
    solve_again_test("R6 solve_again: nothing known, overshooting 1.5: each shooter's row computed once", 2,
                 random_system(5, seed=23), "none", overshoot=1.5),
    largest_first_test("R7 shoot_largest_first (optional): six patches, 14 shots, each from the largest key now", 2,
                       SIX, 14),
    largest_first_test("R7 shoot_largest_first (optional): nothing reflects (ρ = 0), tolerance 0: it stops once "
                       "every key is 0", 1, absorbing(SIX), 100, vary=variant(variants.absorbing)),
    largest_first_test("R7 shoot_largest_first (optional): the hand-worked scene overshooting (ω = 1.5) to 1e-6", 2,
                       HAND, 10_000, tolerance=1e-6, overshoot=1.5),
]
