"""Stage 4: the reference radiosity solver against independent truths.

Truths (autograder/radiosity/truth.py, sharing no code with reference/ or the hemicube):
the white furnace B = E/(1 − ρ) on exact form factors (Howell's cube, Lambert's
contour formula for subdivided faces), energy conservation shot by shot,
progressive refinement against the direct solve of (I − ρF)B = E, hand-worked
shooting, brute-force vertex colours; the kit's counters for skipped work; bad input.
"""
from __future__ import annotations

import copy
import json

import numpy as np
import pytest

from autograder.radiosity import truth
from cs451.errors import InputError, KitError
from cs451.impl import load_impl, resolve_impl
from cs451.patches import patch_areas, patch_normals

from bench.meshes import subdivide_uniform
from cs451.scene import BUNDLED_DIR, load_scene, parse_scene
from cs451.stages import radiosity as R
from cs451.stages.radiosity import solvers as S
from cs451 import patching as P

REF = load_impl(resolve_impl("reference", "radiosity"), "radiosity")
FURNACE = json.loads((BUNDLED_DIR / "furnace.json").read_text())


@pytest.fixture(scope="module")
def furnace_cube():
    """The furnace box, one patch per face, with Howell's exact form factors."""
    quads, _, _, _ = P.radiosity_surfaces(load_scene("furnace"))
    return quads, truth.cube_formfactors(patch_normals(quads))


@pytest.fixture(scope="module")
def furnace_fine():
    """The furnace box, 2 × 2 patches per face, with Lambert's contour formula (rows sum to 1)."""
    quads, _, _, _ = P.radiosity_surfaces(load_scene("furnace"))
    fine, _ = subdivide_uniform(quads, 2)
    return fine, truth.contour_formfactors(fine, 6)


def uniform(n, value):
    return np.full((n, 3), float(value))


# --- the white furnace -------------------------------------------------------------

@pytest.mark.parametrize("rho", [0.5, 0.9, 0.99])
@pytest.mark.parametrize("overshoot", [1.0, 1.5])
def test01_furnace_cube_gives_e_over_one_minus_rho_within_the_tolerance(furnace_cube, rho, overshoot):
    quads, F = furnace_cube
    n, tol = len(quads), 1e-4
    sol = R.solve_progressive(REF, S.MatrixRows(F), patch_areas(quads), uniform(n, rho), uniform(n, 1.0),
                              tolerance=tol, overshoot=overshoot, use_ambient=False)
    assert sol.converged, sol.message
    err = np.abs(sol.radiosity / truth.furnace(1.0, rho) - 1)
    assert err.max() <= tol, f"furnace ρ={rho}: relative error {err.max():.2e} above the tolerance {tol}"


@pytest.mark.parametrize("rho", [0.5, 0.9, 0.99])
def test02_furnace_subdivided_on_contour_form_factors(furnace_fine, rho):
    quads, F = furnace_fine
    assert np.allclose(F.sum(axis=1), 1.0, atol=1e-12)
    n, tol = len(quads), 1e-4
    sol = R.solve_progressive(REF, S.MatrixRows(F), patch_areas(quads), uniform(n, rho), uniform(n, 2.0),
                              tolerance=tol, overshoot=1.5, use_ambient=False)
    err = np.abs(sol.radiosity / truth.furnace(2.0, rho) - 1)
    assert sol.converged and err.max() <= tol, f"ρ={rho}: {sol.message}; error {err.max():.2e}"


def test03_furnace_ambient_preview_is_exact_before_the_first_shot(furnace_fine):
    quads, F = furnace_fine
    n, rho = len(quads), 0.8
    A = patch_areas(quads)
    preview = uniform(n, 1.0) + uniform(n, rho) * R.call_ambient(REF, A, uniform(n, rho), uniform(n, 1.0))
    assert np.allclose(preview, truth.furnace(1.0, rho), rtol=1e-12)
    worse = []

    def on_shot(k, i, B, dB):
        amb = np.asarray(REF.ambient_term(A, uniform(n, rho), dB))
        plain, with_amb = np.abs(B - 5.0).mean(), np.abs(B + rho * amb - 5.0).mean()
        if with_amb > plain + 1e-9:
            worse.append(k)

    REF.progressive_refinement(S.MatrixRows(F).row, A, uniform(n, rho), uniform(n, 1.0), 1e-3, 200, 1.0, on_shot)
    assert not worse, f"the ambient preview was further from the answer than B alone after shots {worse[:5]}"


