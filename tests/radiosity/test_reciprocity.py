"""Reciprocal form factors (cs451/stages/radiosity/reciprocity.py) and the furnace, patch by patch, on hemicube rows.

Truths: A F' symmetric and F' keeping F's row sums (checked directly on the matrix); the white furnace
B = E/(1 − ρ) (autograder/radiosity/truth.py), which shooting gives on every patch only when the rows are
reciprocal (notes §2.2, eq. 3): a receiver j gets Σ_i F_ij A_i/A_j of a uniform field. Without the option the
same hemicube rows leave single patches percents off, which these tests also show (so they can fail).
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from autograder.radiosity import truth
from cs451.stages.radiosity import solvers as S
from cs451.errors import InputError, KitError
from cs451.formfactors import HemicubeFormFactors
from cs451.stages.radiosity.reciprocity import MATRICES, describe, enforce_reciprocity, reciprocity_error
from cs451.impl import load_impl, resolve_impl
from cs451.scene import BUNDLED_DIR, load_scene, parse_scene
from cs451.stages import radiosity as R

REF = load_impl(resolve_impl("reference", "radiosity"), "radiosity")
UNIFORM = 0.005            # the bar: every patch within 0.5% of E/(1 − ρ)


def closed_random(n: int, seed: int = 12345) -> tuple[np.ndarray, np.ndarray]:
    """A random closed 'scene': positive areas, rows summing to 1, a third of the pairs not seeing each other,
    F_ii = 0, and rows far from reciprocal (multiplicative noise of ±30% after making them so)."""
    rng = np.random.default_rng(seed)
    areas = rng.uniform(0.2, 3.0, n)
    K = rng.uniform(0.0, 1.0, (n, n)) * (rng.uniform(size=(n, n)) > 0.33)
    K = np.triu(K, 1)
    K = K + K.T                                             # symmetric: A F reciprocal before the noise
    F = K / areas[:, None]
    F *= rng.uniform(0.7, 1.3, (n, n))
    return F / F.sum(axis=1, keepdims=True), areas


def box_scene(dims: tuple[float, float, float], albedo: float, patch_size: float, **options) -> object:
    """The furnace's closed box stretched to ``dims``, of uniform ``albedo``, emitting 1."""
    data = json.loads((BUNDLED_DIR / "furnace.json").read_text())
    for o in data["objects"]:
        o["vertices"] = [[v[k] * dims[k] for k in range(3)] for v in o["vertices"]]
    data["materials"]["wall"]["diffuse"] = [albedo] * 3
    data["options"]["radiosity"] = {"patch_size": patch_size, "tolerance": 1e-4, **options}
    return parse_scene(data, "box")


def furnace_errors(scene, reciprocity: bool, rows=None, **overrides) -> tuple[np.ndarray, S.Solution, object]:
    """Per-patch B / (E/(1 − ρ)) − 1 through the hemicube engine and the reference's shooting loop."""
    opts = R.STAGE.options(scene, reciprocity=reciprocity, **overrides)
    patches = R.make_patches(scene, REF, opts.patch_size)
    if rows is None:
        rows = R.hemicube_formfactors(patches.quads, opts.resolution, opts.proximity, batch=256)
    sol = R.solve(patches, REF, opts, rows)
    rho = float(patches.reflectance[0, 0])
    return sol.radiosity / truth.furnace(1.0, rho) - 1, sol, rows


# --- the correction on a matrix ---------------------------------------------------------------------

def test01_corrected_matrix_is_reciprocal_and_keeps_every_row_sum():
    F, areas = closed_random(120)
    assert reciprocity_error(F, areas)["max"] > 0.2, "the test matrix must start far from reciprocal"
    Fc, report = enforce_reciprocity(F, areas)
    AF = Fc * areas[:, None]
    assert np.abs(AF - AF.T).max() <= 1e-14 * AF.max(), "A F' must be symmetric"
    assert np.abs(Fc.sum(axis=1) - F.sum(axis=1)).max() <= 1e-10, "every row keeps its sum (energy is conserved)"
    assert (Fc >= 0).all() and np.array_equal(Fc == 0, (F == 0) & (F.T == 0)), "zeros stay zeros, and only they"
    assert report["reciprocity_after"]["max"] < 1e-12 < report["reciprocity_before"]["max"]
    assert report["row_sum_error"] <= report["tolerance"] and report["iterations"] > 0
    assert 0 < report["entry_change_mean"] <= report["entry_change_max"] and 0 < report["energy_moved"] < 1
    assert "Sinkhorn iterations" in describe(report) and "\n" not in describe(report)


def test02_reciprocal_rows_are_left_as_they_are_and_open_rows_keep_their_sums():
    F, areas = closed_random(40, seed=7)
    Fc, _ = enforce_reciprocity(F, areas)
    again, report = enforce_reciprocity(Fc, areas)
    assert np.allclose(again, Fc, rtol=1e-10, atol=0) and report["iterations"] == 0
    open_rows = F * np.linspace(0.5, 0.95, len(F))[:, None]          # an open scene: some light leaves
    Fo, _ = enforce_reciprocity(open_rows, areas)
    assert np.allclose(Fo.sum(axis=1), open_rows.sum(axis=1), rtol=1e-10)
    assert reciprocity_error(Fo, areas)["max"] < 1e-12


