"""The form-factor engine (cs451/formfactors.py) and patch helpers (cs451/patches.py) with the reference stage-3 code.

Rows are checked against closed forms (truth.py), closure of a cube, reciprocity, and
ray casting; the counters show that rows are lazy, cached and batched.
"""
from __future__ import annotations

import numpy as np
import pytest

from autograder.hemicube import truth
from cs451.errors import KitError
from cs451.formfactors import HemicubeFormFactors, clip_polygon_to_plane, formfactor_matrix_raycast, gauss_points
from cs451.impl import load_impl, resolve_impl
from cs451.patches import patch_areas, patch_centers, patch_normals, patch_triangles, polygon_to_quads, scene_polygons
from cs451.scene import load_scene
from cs451.stages.hemicube import calls

from bench.meshes import subdivide_uniform


@pytest.fixture(scope="module")
def ref():
    return load_impl(resolve_impl("reference", "hemicube"), "hemicube")


# --- patches ------------------------------------------------------------------------

def test01_patch_helpers_on_a_quad_and_a_triangle():
    quad = [[0, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0]]
    tri = [[0, 0, 1], [0, 3, 1], [3, 0, 1], [3, 0, 1]]       # clockwise from above: faces down
    q = np.array([quad, tri], float)
    assert patch_areas(q) == pytest.approx([2.0, 4.5])
    assert np.allclose(patch_normals(q), [[0, 0, 1], [0, 0, -1]])
    assert np.allclose(patch_centers(q), [[1, 0.5, 0], [1, 1, 1]])
    tris, ids = patch_triangles(q)
    assert tris.shape == (4, 3, 3) and list(ids) == [0, 0, 1, 1]


def test02_polygons_with_more_corners_are_fanned():
    hexagon = truth.regular_polygon(1.0, 0.0, 6, facing_down=False)
    quads = polygon_to_quads(hexagon)
    assert quads.shape == (4, 4, 3)
    assert patch_areas(quads).sum() == pytest.approx(1.5 * np.sqrt(3))
    assert np.allclose(patch_normals(quads), [0, 0, 1])


def test03_subdivision_keeps_area_and_orientation():
    q = np.array([[[0, 0, 0], [2, 0, 0], [2.5, 1, 0], [0, 1, 0]], [[0, 0, 1], [0, 3, 1], [3, 0, 1], [3, 0, 1]]], float)
    sub, parent = subdivide_uniform(q, 3)
    assert sub.shape == (18, 4, 3) and list(np.bincount(parent)) == [9, 9]
    assert np.bincount(parent, weights=patch_areas(sub)) == pytest.approx(patch_areas(q))
    assert np.allclose(patch_normals(sub), patch_normals(q)[parent])


def test04_cornell_box_patches():
    quads, names, emission = scene_polygons(load_scene("cornell-box"))
    assert quads.shape == (16, 4, 3)
    assert names[-1] == "light" and list(emission[-1]) == [17, 12, 4] and not emission[:-1].any()
    n = patch_normals(quads)
    assert np.allclose(n[[0, 1, 15]], [[0, 1, 0], [0, -1, 0], [0, -1, 0]])
    assert patch_areas(quads)[-1] == pytest.approx(105 * 130)


def test05_clipping_and_gauss_points():
    square = np.array([[0, 0, -1], [1, 0, -1], [1, 0, 1], [0, 0, 1]], float)
    part = clip_polygon_to_plane(square, np.zeros(3), np.array([0, 0, 1.0]))
    assert patch_areas(polygon_to_quads(part)).sum() == pytest.approx(1.0)
    p, w = gauss_points(np.array([[0, 0, 0], [2, 0, 0], [3, 1, 0], [0, 1, 0]], float), 4)
    assert w.sum() == pytest.approx(2.5) and (p[:, :2] @ [1, 0]).max() < 3


# --- rows against closed forms ---------------------------------------------------------------

