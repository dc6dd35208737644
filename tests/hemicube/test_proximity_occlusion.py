"""The proximity fix (H6 integrated over the shooter) where something stands between two close patches.

Before the fix followed sight lines, the Cornell box's floor (whole polygons, the hemicube stage's default
scene) summed to 0.4687 where the area average is 0.698: the fix integrated H6 over the whole floor, the
part under the blocks included, and scaled by what the floor's centre saw. Truths here are independent of
the engine: Lambert's contour formula (the reference's H6 is not used for them) and Monte Carlo ray casting on
Embree from uniformly random points of each patch (the area average itself).
"""
from __future__ import annotations

import numpy as np
import pytest

from autograder.hemicube import truth
from cs451.formfactors import HemicubeFormFactors
from cs451.formfactors.visibility import Sightlines, occluders
from cs451.patches import patch_normals, scene_polygons
from cs451.scene import load_scene
from cs451.stages import hemicube as H


@pytest.fixture(scope="module")
def calls():
    from cs451.impl import load_impl, resolve_impl
    return H.calls(load_impl(resolve_impl("reference", "hemicube"), "hemicube"))


def _square(x0, x1, y0, y1, z, up=True):
    q = [[x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z]]
    return q if up else q[::-1]


def test01_occluders_never_miss_one():
    """Every quad that some segment from patch i to patch j crosses is among the candidates (random scenes)."""
    rng = np.random.default_rng(3)
    for _ in range(30):
        quads = rng.uniform(-1, 1, (12, 1, 3)) + rng.uniform(-0.6, 0.6, (12, 4, 3)) * [1, 1, 0]
        quads = quads.copy()
        quads[:, :, 2] = quads[:, :1, 2]                      # planar: each quad at its own height
        quads[:, 2] = quads[:, 1] + quads[:, 3] - quads[:, 0]  # a parallelogram
        quads[0, :, 2], quads[1, :, 2] = -1.5, 1.5             # shooter below, receiver above, facing each other
        for k, up in ((0, True), (1, False)):
            if (patch_normals(quads[k:k + 1])[0][2] > 0) != up:
                quads[k] = quads[k][::-1]
        normals = patch_normals(quads)
        found = set(occluders(quads, normals, 0, 1, 3.0).tolist())
        s, t = rng.random((2, 2000, 2))
        p = quads[0, 0] + s[:, :1] * (quads[0, 1] - quads[0, 0]) + s[:, 1:] * (quads[0, 3] - quads[0, 0])
        q = quads[1, 0] + t[:, :1] * (quads[1, 1] - quads[1, 0]) + t[:, 1:] * (quads[1, 3] - quads[1, 0])
        for k in range(2, 12):
            z = quads[k, 0, 2]
            u = (z - p[:, 2]) / (q[:, 2] - p[:, 2])
            x = p + u[:, None] * (q - p)
            a, b, d = quads[k, 0], quads[k, 1], quads[k, 3]
            m = np.linalg.solve(np.array([(b - a)[:2], (d - a)[:2]]).T, (x - a)[:, :2].T)
            crossed = ((m >= 0) & (m <= 1)).all(axis=0) & (u > 0) & (u < 1)
            if crossed.any():
                assert k in found, f"quad {k} blocks {crossed.sum()} segments but is not a candidate"


def test02_a_plate_hiding_half_the_receiver_hides_half_its_form_factor():
    """Under a 2 × 2 square 1 above, a plate just below its x > 0 half: the visible fraction seen from a point is
    F(point → the x < 0 half) / F(point → all of it), by Lambert's contour formula (exact)."""
    receiver = np.array(_square(-1, 1, -1, 1, 1.0, up=False), float)
    plate = np.array(_square(0, 1.2, -1.2, 1.2, 0.999, up=False), float)
    sight = Sightlines(plate[None], receiver, np.array([0, 0, -1.0]), np.array([0, 0, 1.0]), np.zeros(3))
    for point in ([0.0, 0.0, 0.0], [-0.4, 0.3, 0.0], [0.5, -0.2, 0.0]):
        exact = (truth.contour(point, [0, 0, 1], _square(-1, 0, -1, 1, 1.0))
                 / truth.contour(point, [0, 0, 1], _square(-1, 1, -1, 1, 1.0)))
        got = float(sight.fraction(np.array([point]))[0])
        assert got == pytest.approx(exact, abs=0.01), (point, got, exact)


def test03_nothing_between_sees_everything():
    receiver = np.array(_square(-1, 1, -1, 1, 1.0, up=False), float)
    beside = np.array(_square(3, 4, -1, 1, 0.5, up=False), float)    # a blocker beside the sight lines
    sight = Sightlines(beside[None], receiver, np.array([0, 0, -1.0]), np.array([0, 0, 1.0]), np.zeros(3))
    points = np.random.default_rng(0).uniform(-1, 1, (20, 3)) * [1, 1, 0]
    assert np.array_equal(sight.fraction(points), np.ones(20))


def _facing(quad, direction):
    """The quad, its corners reversed if needed so that its front faces ``direction``."""
    q = np.array(quad, float)
    return q if patch_normals(q[None])[0] @ direction > 0 else q[::-1]


