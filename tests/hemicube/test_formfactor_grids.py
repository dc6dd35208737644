"""Grids (cs451/formfactors/grids.py): a polygon's patches drawn as one quad, the fragment finding its patch.

Detection must only ever gather patches that are exactly the cells of a planar convex quad's bilinear grid; the
item buffers drawn that way may differ from the patch-by-patch ones only on patch edges; and the rows must be as
close to a finer hemicube's as the patch-by-patch rows are.
"""
from __future__ import annotations

import numpy as np
import pytest

from cs451.errors import KitError
from cs451.formfactors import HemicubeFormFactors
from cs451.formfactors.geometry import bilinear
from cs451.formfactors.grids import patch_grids
from cs451.impl import load_impl, resolve_impl
from cs451.scene import load_scene
from cs451.stages import hemicube as H
from cs451.stages import radiosity as R

RADIOSITY_SCENES = ("cornell-box", "room", "furnace", "glossy-box")


@pytest.fixture(scope="module")
def r1():
    """Stage 4's R1 (the reference's subdivide): the order grids are found in."""
    return load_impl(resolve_impl("reference", "radiosity"), "radiosity").subdivide


@pytest.fixture(scope="module")
def hemicube_calls():
    return H.calls(load_impl(resolve_impl("reference", "hemicube"), "hemicube"))


def assert_cells_are_the_patches(grids, quads):
    """The invariant every answer must keep: grid g's cells, rebuilt from its quad, are patches first[g] ..., in order,
    and the grids cover every patch once."""
    covered = 0
    for corners, first, (nu, nv) in zip(grids.corners, grids.first, grids.shape):
        assert first == covered
        i, j = np.meshgrid(np.arange(nu), np.arange(nv))
        st = (np.stack([i.ravel(), j.ravel()], axis=1)[:, None, :] + [[0, 0], [1, 0], [1, 1], [0, 1]]) / [nu, nv]
        np.testing.assert_allclose(bilinear(corners, st), quads[first:first + nu * nv], atol=1e-9)
        covered += nu * nv
    assert covered == len(quads)


def test01_a_subdivided_trapezoid_and_parallelogram_are_one_grid_each(r1):
    trapezoid = [[0, 0, 0], [4, 0, 0], [3, 2, 0], [0.5, 2, 0]]
    slanted = [[0, 0, 1], [0, 3, 1], [2, 4, 3], [2, 1, 3]]          # a parallelogram, not axis-aligned
    polygons = np.array([trapezoid, slanted], float)
    quads, _ = r1(polygons, 0.7)
    grids = patch_grids(quads)
    assert len(grids) == 2
    np.testing.assert_allclose(grids.corners, polygons, atol=1e-12)
    assert grids.shape.prod(axis=1).sum() == len(quads) and (grids.shape > 1).all()
    assert_cells_are_the_patches(grids, quads)


def test02_what_is_no_grid_is_drawn_patch_by_patch(r1):
    """A non-planar quad, a triangle's last row (triangles) and patches out of R1's order are grids of one cell:
    their own triangles. A triangle's rows below the last are a trapezoid's grid."""
    bent = [[0, 0, 5], [3, 0, 5], [3, 3, 5.5], [0, 3, 5]]
    quads, _ = r1(np.array([bent], float), 0.5)
    grids = patch_grids(quads)
    assert len(grids) == len(quads) and (grids.shape == 1).all()
    np.testing.assert_array_equal(grids.corners, quads)
    triangle = [[0, 0, 0], [2, 0, 0], [0, 2, 0], [0, 2, 0]]
    quads, _ = r1(np.array([triangle], float), 0.5)                 # 4 × 6 cells, the top row triangles
    grids = patch_grids(quads)
    assert grids.shape.tolist() == [[4, 5]] + [[1, 1]] * 4
    assert_cells_are_the_patches(grids, quads)
    flat, _ = r1(np.array([[[0, 0, 0], [3, 0, 0], [3, 2, 0], [0, 2, 0]]], float), 0.5)
    shuffled = flat[np.random.default_rng(1).permutation(len(flat))]
    assert_cells_are_the_patches(patch_grids(shuffled), shuffled)
    assert len(patch_grids(shuffled)) > len(flat) // 2


def test03_random_scenes_keep_the_invariant(r1):
    """Whatever comes in (mixed shapes, reversed, runs of coplanar polygons side by side), every grid is exact."""
    rng = np.random.default_rng(7)
    for trial in range(20):
        polygons = []
        for _ in range(rng.integers(1, 6)):
            base = rng.normal(size=3) * 5
            u, v = rng.normal(size=3), rng.normal(size=3)
            kind = rng.integers(0, 4)
            if kind == 0:        # a parallelogram
                polygons.append([base, base + u, base + u + v, base + v])
            elif kind == 1:      # a planar trapezoid
                polygons.append([base, base + 2 * u, base + 1.5 * u + v, base + 0.5 * u + v])
            elif kind == 2:      # a triangle
                polygons.append([base, base + u, base + v, base + v])
            else:                # the same parallelogram's neighbour: runs may continue into it
                polygons.append([base, base + u, base + u + v, base + v])
                polygons.append([base + v, base + u + v, base + u + 2 * v, base + 2 * v])
        quads, _ = r1(np.array(polygons, float), float(rng.uniform(0.3, 1.5)))
        if trial % 3 == 1:
            quads = quads[::-1].copy()
        assert_cells_are_the_patches(patch_grids(quads), quads)