def test06_opposed_and_perpendicular_unit_squares_with_the_proximity_fix(ref):
    ff = HemicubeFormFactors(truth.opposed_squares(1, 1), calls(ref), resolution=32)
    assert ff.matrix()[0, 1] == pytest.approx(0.19982, abs=2e-5)
    ff = HemicubeFormFactors(truth.perpendicular_squares(1, 1), calls(ref), resolution=32)
    F = ff.matrix()
    assert F[0, 1] == pytest.approx(0.20004, abs=2e-5) and F[1, 0] == pytest.approx(0.20004, abs=2e-5)
    assert ff.counters["proximity_pairs"] == 2


FAMILY = truth.form_factor_family()
#: the disks whose rows take seconds (tens of thousands of H6 calls): run with the slow tests
SLOW_FAMILY = {"disks r 2.5 to r 2.5", "disks r 2 to r 0.5", "disks r 2.5 to r 0.1"}


def _family_value(ref, quads, shooters, receivers, **options):
    q = np.array(quads, float)
    ff = HemicubeFormFactors(q, calls(ref), resolution=128, **options)
    a = patch_areas(q)[shooters]
    return float((a[:, None] * ff.rows(shooters)[:, receivers]).sum() / a.sum()), ff


@pytest.mark.parametrize("case", [pytest.param(c, id=c[0], marks=[pytest.mark.slow] if c[0].split(",")[0] in SLOW_FAMILY
                                               else []) for c in FAMILY])
def test06a_howell_and_disk_configurations_within_one_percent_with_default_options(ref, case):
    """C-11, C-14 and coaxial disks, sizes 0.2 to 5 times the separation, at resolution 128 and default options."""
    name, quads, shooters, receivers, exact = case
    value, _ = _family_value(ref, quads, shooters, receivers)
    assert value == pytest.approx(exact, rel=0.01), name


def test06c_a_split_shooter_is_not_corrected_twice_and_close_rows_are_not_biased_low(ref):
    # the fix divides by what the split's own hemicubes measure: unit squares one apart, 4 × 4, were 0.1684
    value, ff = _family_value(ref, truth.opposed_squares(1, 1), [0], [1], shooter_split=4)
    assert value == pytest.approx(truth.howell_c11(1, 1, 1), rel=2e-3) and ff.counters["proximity_pairs"] == 1
    # no cap on the visible fraction: over many rotations the fixed entry averages to the truth, not below it
    quads = truth.parallel_rectangles(1.0, 0.3, 0.4)
    exact = truth.howell_c11(1.0, 0.3, 0.4)
    values = [_family_value(ref, quads, [0], [1], seed=s, proximity_distance=2.0)[0] / exact for s in range(12)]
    assert abs(np.mean(values) - 1) < 1e-3


def test06d_far_pairs_are_left_alone_and_middle_ones_corrected_by_the_kernel(ref):
    q = np.array(truth.parallel_rectangles(0.2, 0.2, 1.0), float)      # 6 radii apart: off by +1.4% from the centre
    plain = HemicubeFormFactors(q, calls(ref), resolution=128, proximity="none").row(0)[1]
    value, ff = _family_value(ref, q, [0], [1])
    exact = truth.howell_c11(0.2, 0.2, 1.0)
    assert plain / exact - 1 > 0.01 and abs(value / exact - 1) < 2e-3
    assert ff.counters["proximity_kernel_pairs"] == 1 and ff.counters["proximity_evaluations"] == 0
    far = np.array(truth.parallel_rectangles(0.02, 0.02, 1.0), float)  # 70 radii apart: within 0.1% as it is
    value, ff = _family_value(ref, far, [0], [1])
    assert ff.counters["proximity_kernel_pairs"] == ff.counters["proximity_pairs"] == 0


def test06b_splitting_the_shooter_converges_as_one_over_k_squared(ref):
    errors = []
    for k in (1, 2, 4):
        ff = HemicubeFormFactors(truth.opposed_squares(1, 1), calls(ref), resolution=64, proximity="none", shooter_split=k)
        errors.append(abs(ff.row(0)[1] / truth.howell_c11(1, 1, 1) - 1))
        assert ff.counters["hemicubes_rendered"] == k * k and ff.counters["rows_computed"] == 1
    assert errors[0] > 0.19 and errors[1] < errors[0] / 3.5 and errors[2] < errors[1] / 3.5 and errors[2] < 0.015