# --- energy -----------------------------------------------------------------------------

def test04_energy_balances_after_every_shot(furnace_fine):
    """Closed scene: unshot + absorbed = emitted, at every shot (absorbed_j = (1 − ρ_j)/ρ_j · (B_j − E_j) · A_j)."""
    quads, F = furnace_fine
    n = len(quads)
    rng = np.random.default_rng(12345)
    rho = rng.uniform(0.2, 0.9, (n, 3))
    E = np.zeros((n, 3))
    E[[0, 7]] = [[3.0, 2.0, 1.0], [0.5, 1.0, 4.0]]
    A = patch_areas(quads)
    emitted = (E * A[:, None]).sum(axis=0)
    worst = []

    def on_shot(k, i, B, dB):
        absorbed = ((1 - rho) / rho * (B - E) * A[:, None]).sum(axis=0)
        unshot = (dB * A[:, None]).sum(axis=0)
        worst.append(np.abs(unshot + absorbed - emitted).max() / emitted.max())

    B, dB, order = REF.progressive_refinement(S.MatrixRows(F).row, A, rho, E, 1e-6, 100_000, 1.0, on_shot)
    assert len(worst) == len(order) > n
    assert max(worst) < 1e-12, f"energy is not conserved: imbalance {max(worst):.2e} of the emitted energy"
    absorbed = ((1 - rho) / rho * (B - E) * A[:, None]).sum(axis=0)
    assert np.allclose(absorbed, emitted, rtol=2e-6), "at convergence everything emitted is absorbed"


# --- agreement with the direct solve ---------------------------------------------------------

def random_scene(n, seed):
    """A random system with reciprocity (A_i F_ij = A_j F_ji) and row sums below 1 (an open scene)."""
    rng = np.random.default_rng(seed)
    A = rng.uniform(0.5, 2.0, n)
    S = rng.uniform(0, 1, (n, n)) ** 4
    S = (S + S.T) / 2
    np.fill_diagonal(S, 0)
    F = S / A[:, None]
    F /= F.sum(axis=1).max() * 1.05
    rho = rng.uniform(0.0, 0.95, (n, 3))
    E = np.where(rng.random((n, 1)) < 0.1, rng.uniform(0, 5, (n, 3)), 0.0)
    E[0] = [1.0, 2.0, 3.0]
    return F, A, rho, E


@pytest.mark.parametrize("overshoot", [1.0, 1.6])
def test05_progressive_refinement_converges_to_the_direct_solve(overshoot):
    F, A, rho, E = random_scene(60, seed=7)
    want = truth.direct(F, rho, E)
    sol = R.solve_progressive(REF, S.MatrixRows(F), A, rho, E, tolerance=1e-8, overshoot=overshoot, use_ambient=False)
    assert sol.converged, sol.message
    assert np.abs(sol.radiosity - want).max() <= 1e-6 * want.max()


@pytest.mark.parametrize("method", ["jacobi", "gauss-seidel"])
def test06_full_matrix_solvers_agree_with_the_direct_solve(method):
    F, A, rho, E = random_scene(40, seed=3)
    want = truth.direct(F, rho, E)
    assert np.allclose(S.solve_direct(F, rho, E), want, rtol=1e-10, atol=1e-12)
    sol = S.solve_iterative(method, F, A, rho, E, tolerance=1e-9)
    assert sol.converged and np.abs(sol.radiosity - want).max() <= 1e-7 * want.max(), sol.message


@pytest.fixture(scope="module")
def cornell_rows():
    """The Cornell box at 140 mm and its hemicube rows (resolution 32), shared by the tests that need every row."""
    patches = R.make_patches(load_scene("cornell-box"), REF, 140.0)
    return patches, R.hemicube_formfactors(patches.quads, 32)


