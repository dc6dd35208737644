"""Substructuring (patches shoot to elements): the engine behind the benchmark's substructured rows.

Truths: plain progressive refinement (one element per patch must reproduce it shot for shot),
the white furnace (energy: mean B = E/(1 − ρs), s the rows' sum), the patch-centred hemicube against the
engine's own row at the same place, and the element system's direct solve.
"""
from __future__ import annotations

import numpy as np
import pytest

from cs451.stages.radiosity import bench_substructuring as S
from cs451.errors import KitError
from cs451.formfactors import HemicubeFormFactors
from cs451.impl import load_impl, resolve_impl
from cs451.patches import patch_areas

from bench.meshes import subdivide_uniform
from cs451.scene import load_scene
from cs451.stages import radiosity as R
from cs451.stages.radiosity import solvers
from cs451 import patching as P
from cs451.stages.hemicube import calls
from test_radiosity import random_scene

REF = load_impl(resolve_impl("reference", "radiosity"), "radiosity")
HEMICUBE = load_impl(resolve_impl("reference", "hemicube"), "hemicube")


def test01_one_element_per_patch_is_plain_progressive_refinement():
    F, A, rho, E = random_scene(30, seed=5)
    n = len(A)
    plain = R.solve_progressive(REF, solvers.MatrixRows(F), A, rho, E, tolerance=1e-6, use_ambient=False)
    sub = S.solve_substructured(solvers.MatrixRows(F), np.arange(n), A, rho, E, tolerance=1e-6)
    assert sub.converged and plain.converged
    assert sub.order == plain.order
    assert np.allclose(sub.radiosity, plain.radiosity, rtol=1e-12, atol=1e-14)


def test02_patch_centred_row_is_the_engines_own_row_at_that_place():
    patches = R.make_patches(load_scene("cornell-box"), REF, 140.0)
    for rotate in (False, True):
        engine = HemicubeFormFactors(patches.quads, calls(HEMICUBE), resolution=32, rotate=rotate, proximity="none")
        for i in (0, 40, 100):
            got = engine.rows_at(engine.centers[i], engine.normals[i], ids=[i])[0]
            assert np.array_equal(got, engine.row(i))


@pytest.fixture(scope="module")
def furnace_elements():
    quads, _, _, _ = P.radiosity_surfaces(load_scene("furnace"))
    patches, _ = subdivide_uniform(quads, 2)
    elements, parent = S.split_patches(patches, 2)
    engine = HemicubeFormFactors(elements, calls(HEMICUBE), resolution=32, proximity="none")
    return patches, elements, parent, S.PatchToElementRows(engine, patches, parent)


@pytest.mark.parametrize("rho", [0.5, 0.9])
def test03_furnace_mean_radiosity_is_e_over_one_minus_rho_s(furnace_elements, rho):
    patches, elements, parent, rows = furnace_elements
    a = patch_areas(elements)
    m = len(elements)
    sol = S.solve_substructured(rows, parent, a, np.full((m, 3), rho), np.ones((m, 3)), tolerance=1e-6)
    assert sol.converged and rows.counters["rows_computed"] <= len(patches)
    # every row sums to the delta form factors' total s (1.0005 at resolution 32, not exactly 1): B = E/(1 − ρs)
    s = rows.row(0).sum()
    mean = (sol.radiosity[:, 0] * a).sum() / a.sum()
    assert abs(mean * (1 - rho * s) - 1) < 1e-5
    for p in range(len(patches)):
        row = rows.row(p)
        assert row[parent == p].sum() == 0.0             # a patch never sees its own elements
        assert abs(row.sum() - 1.0) < 1e-3              # a closed box: everything it sends arrives


def test04_cornell_box_substructured_approaches_the_element_solution_with_a_row_per_patch():
    patches = R.make_patches(load_scene("cornell-box"), REF, 140.0)
    elements, parent = S.split_patches(patches.quads, 2)
    a = patch_areas(elements)
    rho, E = patches.reflectance[parent], patches.emission[parent]
    engine = HemicubeFormFactors(elements, calls(HEMICUBE), resolution=32, proximity="none")
    rows = S.PatchToElementRows(engine, patches.quads, parent)
    sol = S.solve_substructured(rows, parent, a, rho, E, tolerance=1e-6)
    assert sol.converged
    assert rows.counters["rows_computed"] <= len(patches) < len(elements)
    # the left wall's published quad is warped: its patches' own elements poke above the patch's plane
    left = np.flatnonzero(patches.parent == 4)
    assert rows.lift[left].max() > 0
    assert all(rows.row(int(p)).sum() > 0.5 for p in left)
    # rows rendered together are the rows rendered one by one (each patch keeps its own rotation), up to where
    # each hemicube's tile lands in the atlas (float32 placement moves a few cells: measured 0.0008 of a row)
    together = S.PatchToElementRows(engine, patches.quads, parent).matrix()
    one_by_one = np.stack([rows.row(p) for p in range(len(patches.quads))])
    assert np.abs(together - one_by_one).sum(axis=1).max() < 5e-3
    truth = solvers.solve_direct(solvers.shooting_matrix(engine.matrix(), a), rho, E)
    lit = E.max(axis=1) == 0
    error = (np.abs(sol.radiosity - truth)[lit] * a[lit, None]).sum() / (truth[lit] * a[lit, None]).sum()
    assert error < 0.10
    with pytest.raises(KitError, match="positive integer"):
        S.split_patches(patches.quads, 0)
    with pytest.raises(KitError, match="each of the"):
        S.PatchToElementRows(engine, patches.quads, parent[:-1])