def test07_without_the_fix_the_hemicube_converges_to_the_point_form_factor(ref):
    q = np.array(truth.opposed_squares(1, 1), float)
    point = truth.contour([0.5, 0.5, 0], [0, 0, 1], q[1])                # 0.2395: the proximity error
    errors = []
    for res in (16, 64, 256):
        ff = HemicubeFormFactors(q, calls(ref), resolution=res, proximity="none", rotate=False)
        errors.append(abs(ff.row(0)[1] - point) / point)
    assert errors[-1] < 5e-4 and errors[-1] < errors[0]
    assert abs(point - truth.howell_c11(1, 1, 1)) > 0.03                 # no resolution reaches the exact value


def test08_small_patch_under_a_disk(ref):
    q = truth.small_patch_under_disk(0.01, 1.0, 1.0, 128)
    ff = HemicubeFormFactors(q, calls(ref), resolution=128, proximity="none", rotate=True)
    assert ff.row(0)[1:].sum() == pytest.approx(truth.polygon_disk(1.0, 1.0, 128), rel=2e-3)


def test09_closed_cube_rows_sum_to_one_and_are_reciprocal(ref):
    q = np.array(truth.cube(2), float)
    ff = HemicubeFormFactors(q, calls(ref), resolution=64, proximity="none")
    F = ff.matrix()
    assert np.abs(F.sum(axis=1) - 1).max() < 3e-3
    assert np.allclose(np.diag(F), 0)
    report = ff.report()
    assert report["rows"] == 24 and report["closure_error_max"] < 3e-3
    # the hemicube sees from the patch's centre: close pairs are not reciprocal (the proximity error) ...
    A = patch_areas(q)[:, None]
    assert np.abs(A * F - (A * F).T).max() > 0.05 * (A * F).max()
    # ... until the fix replaces them by exact area averages
    G = HemicubeFormFactors(q, calls(ref), resolution=64, proximity="contour").matrix()
    assert np.abs(A * G - (A * G).T).max() < 0.01 * (A * G).max()
    assert np.abs(G.sum(axis=1) - 1).max() < 0.01


# --- laziness, caching, batching, culling --------------------------------------------------------

def test10_rows_are_lazy_cached_and_batched(ref):
    q = np.array(truth.cube(2), float)
    ff = HemicubeFormFactors(q, calls(ref), resolution=16, batch=8, proximity="none")
    assert ff.counters["hemicubes_rendered"] == 0 and ff._renderer is None     # nothing until asked
    first = ff.row(3)
    assert ff.counters["hemicubes_rendered"] == 1 and ff.counters["rows_computed"] == 1
    again = ff.row(3)
    assert ff.counters["hemicubes_rendered"] == 1 and ff.counters["rows_cached_hits"] == 1
    assert np.array_equal(first, again)
    ff.rows(range(24))                                  # 23 missing rows, 8 a read-back
    assert ff.counters["hemicubes_rendered"] == 24 and ff.counters["readbacks"] == 1 + 3
    # a patch's own face (3 others coplanar with it, and itself excluded) and the face opposite... are culled
    assert ff.counters["patches_culled"] == 24 * 3


def test11_batching_does_not_change_rows(ref):
    q = np.array(truth.cube(2), float)
    a = HemicubeFormFactors(q, calls(ref), resolution=16, batch=1, seed=7).matrix()
    b = HemicubeFormFactors(q, calls(ref), resolution=16, batch=100, seed=7).matrix()
    assert np.array_equal(a, b)


def test11a_culled_faces_give_the_same_item_buffers_and_rows(ref):
    """Drawing each face with only the patches that can land in it (radiosity's engine) changes nothing drawn."""
    scene = load_scene("cs451/scenes/cornell-box.json")
    quads, _, _ = scene_polygons(scene)
    q = subdivide_uniform(quads, 3)[0]
    picks = list(range(0, len(q), 7))
    out = {}
    for cull in (False, True):
        ff = HemicubeFormFactors(q, calls(ref), resolution=32, batch=8, cull=cull, resample_blind=2, trusted=True,
                                 reduction="stage")
        out[cull] = (*ff.item_buffers(picks), ff.rows(picks), dict(ff.renderer.triangles), dict(ff.counters))
    for k in range(3):
        assert np.array_equal(out[False][k], out[True][k])
    assert out[False][4] == out[True][4]                       # the same counters (culled, back-facing, blind rows)
    plain, culled = out[False][3], out[True][3]
    assert plain["drawn"] == plain["scene_per_face"] == culled["scene_per_face"]
    assert culled["drawn"] < 0.4 * plain["drawn"]              # a face draws a small part of the scene