def test07_cornell_box_on_hemicube_rows_converges_to_the_direct_solve(cornell_rows):
    patches, rows = cornell_rows
    sol = R.solve_progressive(REF, rows, patches.areas, patches.reflectance, patches.emission, tolerance=1e-7,
                              use_ambient=False)
    F, A = rows.matrix(), patches.areas
    shooting = (F * A[:, None] / A[None, :]).T            # F̃_ji = F_ij A_i / A_j: the rows that shoot
    want = truth.direct(shooting, patches.reflectance, patches.emission)
    rel = np.abs(sol.radiosity - want).sum() / want.sum()
    assert sol.converged and rel < 1e-6, f"{sol.message}; differs from the direct solve by {rel:.2e}"


# --- hand-worked shooting ----------------------------------------------------------------------

HAND = {  # three patches: an emitter over two receivers, reciprocity A_i F_ij = A_j F_ji
    "F": [[0.0, 0.3, 0.2], [0.6, 0.0, 0.1], [0.2, 0.05, 0.0]],
    "areas": [2.0, 1.0, 2.0],
    "reflectance": [[0.0, 0.0, 0.0], [0.5, 0.4, 0.3], [0.8, 0.2, 0.6]],
    "emission": [[10.0, 5.0, 2.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]],
}


def test08_one_shot_matches_the_hand_worked_numbers():
    F = np.array(HAND["F"])
    B, dB = R.call_shoot(REF, 0, F[0], np.array(HAND["areas"]), np.array(HAND["reflectance"]),
                    np.array(HAND["emission"]), np.array(HAND["emission"]))
    # patch 1: ρ ΔB_0 F_01 A_0/A_1 = (0.5·10, 0.4·5, 0.3·2) · 0.3 · 2 = (3, 1.2, 0.36)
    assert np.allclose(B[1], [3.0, 1.2, 0.36]) and np.allclose(dB[1], [3.0, 1.2, 0.36])
    # patch 2: (0.8·10, 0.2·5, 0.6·2) · 0.2 · 1 = (1.6, 0.2, 0.24)
    assert np.allclose(B[2], [1.6, 0.2, 0.24])
    assert np.allclose(dB[0], 0.0) and np.allclose(B[0], HAND["emission"][0])


@pytest.mark.parametrize("shots", [1, 2, 3, 5, 40])
def test09_shot_order_and_values_match_the_loop_worked_by_hand(shots):
    want_B, want_dB, want_order = truth.progressive_by_hand(**HAND, tolerance=0.0, max_shots=shots)
    B, dB, order = REF.progressive_refinement(S.MatrixRows(np.array(HAND["F"])).row, np.array(HAND["areas"]),
                                              np.array(HAND["reflectance"]), np.array(HAND["emission"]), 0.0, shots,
                                              1.0, None)
    assert list(order) == want_order
    assert np.allclose(B, want_B, rtol=1e-12) and np.allclose(dB, want_dB, rtol=1e-12, atol=1e-15)


# --- skipping what a scene does not need ----------------------------------------------------------

def cornell(**changes):
    data = json.loads((BUNDLED_DIR / "cornell-box.json").read_text())
    data["options"]["radiosity"] = {"patch_size": 140.0, "resolution": 32, **changes}
    return parse_scene(data, "cornell")


def test10_rows_only_for_shooters_and_none_for_a_new_light_colour():
    scene = cornell()
    patches = R.make_patches(scene, REF, 140.0)
    rows = R.hemicube_formfactors(patches.quads, 32)
    first = R.solve_progressive(REF, rows, patches.areas, patches.reflectance, patches.emission, 0.2)
    c = first.counters
    assert c["rows_computed"] == c["distinct_shooters"] == len(set(first.order)) < len(patches)
    # one hemicube a row, and k × k more for a row blind from its patch's centre (under a block)
    assert c["hemicubes_rendered"] == c["rows_computed"] + R.RESAMPLE_BLIND ** 2 * c["blind_rows_resampled"]
    rendered = rows.counters["hemicubes_rendered"]
    bluer = patches.emission * np.array([0.2, 0.5, 3.0])            # a new light colour: same geometry
    second = R.solve_progressive(REF, rows, patches.areas, patches.reflectance * 0.9, bluer, 0.2)
    assert rows.counters["hemicubes_rendered"] == rendered, "re-solving with new colours rendered hemicubes"
    assert second.radiosity[:, 2].sum() > first.radiosity[:, 2].sum()