def _occluded_floor():
    """A 2 × 2 floor, a 2 × 1 wall at its x = 1 edge, and a box standing on the floor (its top and four sides):
    the box hides part of the wall from part of the floor, and covers part of the floor, its centre included."""
    a, b, h = -0.2, 0.6, 0.5
    faces = [(_square(-1, 1, -1, 1, 0.0), [0, 0, 1]),                                 # floor
             ([[1, -1, 0], [1, -1, 1], [1, 1, 1], [1, 1, 0]], [-1, 0, 0]),            # wall
             (_square(a, b, -0.4, 0.4, h), [0, 0, 1]),                                # the box: top and sides
             ([[a, -0.4, 0], [a, 0.4, 0], [a, 0.4, h], [a, -0.4, h]], [-1, 0, 0]),
             ([[b, -0.4, 0], [b, 0.4, 0], [b, 0.4, h], [b, -0.4, h]], [1, 0, 0]),
             ([[a, -0.4, 0], [b, -0.4, 0], [b, -0.4, h], [a, -0.4, h]], [0, -1, 0]),
             ([[a, 0.4, 0], [b, 0.4, 0], [b, 0.4, h], [a, 0.4, h]], [0, 1, 0])]
    return np.array([_facing(q, d) for q, d in faces])


@pytest.fixture(scope="module")
def embree():
    return pytest.importorskip("embreex.rtcore_scene", reason="ray casting runs on Embree, an optional peer")


def test04_occluded_floor_and_wall_against_the_area_average(calls, embree):
    """The floor's row against Monte Carlo from random points of it (400,000 rays): the fix follows the box's
    shadow on the floor; the plain hemicube, standing at the floor's centre under the box, sees nothing."""
    from cs451.formfactors import formfactor_matrix_raycast
    quads = _occluded_floor()
    truth_rows = formfactor_matrix_raycast(quads, 400_000, seed=5, rows=[0, 1])
    ff = HemicubeFormFactors(quads, calls, resolution=128, proximity="contour")
    rows = ff.rows([0, 1])
    assert np.abs(rows - truth_rows).max() < 0.01, np.round(rows - truth_rows, 4)
    plain = HemicubeFormFactors(quads, calls, resolution=128, proximity="none").row(0)
    assert plain.sum() < 0.01 and truth_rows[0].sum() > 0.2     # the case the fix exists for: a blind centre


@pytest.fixture(scope="module")
def cornell():
    return scene_polygons(load_scene("cornell-box"))[0]


@pytest.mark.parametrize("patch, name", [(0, "floor"), (4, "red wall"), (2, "back wall"), (10, "tall block's top")])
def test05_cornell_rows_at_the_stage_defaults_match_the_area_average(calls, embree, cornell, patch, name):
    """The rows the issue measured (16 patches, resolution 128, as `cs451 render --stage hemicube` computes them):
    every entry within 0.01 of the area average (Monte Carlo standard error under 0.001), the row sum within 1%.
    The floor's was 0.4687 (truth 0.698), the red wall's 0.5506 (0.813)."""
    from cs451.formfactors import formfactor_matrix_raycast
    expected = formfactor_matrix_raycast(cornell, 400_000, seed=7, rows=[patch])[0]
    row = HemicubeFormFactors(cornell, calls, resolution=128, rotate=False, proximity="contour").row(patch)
    assert np.abs(row - expected).max() < 0.01, (name, np.round(row - expected, 4))
    assert row.sum() == pytest.approx(expected.sum(), rel=0.01), name


@pytest.mark.parametrize("far", [False, True], ids=["close (H6 over the shooter)", "in between (the kernel)"])
def test06_a_receiver_edge_on_from_the_hemicube_is_never_seen_more_than_wholly(calls, far):
    """A receiver whose plane passes a hair under the shooter's centre: the centre reaches it by ~1e-10, so
    one cell's reading of it (rasterised edge-on) over that reach is no fraction seen. The Cornell box's
    tall block has such a face (centre at y = 165, the short block's top): its entry was 5e9 and the solve
    diverged. The entry must stay within the unoccluded area average, which half the shooter sees."""
    shooter = np.array([[0, -0.5, 0], [0, 0.5, 0], [1, 0.5, 0], [1, -0.5, 0]], float)      # x = 0..1, y = ±0.5
    z0 = 2.5 if far else 0.4
    receiver = np.array([[0, -1e-9, z0], [0, -1e-9, z0 + 1], [1, -1e-9, z0 + 1], [1, -1e-9, z0]], float)
    quads = np.stack([shooter, receiver])
    normals = patch_normals(quads)
    if normals[0] @ [0, 0, 1] < 0:
        quads[0] = quads[0][::-1]
    if normals[1] @ [0, 1, 0] < 0:
        quads[1] = quads[1][::-1]
    ff = HemicubeFormFactors(quads, calls, resolution=64, proximity="contour")
    assert ff.normals[0] @ [0, 0, 1] > 0.99 and ff.normals[1] @ [0, 1, 0] > 0.99
    one_cell = float(ff.tables[0].max())
    unoccluded = ff.proximity_fixed(0, np.array([0.0, 1.0]))[1] if not far else None
    fixed = ff.proximity_fixed(0, np.array([0.0, one_cell]))[1]
    assert 0 < fixed < 0.5
    if unoccluded is not None:
        assert fixed <= unoccluded * (1 + 1e-12)