def test11b_new_colours_reuse_every_row(ref):
    import json

    from cs451.scene import BUNDLED_DIR, parse_scene
    data = json.loads((BUNDLED_DIR / "cornell-box.json").read_text())
    quads, _, emission = scene_polygons(parse_scene(data, "cb"))
    ff = HemicubeFormFactors(quads, calls(ref), resolution=16)
    ff.rows([0, 15])
    data["materials"]["white"]["diffuse"] = [0.2, 0.3, 0.4]
    data["lights"][0]["radiance"] = [1, 1, 1]
    quads2, _, emission2 = scene_polygons(parse_scene(data, "cb"))
    assert not np.array_equal(emission, emission2) and ff.matches(quads2)
    ff.rows([0, 15])
    assert ff.counters["hemicubes_rendered"] == 2 and ff.counters["rows_cached_hits"] == 2
    assert not ff.matches(quads2[:-1]) and not ff.matches(quads2 + 1e-3)


def test12_bad_arguments_are_refused(ref):
    q = truth.cube(1)
    with pytest.raises(KitError, match="even"):
        HemicubeFormFactors(q, calls(ref), resolution=31)
    with pytest.raises(KitError, match="proximity"):
        HemicubeFormFactors(q, calls(ref), proximity="magic")
    with pytest.raises(KitError, match="out of range"):
        HemicubeFormFactors(q, calls(ref)).row(6)
    with pytest.raises(KitError, match=r"\(n, 4, 3\)"):
        HemicubeFormFactors(np.zeros((3, 3)), calls(ref))


# --- ray casting, the comparison ---------------------------------------------------------------

def test13_ray_casting_agrees_with_closed_forms():
    pytest.importorskip("embreex", reason="ray casting runs on Embree, an optional peer")
    samples = 40_000
    F = formfactor_matrix_raycast(truth.opposed_squares(1, 1), samples, seed=1)
    sigma = np.sqrt(0.2 * 0.8 / samples)
    assert abs(F[0, 1] - truth.howell_c11(1, 1, 1)) < 4 * sigma
    F = formfactor_matrix_raycast(truth.cube(1), samples, seed=2)
    assert F.sum(axis=1) == pytest.approx(1.0, abs=1e-3)     # every ray hits a face of a closed cube


def test14_hemicube_and_ray_casting_agree_on_the_cornell_box(ref):
    pytest.importorskip("embreex", reason="ray casting runs on Embree, an optional peer")
    quads, _, _ = scene_polygons(load_scene("cornell-box"))
    quads, _ = subdivide_uniform(quads, 3)
    rows = [9, 11, 24, len(quads) - 5]   # ceiling and back-wall patches, the light: no occluder close to them
    hemi = HemicubeFormFactors(quads, calls(ref), resolution=128).rows(rows)
    rays = formfactor_matrix_raycast(quads, 200_000, seed=3, rows=rows)
    sigma = np.sqrt(np.maximum(rays, 1e-3) / 200_000)
    assert hemi.sum(axis=1) == pytest.approx(rays.sum(axis=1), abs=0.01)
    assert np.abs(hemi - rays).max() < 0.01 and np.median(np.abs(hemi - rays) / sigma) < 3


def test_rows_are_right_after_another_gl_context_is_made_current(ref):
    """A second context (a demo window, another engine) must not redirect the engine's draws and reads."""
    from cs451.gl import create_context
    quads, _, _ = scene_polygons(load_scene("cornell-box"))
    alone = HemicubeFormFactors(quads, calls(ref), resolution=64).row(2)
    ff = HemicubeFormFactors(quads, calls(ref), resolution=64, batch=1)
    ff.row(0)                                              # its GL state exists
    other = create_context()
    fbo = other.simple_framebuffer((8, 8))
    fbo.use()
    fbo.clear(1.0, 0.0, 0.0, 1.0)
    assert ff.row(2) == pytest.approx(alone, abs=2e-3)     # before the fix: off by 0.2