def test11_zero_albedo_patches_receive_nothing_and_never_shoot(furnace_fine):
    quads, F = furnace_fine
    n = len(quads)
    rho = uniform(n, 0.6)
    rho[5:12] = 0.0
    E = np.zeros((n, 3))
    E[0] = 1.0
    rows = S.MatrixRows(F)
    sol = R.solve_progressive(REF, rows, patch_areas(quads), rho, E, 1e-6)
    assert not set(sol.order) & set(range(5, 12)), "a black patch shot"
    assert np.all(sol.radiosity[5:12] == 0.0) and rows.counters["rows_computed"] == n - 7


# --- bad input --------------------------------------------------------------------------------------

def furnace_variant(**material):
    data = copy.deepcopy(FURNACE)
    data["materials"]["wall"].update(material)
    return data


def test12_albedo_one_in_a_closed_scene_is_refused():
    scene = parse_scene(furnace_variant(diffuse=[1.0, 0.5, 0.5]), "furnace-white")
    with pytest.raises(InputError, match="no solution"):
        R.make_patches(scene, REF, 0.5)
    # one perfectly white wall among grey ones still has a solution (the others absorb): allowed, and it converges
    data = furnace_variant()
    data["materials"]["white"] = {**data["materials"]["wall"], "diffuse": [1.0, 1.0, 1.0]}
    data["objects"][0]["material"] = "white"
    quads, rho, E, _ = P.radiosity_surfaces(parse_scene(data, "one-white-wall"))
    assert P.is_closed(quads) and rho[0].min() == 1.0
    F = truth.cube_formfactors(patch_normals(quads))
    sol = R.solve_progressive(REF, S.MatrixRows(F), patch_areas(quads), rho, E, tolerance=1e-6)
    assert sol.converged and np.allclose(sol.radiosity, truth.direct(F, rho, E), rtol=1e-5)


@pytest.mark.parametrize("field,value,message", [
    ("emission", [-1.0, 0, 0], "emission"),
    ("diffuse", [1.2, 0.5, 0.5], "diffuse"),
])
def test13_bad_materials_are_refused_with_the_json_path(field, value, message):
    with pytest.raises(InputError, match=f"materials.wall.{message}"):
        parse_scene(furnace_variant(**{field: value}), "bad")


def test14_bad_arrays_are_refused():
    F, A, rho, E = random_scene(5, seed=1)
    for what, args in {"NaN": (A, rho, np.where(E > 0, np.nan, E)), "negative emission": (A, rho, -np.abs(E) - 1),
                       "zero area": (np.where(A == A[0], 0.0, A), rho, E)}.items():
        with pytest.raises(KitError):
            R.solve_progressive(REF, S.MatrixRows(F), *args)
    scene = load_scene("furnace")
    p = R.make_patches(scene, REF, 0.0)
    p.areas[2] = 0.0
    with pytest.raises(InputError, match=r"objects\[2\].*zero area"):
        P.check_patches(p, "furnace")


def test15_a_solve_that_cannot_converge_says_so_and_returns_its_best_state(furnace_cube):
    quads, F = furnace_cube
    n = len(quads)
    sol = R.solve_progressive(REF, S.MatrixRows(F), patch_areas(quads), uniform(n, 0.999), uniform(n, 1.0),
                              tolerance=1e-6, max_shots=50)
    assert not sol.converged and sol.steps == 50 and sol.residual > 1e-6
    assert "did NOT converge" in sol.message and f"{sol.residual:.3g}" in sol.message
    assert np.all(sol.radiosity >= 1.0) and np.all(sol.radiosity < 1000.0)


# --- patches and vertex colours ----------------------------------------------------------------------

def test16_subdivision_keeps_area_orientation_and_edge_lengths():
    quads, _, _, _ = P.radiosity_surfaces(load_scene("cornell-box"))
    patches, parent = R.call_subdivide(REF, quads, 50.0)
    # the published red wall is not quite planar (its subdivided area differs by 3e-6); the others are exact
    assert np.allclose(np.bincount(parent, weights=patch_areas(patches)), patch_areas(quads), rtol=1e-5)
    # (its sub-patches' normals turn by up to 0.15°; every other wall's are its own to rounding)
    assert np.allclose(patch_normals(patches), patch_normals(quads)[parent], atol=5e-3)
    assert np.allclose(patch_normals(patches)[parent != 4], patch_normals(quads)[parent[parent != 4]], atol=1e-12)
    edges = np.linalg.norm(patches - np.roll(patches, -1, axis=1), axis=2)
    assert edges.max() <= 50.0 + 1e-9
    triangle = np.array([[[0, 0, 0], [4, 0, 0], [0, 3, 0], [0, 3, 0]]], dtype=float)
    small, _ = R.call_subdivide(REF, triangle, 1.0)
    assert np.isclose(patch_areas(small).sum(), 6.0) and np.all(patch_areas(small) > 0)