def test04_the_built_in_scenes_are_mostly_grids():
    """The room and the furnace are one grid a polygon; the Cornell box's one non-planar wall (objects[4], 3.2
    units off its plane in the original data) stays patch by patch."""
    radiosity = load_impl(resolve_impl("reference", "radiosity"), "radiosity")
    counts = {}
    for name in RADIOSITY_SCENES:
        scene = load_scene(name)
        patches = R.make_patches(scene, radiosity, R.STAGE.options(scene).patch_size)
        grids = patch_grids(patches.quads)
        assert_cells_are_the_patches(grids, patches.quads)
        counts[name] = (len(patches.polygons), len(grids), int((grids.shape.prod(axis=1) == 1).sum()))
    assert counts["room"][1] == counts["room"][0] and counts["furnace"][1] == counts["furnace"][0]
    polygons, found, ones = counts["cornell-box"]
    assert found == polygons - 1 + 132 and ones == 132


def _faces(tops, sides):
    """Each face of each hemicube as its own image (for neighbourhoods)."""
    return [t for t in tops] + [s for side in sides for s in side]


@pytest.mark.parametrize("scene_name", RADIOSITY_SCENES)
def test05_item_buffers_differ_only_on_patch_edges(scene_name, hemicube_calls):
    """Drawn as grids, a hemicube's pixels are the patch-by-patch ones except a few whose centres lie on a patch
    edge, within rounding: each such pixel is on an edge of the patch-by-patch drawing (its 3 × 3 neighbourhood
    there holds more than one id; a wrong cell would show inside a patch). Those are few, and most of them swap
    for a neighbour's id; the rest are slivers (a face seen edge-on from behind draws 0 over a pixel or not)."""
    scene = load_scene(scene_name)
    radiosity = load_impl(resolve_impl("reference", "radiosity"), "radiosity")
    quads = R.make_patches(scene, radiosity, R.STAGE.options(scene).patch_size).quads
    picks = list(range(0, len(quads), max(1, len(quads) // 40)))
    buffers = []
    for grids in (False, True):
        ff = HemicubeFormFactors(quads, hemicube_calls, resolution=64, batch=64, proximity="none", trusted=True,
                                 cull=True, reduction="atlas", grids=grids)
        buffers.append(_faces(*ff.item_buffers(picks)))
        assert ff.grids is grids
    differing = swapped = total = 0
    for patch_drawn, grid_drawn in zip(*buffers):
        total += patch_drawn.size
        for y, x in zip(*np.nonzero(patch_drawn != grid_drawn)):
            differing += 1
            window = patch_drawn[max(0, y - 1):y + 2, max(0, x - 1):x + 2]
            assert (window != window[0, 0]).any(), (scene_name, y, x, patch_drawn[y, x], grid_drawn[y, x])
            swapped += int((window == grid_drawn[y, x]).any())
    assert differing <= 2e-3 * total, (differing, total)
    assert swapped >= 0.8 * differing, (swapped, differing)


def test06_grid_rows_are_as_close_to_a_finer_hemicube(hemicube_calls):
    """Against the Cornell box's rows at resolution 256, rows at 64 drawn as grids are as close as patch by patch
    (the same rms to 3%), and their row sums agree to the few cells the edge pixels can move."""
    scene = load_scene("cornell-box")
    radiosity = load_impl(resolve_impl("reference", "radiosity"), "radiosity")
    quads = R.make_patches(scene, radiosity, R.STAGE.options(scene).patch_size).quads

    def matrix(resolution, grids, seed=0):
        return HemicubeFormFactors(quads, hemicube_calls, resolution=resolution, batch=64, proximity="none", seed=seed,
                                   trusted=True, cull=True, reduction="atlas", grids=grids).matrix()

    finer = matrix(256, False, seed=5)
    patch_rows, grid_rows = matrix(64, False), matrix(64, True)
    rms = [np.sqrt(((rows - finer) ** 2).mean()) for rows in (patch_rows, grid_rows)]
    assert rms[1] == pytest.approx(rms[0], rel=0.03)
    cell = float(hemicube_calls.tables(64)[0].max())
    assert np.abs(grid_rows.sum(axis=1) - patch_rows.sum(axis=1)).max() < 20 * cell
    assert not np.array_equal(grid_rows, patch_rows)          # drawn another way: the comparison is not vacuous


def test07_grids_are_the_trusted_engines_choice_on_a_cpu_rasteriser(hemicube_calls):
    quads = np.array([[[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 0, 1], [0, 1, 1], [1, 1, 1], [1, 0, 1]]], float)
    trusted = HemicubeFormFactors(quads, hemicube_calls, resolution=16, trusted=True)
    student = HemicubeFormFactors(quads, hemicube_calls, resolution=16)
    trusted.row(0), student.row(0)
    from cs451.gl import is_software
    assert trusted.grids is is_software(trusted.renderer.ctx) and student.grids is False
    with pytest.raises(KitError, match="trusted"):
        HemicubeFormFactors(quads, hemicube_calls, resolution=16, grids=True)