def cornell_patches(size: float) -> tuple[np.ndarray, np.ndarray]:
    """The Cornell box's polygons subdivided by the reference R1: (patches, parent polygon)."""
    from cs451.stages import radiosity as R
    quads, _, _ = scene_polygons(load_scene("cornell-box"))
    return R.call_subdivide(load_impl(resolve_impl("reference", "radiosity"), "radiosity"), quads, size)


def test15_the_floor_sees_the_light_not_the_ceiling_behind_it(ref):
    """The light hangs 0.1 mm below the ceiling: the near plane must leave the depth buffer enough precision."""
    patches, parent = cornell_patches(50.0)
    light, ceiling = parent == 15, parent == 1
    q = patches
    behind = ceiling & (q[:, :, 0].min(1) >= 213) & (q[:, :, 0].max(1) <= 343) & (q[:, :, 2].min(1) >= 227) \
        & (q[:, :, 2].max(1) <= 332)
    assert behind.sum() == 4
    ff = HemicubeFormFactors(patches, calls(ref), resolution=64, proximity="none")
    rows = ff.rows(np.flatnonzero(parent == 0)[::7])
    open_view = rows.sum(axis=1) > 0.5                          # not under a block
    assert open_view.sum() >= 10
    assert rows[:, behind].sum() == 0.0
    sees_light = rows[open_view][:, light].sum(axis=1) > 0.002
    assert sees_light.mean() > 0.7                              # all but those in a block's shadow
    # the cause: with the near plane at 1e-5 of the diagonal the ceiling wins the depth test everywhere
    tiny = HemicubeFormFactors(patches, calls(ref), resolution=64, proximity="none", near=1e-5 * ff.far / 2)
    old = tiny.rows(np.flatnonzero(parent == 0)[::7])
    assert old[:, light].sum() == 0.0 and old[:, behind].sum() > 0.05


def test16_a_patch_blind_from_its_centre_shoots_from_the_part_that_sees(ref):
    """A floor patch whose centre lies under a block is lit on its exposed part; that part must shoot."""
    patches, parent = cornell_patches(140.0)
    plain = HemicubeFormFactors(patches, calls(ref), resolution=32, proximity="none")
    light_row = plain.row(int(np.flatnonzero(parent == 15)[0]))
    floor = np.flatnonzero(parent == 0)
    sums = plain.rows(floor).sum(axis=1)
    blind_but_lit = floor[(sums < 0.05) & (light_row[floor] > 0)]
    assert len(blind_but_lit), "the scene no longer has a lit floor patch with its centre under a block"
    again = HemicubeFormFactors(patches, calls(ref), resolution=32, proximity="none", resample_blind=3)
    fixed = again.rows(blind_but_lit)
    assert (fixed.sum(axis=1) > 0.5).all()
    assert again.counters["blind_rows_resampled"] == len(blind_but_lit)
    assert again.counters["hemicubes_rendered"] == len(blind_but_lit) * (1 + 9)
    # a row that sees little from everywhere (a block face toward the box's open front) keeps its centre's row
    open_front = np.flatnonzero(parent == 14)
    assert np.array_equal(again.rows(open_front), plain.rows(open_front))
    with pytest.raises(KitError, match="resample_blind"):
        HemicubeFormFactors(patches, calls(ref), resample_blind=-1)


# --- the trusted engine's own reductions --------------------------------------------