def test17_vertex_colours_are_the_average_of_adjoining_patches_of_the_same_polygon():
    quads, _, _, _ = P.radiosity_surfaces(load_scene("furnace"))
    patches, parent = R.call_subdivide(REF, quads[:3], 0.34)
    rng = np.random.default_rng(1)
    radiosity = rng.uniform(0, 1, (len(patches), 3))
    positions, colors, corners = R.call_vertex_colors(REF, patches, parent, radiosity)
    assert np.allclose(positions[corners], patches)
    assert np.allclose(colors[corners], truth.corner_colors_by_hand(patches, parent, radiosity))
    assert len(positions) == 3 * 16, "corners of different polygons must stay apart"


# --- display ---------------------------------------------------------------------------------------------

def test18_furnace_renders_its_radiance_and_conserves_its_energy_on_hemicube_rows():
    """On hemicube rows (closed box: rows sum to 1 within 1e-4, proximity fix off) the energy is exact,
    Σ A B = Σ A E / (1 − ρ); single patches are off by the rows' reciprocity error (about 2%) without the
    scene's ``reciprocity`` option (with it: tests/radiosity/test_reciprocity.py)."""
    scene = load_scene("furnace")
    opts = R.STAGE.options(scene, reciprocity=False)
    patches = R.make_patches(scene, REF, opts.patch_size)
    rows = R.hemicube_formfactors(patches.quads, opts.resolution, opts.proximity)
    sol = R.solve(patches, REF, opts, rows)
    mean = (sol.radiosity[:, 0] * patches.areas).sum() / patches.areas.sum()
    assert abs(mean / truth.furnace(1.0, 0.5) - 1) < 5e-4 + opts.tolerance
    assert np.abs(sol.radiosity / truth.furnace(1.0, 0.5) - 1).max() < 0.03
    image = R.draw_solution(scene, REF, patches, sol.display, (64, 64))
    assert image.shape == (64, 64, 3) and np.allclose(image, 2.0 / np.pi, rtol=0.03)
    assert np.allclose(image[..., 0], image[..., 2]), "a grey furnace renders grey"


def test19_every_solver_option_solves_the_same_equations(cornell_rows):
    """solver = progressive, jacobi, gauss-seidel, direct on the same hemicube rows: the same B within the tolerance."""
    scene = load_scene("cornell-box")
    patches, rows = cornell_rows
    results = {}
    for solver in R.SOLVERS:
        opts = R.STAGE.options(scene, solver=solver, tolerance=1e-6, patch_size=140.0, ambient=False)
        results[solver] = R.solve(patches, REF, opts, rows)
        assert results[solver].converged, results[solver].message
    want = results["direct"].radiosity
    for solver, sol in results.items():
        assert np.abs(sol.radiosity - want).sum() / want.sum() < 1e-5, solver
    assert rows.counters["rows_computed"] == len(patches), "the full-matrix solvers reuse the cached rows"
    assert rows.counters["hemicubes_rendered"] == (len(patches) + R.RESAMPLE_BLIND ** 2
                                                   * rows.counters["blind_rows_resampled"])