def test03_a_row_of_sum_zero_is_seen_by_none_and_the_others_keep_their_sums():
    F, areas = closed_random(30, seed=3)
    F[5] = 0.0                                            # patch 5 sees nothing (faces an opening, a blind hemicube)
    Fc, report = enforce_reciprocity(F, areas)
    assert report["empty_rows"] == 1 and "rows of sum 0" in describe(report)
    assert not Fc[5].any() and not Fc[:, 5].any()
    assert np.allclose(Fc.sum(axis=1), F.sum(axis=1), rtol=1e-10, atol=0)


# --- the furnace end to end through the hemicube engine -----------------------------------------------

def test04_bundled_furnace_is_uniform_per_patch_with_the_option_and_not_without():
    scene = load_scene("furnace")
    assert R.STAGE.options(scene).reciprocity, "the bundled furnace turns the option on (the handout says so)"
    without, plain, rows = furnace_errors(scene, False)
    assert isinstance(rows, HemicubeFormFactors)
    assert np.abs(without).max() > 2 * UNIFORM, f"hemicube rows alone: {np.abs(without).max():.2%} (expected percents)"
    errors, sol, _ = furnace_errors(scene, True, rows)
    assert np.abs(errors).max() < UNIFORM, f"patches off by up to {np.abs(errors).max():.2%} with reciprocity"
    assert sol.converged and sol.reciprocity is not None and plain.reciprocity is None
    assert "reciprocity enforced on 96 rows" in sol.message and sol.reciprocity["reciprocity_before"]["max"] > 0.01
    assert sol.counters["hemicubes_rendered"] == len(errors) and sol.counters["shots"] == len(sol.order)


@pytest.mark.parametrize("solver", ["progressive", "direct"])
def test05_box_1x2x3_of_albedo_08_gives_five_on_every_patch_with_the_option(solver):
    scene = box_scene((1.0, 2.0, 3.0), 0.8, 0.5)
    assert truth.furnace(1.0, 0.8) == pytest.approx(5.0)
    without, _, rows = furnace_errors(scene, False, resolution=64, solver=solver)
    errors, sol, _ = furnace_errors(scene, True, rows, resolution=64, solver=solver)
    assert len(errors) == 88 and sol.converged, sol.message
    assert np.abs(without).max() > 2 * UNIFORM, f"hemicube rows alone: {np.abs(without).max():.2%}"
    assert np.abs(errors).max() < UNIFORM, f"patches off by up to {np.abs(errors).max():.2%} with reciprocity"
    spread = errors.max() - errors.min()
    assert spread < 1e-3, f"B must be uniform (within the rows' closure error), spread {spread:.2%}"


def test06_the_option_costs_the_whole_matrix_in_the_estimate():
    data = json.loads((BUNDLED_DIR / "furnace.json").read_text())
    on = R.STAGE.estimate(parse_scene(data, "on"))[0]
    data["options"]["radiosity"]["reciprocity"] = False
    off = R.STAGE.estimate(parse_scene(data, "off"))[0]
    geometry = R.cost.PATCH_BYTES * R.cost.patch_count(parse_scene(data, "off"), 0.25)
    assert on.bytes - geometry == pytest.approx((1 + MATRICES) * (off.bytes - geometry))
    assert "reciprocity" in on.what and "reciprocity" not in off.what


# --- bad input --------------------------------------------------------------------------------------

@pytest.mark.parametrize("F, areas, message", [
    (np.zeros((3, 4)), np.ones(3), r"square \(n, n\) matrix, got shape \(3, 4\)"),
    (np.zeros(3), np.ones(3), "square"),
    (np.full((2, 2), 0.5), np.array([1.0, 0.0]), "patch 1 has area 0"),
    (np.full((2, 2), 0.5), np.array([1.0, -2.0]), "patch 1 has area -2"),
    (np.full((2, 2), 0.5), np.ones(3), r"areas must have shape \(2,\)"),
    (np.array([[0.0, np.nan], [0.5, 0.0]]), np.ones(2), "form factors contain NaN"),
    (np.array([[0.0, -0.1], [0.5, 0.0]]), np.ones(2), r"F\[0, 1\] = -0.1 is negative"),
    (np.array([[0.0, 1.0], [0.5, 0.0]]), np.ones(2), "no reciprocal form factors keep these row sums"),
])
def test07_bad_input_is_refused_in_one_line(F, areas, message):
    with pytest.raises(KitError, match=message) as err:
        enforce_reciprocity(F, areas)
    assert "\n" not in str(err.value) and str(err.value).startswith("reciprocity: ")


def test08_a_bad_option_names_its_json_path():
    data = json.loads((BUNDLED_DIR / "furnace.json").read_text())
    data["options"]["radiosity"]["reciprocity"] = "yes"
    with pytest.raises(InputError, match="options.radiosity.reciprocity") as err:
        R.STAGE.options(parse_scene(data, "bad"))
    assert "\n" not in str(err.value)