@pytest.mark.parametrize("scene_name", ["cornell-box", "furnace", "glossy-box", "room"])
def test11c_the_engines_reductions_give_h5s_rows_on_every_built_in_scene(ref, scene_name):
    """The atlas reduction (CPU) and the device reduction (compute shader) sum what H5 sums, to float64 rounding:
    the trusted engine's rows are the stage's rows. Drawn culled and unculled, every seventh patch's row, patch by
    patch and as grids (which draw other pixels on patch edges: tests/hemicube/test_formfactor_grids.py)."""
    from cs451.stages import radiosity as R
    scene = load_scene(scene_name)
    opts = R.STAGE.options(scene)
    radiosity = load_impl(resolve_impl("reference", "radiosity"), "radiosity")
    quads = R.make_patches(scene, radiosity, opts.patch_size).quads
    picks = list(range(0, len(quads), 7))
    for grids in (False, True):
        rows = {}
        for reduction, cull in (("stage", True), ("atlas", True), ("device", True), ("atlas", False), ("device", False)):
            ff = HemicubeFormFactors(quads, calls(ref), resolution=32, batch=64, resample_blind=R.RESAMPLE_BLIND,
                                     proximity="none", trusted=True, reduction=reduction, cull=cull, grids=grids)
            rows[reduction, cull] = ff.rows(picks)
            assert ff.reduction == reduction and ff.cull == cull and ff.grids == grids
        truth = rows["stage", True]
        assert truth.sum(axis=1).max() > 0.5                       # the rows see something
        for key, found in rows.items():
            np.testing.assert_allclose(found, truth, rtol=1e-12, atol=1e-15, err_msg=str((grids, *key)))


def test11d_device_rows_are_the_same_bits_whatever_the_order(ref):
    """Fixed-point atomics commute: two runs of the device reduction give identical rows; a tile's items beyond n
    (never drawn by trusted shaders) are ignored rather than written out of bounds."""
    from cs451.formfactors.device_reduction import DeviceReduction
    from cs451.gl import create_context
    ctx = create_context()
    r, n = 16, 5
    top, side = calls(ref).tables(r)
    rng = np.random.default_rng(3)
    atlas = rng.integers(0, n + 3, size=(3 * r, 2 * r), dtype=np.uint32)       # two tiles; items n+1, n+2 are junk
    texture = ctx.texture((2 * r, 3 * r), 1, data=atlas.tobytes(), dtype="u4")
    device = DeviceReduction(ctx, top, side, cols=2, n=n, batch=2)
    first, second = device.rows(texture, 2, 3 * r), device.rows(texture, 2, 3 * r)
    assert np.array_equal(first, second)
    weights = np.concatenate([top, side, side, side, side])
    for b in range(2):
        tile = atlas[:, b * r:(b + 1) * r]
        expected = [weights[tile == j + 1].sum() for j in range(n)]
        np.testing.assert_allclose(first[b], expected, rtol=1e-13)


def test11e_batches_fit_the_memory_budget_and_the_gl_limits(ref):
    """An atlas takes at most ATLAS_BYTES (two atlases and the read-back) and no side over the GL's own limit."""
    from types import SimpleNamespace

    from cs451.formfactors.atlas import ATLAS_BYTES, BYTES_PER_PIXEL, atlas_side, one_thread_product
    q = truth.cube(2)
    for resolution in (32, 128, 256):
        ff = HemicubeFormFactors(q, calls(ref), resolution=resolution, batch=10_000, trusted=True)
        ff.rows([0])
        w, h = ff.renderer.size
        assert w * h * BYTES_PER_PIXEL <= ATLAS_BYTES and ff.renderer.batch >= 1
    small = SimpleNamespace(info={"GL_MAX_TEXTURE_SIZE": 2048, "GL_MAX_VIEWPORT_DIMS": (1024, 4096),
                                  "GL_MAX_RENDERBUFFER_SIZE": 8192})
    assert atlas_side(small) == 1024
    a, b = np.random.default_rng(0).standard_normal((500, 4)), np.random.default_rng(1).standard_normal((4, 3000))
    np.testing.assert_allclose(one_thread_product(a, b), a @ b, rtol=1e-12, atol=1e-12)


def test11f_only_trusted_code_is_culled_or_summed_by_the_engine(ref):
    q = truth.cube(1)
    for kwargs in ({"cull": True}, {"reduction": "atlas"}, {"reduction": "device"}):
        with pytest.raises(KitError, match="trusted"):
            HemicubeFormFactors(q, calls(ref), resolution=16, **kwargs)
    with pytest.raises(KitError, match="reduction must be"):
        HemicubeFormFactors(q, calls(ref), resolution=16, trusted=True, reduction="gpu")
    plain = HemicubeFormFactors(q, calls(ref), resolution=16)
    plain.row(0)
    assert not plain.cull and plain.reduction == "stage"