def test_the_papers_order_converges_to_the_same_answer_as_the_notes_sweeps():
    """The reference's R7 (always the current maximum, 1988; the bench's other order) against its sweeps (notes §2.5)."""
    import numpy as np

    from autograder.radiosity.public import SIX
    from cs451 import KIT_ROOT
    from cs451.impl import load_impl
    ref = load_impl(KIT_ROOT / "reference" / "radiosity", "radiosity")
    F = np.array(SIX["F"])
    args = (lambda i: F[i], np.array(SIX["areas"]), np.array(SIX["reflectance"]), np.array(SIX["emission"]))
    B_sweeps, _, sweeps = ref.progressive_refinement(*args, 1e-9, 100_000, 1.0, None)
    B_max, _, maximum = ref.shoot_largest_first(*args, 1e-9, 100_000, 1.0, None)
    np.testing.assert_allclose(B_max, B_sweeps, rtol=1e-7)
    assert sweeps[:4] == maximum[:4] and sweeps[4] != maximum[4]   # where the two orders part ways
    B_direct = np.column_stack([np.linalg.solve(np.eye(len(F)) - args[2][:, c:c + 1] * F, args[3][:, c])
                                for c in range(3)])
    np.testing.assert_allclose(B_sweeps, B_direct, rtol=1e-6)


class RowSource:
    """Rows of zeros as the hemicube engine hands them out, recording each batch asked for."""

    def __init__(self, n):
        self.n, self.batches, self.done = n, [], set()

    def has_row(self, i):
        return i in self.done

    def rows(self, indices):                  # as the hemicube engine's: the rows (k, n) of the indices
        self.batches.append(list(indices))
        self.done.update(indices)
        return np.zeros((len(indices), self.n))

    def row(self, i):
        if i not in self.done:
            self.rows([i])
        return np.zeros(self.n)


def test_rows_ahead_render_the_likely_next_shooters_in_the_same_batch():
    """A row not rendered yet comes with the rows of the patches with the most unshot energy (RowsAhead)."""
    import numpy as np

    from cs451.stages.radiosity.solvers import RowsAhead

    source = RowSource(6)
    areas = np.ones(6)
    emission = np.zeros((6, 3))
    emission[4] = 1.0
    ahead = RowsAhead(source, areas, emission, ahead=2)
    ahead.row(4)                                  # only patch 4 has unshot energy: nothing to render ahead
    assert source.batches == [[4]]
    unshot = np.array([[0.0] * 3, [0.1] * 3, [0.5] * 3, [0.0] * 3, [0.0] * 3, [0.3] * 3])
    ahead.seen(unshot)
    ahead.row(2)                                  # then 5 and 1, the largest keys not rendered
    assert source.batches[-1] == [2, 5, 1]
    ahead.row(5)                                  # rendered ahead: no new batch
    assert len(source.batches) == 2
    assert ahead.counters() == {"rows_ahead": 2, "rows_ahead_unused": 1}


def test_rows_ahead_grow_while_the_solve_keeps_asking_for_new_rows():
    """With ``most``, each batch is twice the last (plus one) up to most + 1 rows: few read-backs for a large scene."""
    import numpy as np

    from cs451.stages.radiosity.solvers import RowsAhead

    source = RowSource(100)
    ahead = RowsAhead(source, np.ones(100), np.ones((100, 3)), ahead=1, most=10)
    for i in range(100):
        if not source.has_row(i):
            ahead.row(i)
    assert [len(b) for b in source.batches[:5]] == [2, 4, 8, 11, 11]
    fixed = RowsAhead(RowSource(100), np.ones(100), np.ones((100, 3)), ahead=3)      # without most: a fixed size
    for i in range(12):
        fixed.row(i)
    assert [len(b) for b in fixed.source.batches] == [4, 4, 4]


def test_faces_are_culled_only_for_the_kits_own_stage_3(tmp_path, monkeypatch):
    """Culling assumes the reference's shaders; a student copy's own hemicube/ package is drawn unculled."""
    import shutil
    import cs451.impl as impl
    quads = np.array([[[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 0, 1], [0, 1, 1], [1, 1, 1], [1, 0, 1]]], float)
    trusted = R.hemicube_formfactors(quads, 16)
    assert trusted.row(0)[1] > 0.1
    assert trusted.cull and trusted.reduction == "atlas"          # llvmpipe here: cull, and sum on the CPU
    own = tmp_path / "hemicube"
    shutil.copytree(impl.KIT_ROOT / "reference" / "hemicube", own)
    monkeypatch.setattr(impl, "earlier_stage_impl", lambda stage: own)
    ff = R.hemicube_formfactors(quads, 16)
    assert ff.row(0)[1] > 0.1 and not ff.cull and ff.reduction == "stage"     # drawn as is, summed by its own H5