def test11i_a_driver_that_cannot_build_the_compute_shader_gets_the_same_rows_from_the_cpu(ref, monkeypatch, capsys):
    import cs451.formfactors.rows as rows_module

    def refuse(*args, **kwargs):
        raise RuntimeError("GLSL Compiler failed\ncompute_shader ...")
    q = truth.cube(1)
    expected = HemicubeFormFactors(q, calls(ref), resolution=16, trusted=True, reduction="atlas").rows([0, 3])
    monkeypatch.setattr(rows_module, "DeviceReduction", refuse)
    ff = HemicubeFormFactors(q, calls(ref), resolution=16, trusted=True, reduction="device")
    np.testing.assert_array_equal(ff.rows([0, 3]), expected)
    assert ff.reduction == "atlas" and "compute shader failed (GLSL Compiler failed)" in capsys.readouterr().err


def test11g_the_formfactors_bench_splits_its_time_and_compares_with_h5():
    """``cs451 bench formfactors``' measurement on a small case: the split adds up, and the rows are H5's."""
    from cs451.stages.hemicube.bench_formfactors import one_matrix, patches_of
    from cs451.gl import create_context
    ctx = create_context()
    quads, proximity = patches_of("cornell-box")
    stage, F_stage = one_matrix(quads, proximity, 16, False, "stage", False, ctx)
    atlas, F_atlas = one_matrix(quads, proximity, 16, True, "atlas", False, ctx)
    grids, F_grids = one_matrix(quads, proximity, 16, True, "atlas", True, ctx)
    for row in (stage, atlas, grids):
        parts = row["draw"] + row["readback"] + row["reduction"] + row["other"]
        assert parts == pytest.approx(row["seconds"], rel=1e-6) and row["hemicubes"] >= len(quads)
    assert atlas["triangles_per_face"] < 0.5 * stage["triangles_per_face"]          # culling draws less
    assert grids["triangles_per_face"] < 0.5 * atlas["triangles_per_face"]          # and grids less again
    np.testing.assert_allclose(F_atlas, F_stage, rtol=1e-12, atol=1e-15)
    assert 0 < np.abs(F_grids - F_stage).max() < 0.05                               # edge pixels only


def test11h_the_walkthrough_stays_where_both_renderers_agree_on_what_is_seen():
    """Its views keep the eye between the side walls' planes and before the opening (a wall seen from behind is
    black to Mitsuba's one-sided material), and a render compared with itself has no error on any wall."""
    from cs451.stages.radiosity.bench_walkthrough import views, wall_errors
    from cs451.stages.radiosity.bench_peer import polygon_ids
    for camera in views(30):
        eye = dict(camera)["eye"]
        assert 0 < eye[0] < 556 and 0 < eye[1] < 548 and eye[2] < 0
    scene = load_scene("cornell-box")
    ids = polygon_ids(scene, (64, 64))
    image = np.random.default_rng(0).uniform(0.1, 1.0, (64, 64, 3))
    errors = wall_errors(image, image, ids)
    assert errors and all(e == 0 for e in errors.values())


def test11j_a_walls_mask_drops_the_crease_between_two_of_its_faces():
    """A block's faces are eroded one by one: the pixels along the crease between a lit top and a dark side are
    in neither face's mask, so a renderer whose edge falls one pixel over is not charged the top's brightness."""
    from cs451.stages.radiosity.bench_peer import WALLS, wall_masks
    top, side = WALLS["short block"][:2]
    ids = np.full((20, 20), -1)
    ids[2:10, 2:18], ids[10:18, 2:18] = top, side                  # two faces of one wall meet at row 10
    mask = wall_masks(ids)["short block"]
    assert mask[4:8, 4:16].all() and mask[12:16, 4:16].all()       # each face's inside is kept
    assert not mask[8:12].any()                                    # the crease, two pixels either side, is not
