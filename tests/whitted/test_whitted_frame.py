"""Stage 2's fast paths: the compiled whole-frame kernel against the numpy wavefront (what the grader runs)
and against the per-bounce compiled path, the hierarchy and layout caches, the eight-wide layout, the
compile message, and the scaffolding's caches (meshes read once, hierarchies checked once)."""
from __future__ import annotations

import contextlib
import importlib
from pathlib import Path

import numpy as np
import pytest

from cs451 import tracescene
from cs451.impl import load_impl, resolve_impl
from cs451.scene import BUNDLED_DIR, load_scene, parse_scene
from cs451.stages import whitted
from cs451.stages.whitted import accel

RAY_COUNTERS = ("camera", "shadow", "reflection", "transmission")


@pytest.fixture(scope="module")
def ref():
    return load_impl(resolve_impl("reference", "whitted"), "whitted")


def part(ref, name: str):
    """A module of the reference's speed layer (instructor-side, outside the reference)."""
    return importlib.import_module(f"cs451.stages.whitted.accel.{name}")


@contextlib.contextmanager
def path(ref, compiled: bool, frame: bool = True):
    """Run the reference on its numpy path, or through its one speed hook on the compiled one (whole frames
    or bounce by bounce), whatever the batch size."""
    mode = "numpy" if not compiled else ("compiled" if frame else "bounces")
    with accel.forced(mode), whitted.STAGE.accelerated(ref):
        yield


def traced(ref, scene, size, **modes):
    ts = whitted.prepare(scene, ref)
    o, d = ref.camera_rays(scene.camera, *size)
    with path(ref, **modes):
        colour = ref.trace(ts, o, d)
    return colour, dict(ts.counters)


def scenes():
    import sys
    sys.path.insert(0, str(BUNDLED_DIR.parent.parent))
    from autograder.whitted.public import LIGHT_BEHIND, two_mirrors
    out = [(name, load_scene(name)) for name in ("whitted", "cornell-spheres", "cornell-box", "rippled-torus")]
    return out + [("two mirrors", parse_scene(two_mirrors(0.5, 0.1, 10))), ("light behind", parse_scene(LIGHT_BEHIND))]


def test01_frame_kernel_agrees_with_the_numpy_wavefront(ref):
    """The grader's numpy path and the compiled frame cast the same rays and see the same colours.

    Equality gives way to a tolerance: the frame sums a pixel's contributions depth first (a ray, then
    its reflection's subtree, then its transmission's), the wavefront bounce by bounce, and the area
    light's cosine is a BLAS product there; measured differences are below 4e-14.
    """
    for name, scene in scenes():
        a, ca = traced(ref, scene, (40, 30), compiled=False)
        b, cb = traced(ref, scene, (40, 30), compiled=True)
        assert {k: ca[k] for k in RAY_COUNTERS} == {k: cb[k] for k in RAY_COUNTERS}, name
        assert np.allclose(a, b, rtol=1e-12, atol=1e-12), f"{name}: differs by {np.abs(a - b).max():.3g}"
        assert cb["camera"] == 1200 and (name != "whitted" or cb["reflection"] > 0 and cb["transmission"] > 0)


def test02_frame_kernel_does_the_work_of_the_per_bounce_compiled_path(ref):
    """The same closest-hit and shadow traversals, so every counter matches, nodes and tests included."""
    seen = {}
    for name, scene in scenes():
        a, ca = traced(ref, scene, (64, 48), compiled=True, frame=False)
        b, cb = traced(ref, scene, (64, 48), compiled=True, frame=True)
        assert ca == cb, name
        assert np.allclose(a, b, rtol=1e-12, atol=1e-12), f"{name}: differs by {np.abs(a - b).max():.3g}"
        seen[name] = cb
    # the counters tell runs apart: a higher cut-off casts fewer reflections
    scene = load_scene("whitted")
    ts = whitted.prepare(scene, ref, min_weight=0.5)
    with path(ref, compiled=True):
        ref.trace(ts, *ref.camera_rays(scene.camera, 64, 48))
    assert 0 < ts.counters["reflection"] < seen["whitted"]["reflection"]


def test03_a_hierarchy_is_built_once_per_geometry(ref):
    hierarchy = part(ref, "hierarchy")
    scene = load_scene("rippled-torus")
    whitted.render_traced(scene, ref, (16, 12))
    before = hierarchy.cache_counts()
    for _ in range(2):
        whitted.render_traced(scene, ref, (16, 12))
    after = hierarchy.cache_counts()
    assert after["hierarchies_built"] == before["hierarchies_built"]
    assert after["hierarchies_reused"] == before["hierarchies_reused"] + 2
    # the compiled kernels' layout is reused too, once a compiled batch has asked for it
    with path(ref, compiled=True):
        whitted.render_traced(scene, ref, (16, 12))
        mid = hierarchy.cache_counts()
        whitted.render_traced(scene, ref, (16, 12))
    end = hierarchy.cache_counts()
    assert end["layouts_built"] == mid["layouts_built"] and end["layouts_reused"] == mid["layouts_reused"] + 1
    # another geometry is another hierarchy
    ts = tracescene.build(scene)
    lo, hi = ts.bounds()
    whitted.STAGE.call(ref, "W4", lo * 2.0, hi * 2.0)
    assert hierarchy.cache_counts()["hierarchies_built"] == end["hierarchies_built"] + 1


def test04_a_cached_hierarchy_is_what_a_fresh_build_gives_and_cannot_be_spoilt(ref):
    hierarchy = part(ref, "hierarchy")
    lo, hi = tracescene.build(load_scene("rippled-torus")).bounds()
    first = whitted.STAGE.call(ref, "W4", lo, hi)
    leaf = importlib.import_module(f"{ref.__name__}.bvh").LEAF_SIZE
    assert part(ref, "queries").LEAF_SIZE == leaf
    fresh = dict(zip(tracescene.BVH_KEYS, hierarchy.build(lo, hi, leaf)))
    assert all(np.array_equal(first[k], fresh[k]) for k in tracescene.BVH_KEYS)
    first["order"][:] = 0                                  # a caller scribbles on what it was handed
    again = whitted.STAGE.call(ref, "W4", lo, hi)
    assert np.array_equal(again["order"], fresh["order"])


def test05_eight_wide_layout_holds_every_node_once_in_boxes_that_contain_it(ref):
    hierarchy = part(ref, "hierarchy")
    ts = whitted.prepare(load_scene("rippled-torus"), ref)
    bvh = ts.bvh
    tri = np.concatenate([ts.tri_v0, ts.tri_v1, ts.tri_v2], axis=1)
    nf, ni, order, ltri, use = hierarchy.eight_wide(bvh, ts.n_spheres, tri)
    w = hierarchy.WIDTH
    assert use and nf.ctypes.data % 64 == 0 and ni.shape[1] == 8 * w == 64
    kind, ref_ = ni[:, 7 * w:], ni[:, 6 * w:7 * w]
    # every leaf of the binary tree is one slot (its start and count kept), inner slots point at rows
    leaves = np.nonzero(bvh["child"] < 0)[0]
    slots = kind >= 0
    assert slots.sum() == len(leaves)
    assert sorted(zip(ref_[slots], kind[slots])) == sorted(zip(bvh["start"][leaves], bvh["count"][leaves]))
    inner = kind == -1
    assert sorted(ref_[inner].tolist()) == list(range(1, len(ni)))   # each row but the root's, once
    assert np.all((kind == -2) | (kind == -1) | (kind > 0))
    # float32 boxes hold what they stand for: each leaf slot's box contains its triangles' corners
    is_tri = order >= ts.n_spheres
    for q, c in zip(*np.nonzero(slots)):
        box_lo, box_hi = nf[q, [c, w + c, 2 * w + c]], nf[q, [3 * w + c, 4 * w + c, 5 * w + c]]
        first, last = ni[q, 6 * w + c], ni[q, 6 * w + c] + ni[q, 7 * w + c]
        t = ltri[first:last][is_tri[first:last]].reshape(-1, 3)
        assert np.all(t >= box_lo) and np.all(t <= box_hi)
    assert np.array_equal(ltri[is_tri], tri[order[is_tri] - ts.n_spheres]) and not ltri[~is_tri].any()


def test06_the_first_compile_says_so_once(ref, capsys):
    from numba import njit
    running = part(ref, "running")
    saved = running._said[0]
    running._said[0] = False
    try:
        running.compiled(njit(lambda x: x + 1), (1.0,))
        running.compiled(njit(lambda x: x * 2), (1.0,))
    finally:
        running._said[0] = saved
    said = capsys.readouterr().err
    assert said.count("compiling the ray tracer's kernels, once") == 1


def test07_meshes_are_read_once_and_reread_when_the_file_changes(tmp_path):
    obj = tmp_path / "tri.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    v, f = tracescene.load_mesh(obj, "objects[0].file")
    v[:] = 7.0                                             # the caller's copy, not the cache's
    again, _ = tracescene.load_mesh(obj, "objects[0].file")
    assert np.array_equal(again, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    obj.write_text("v 0 0 0\nv 2 0 0\nv 0 2 0\nv 5 5 5\nf 1 2 3\n")
    changed, _ = tracescene.load_mesh(obj, "objects[0].file")
    assert changed[1, 0] == 2.0


def test08_a_hierarchy_checked_before_is_judged_the_same_and_a_changed_one_again(ref):
    lo, hi = tracescene.build(load_scene("cornell-box")).bounds()
    good = {k: np.array(v) for k, v in ref.build_bvh(lo, hi).items()}
    assert tracescene.bvh_problems(good, lo, hi) == [] == tracescene.bvh_problems(good, lo, hi)
    bad = {k: v.copy() for k, v in good.items()}
    bad["order"][0] = bad["order"][1]
    first = tracescene.bvh_problems(bad, lo, hi)
    assert first and tracescene.bvh_problems(bad, lo, hi) == first
    assert tracescene.bvh_problems({**good, "order": [[1, 2], [3]]}, lo, hi)   # unkeyable input is still judged


def test09_compiled_camera_rays_are_numpys_bit_for_bit(ref):
    for name in ("whitted", "cornell-box", "rippled-torus"):
        camera = load_scene(name).camera
        for size in ((97, 61), (1, 1), (320, 240)):
            with path(ref, compiled=False):
                a = ref.camera_rays(camera, *size)
            with path(ref, compiled=True):
                b = ref.camera_rays(camera, *size)
            assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1]), (name, size)


def bench_module(name: str):
    """A part of the Whitted benchmark (``cs451/stages/whitted/bench_<name>.py``)."""
    return importlib.import_module(f"cs451.stages.whitted.bench_{name}")


def test10_the_bench_records_every_ray_a_frame_casts(ref):
    kernels = bench_module("kernels")
    parts = kernels.reference_parts(ref)
    for name in ("whitted", "rippled-torus"):
        scene = load_scene(name)
        ts = whitted.prepare(scene, ref)
        o, d = ref.camera_rays(scene.camera, 40, 30)
        with path(ref, compiled=True):
            rays = kernels.frame_rays(parts, ts, o, d)
        c = ts.counters
        assert len(rays["closest"][0]) == c["camera"] + c["reflection"] + c["transmission"]
        assert len(rays["shadow"][0]) == c["shadow"] > 0
        assert np.allclose(np.linalg.norm(rays["shadow"][1], axis=1), 1.0)


def test11_mitsuba_is_handed_the_same_camera_and_geometry(ref, tmp_path):
    """Where the kit's camera rays see nothing, Mitsuba's frame of the converted scene is black, and the
    converted scene's lit pixels are where the kit's rays hit something."""
    mi = pytest.importorskip("mitsuba")
    convert = bench_module("mitsuba")
    mi.set_variant(convert.VARIANT)
    for name in ("rippled-torus", "cornell-spheres"):
        scene = load_scene(name)
        ts = tracescene.build(scene)
        image = np.array(mi.render(mi.load_dict(convert.mitsuba_dict(scene, ts, (48, 36), 4, tmp_path)), spp=4))
        o, d = ref.camera_rays(scene.camera, 48, 36)
        with path(ref, compiled=False):
            _, prim, _ = ref.closest_hit(whitted.prepare(scene, ref), o, d)
        seen = (prim >= 0).reshape(36, 48)
        near = np.zeros_like(seen)                         # Mitsuba's samples spread over the pixel: one pixel of slack
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                near |= np.roll(np.roll(seen, dy, 0), dx, 1)
        lit = image[..., :3].max(axis=2) > 0
        assert image.shape[:2] == (36, 48) and lit.mean() > 0.2
        assert not (lit & ~near).any(), f"{name}: Mitsuba lights pixels where the kit sees background"


def test12_the_bench_times_the_demo_to_a_finished_picture(ref):
    from cs451.stages.whitted.demo import WhittedDemo, progressive_order
    demo = WhittedDemo(ref, "whitted", (40, 30))
    seconds, shown = bench_module("demo")._refine(demo)
    assert not demo.busy() and seconds > 0
    assert shown >= len(progressive_order(40, 30)[1]), "each pass ends a step, and a frame is drawn after each"
    assert demo.render.scene.counters["camera"] == 40 * 30


def test13_the_kernels_bit_tricks_are_numpys_comparisons(ref):
    """The vector compares the traversal reads a row through (which children a ray enters, how many slots are
    full, the lowest entered one) against numpy's, NaN and infinities included."""
    from numba import njit
    K = part(ref, "kernels")

    @njit
    def tricks(n, f, x, v):
        entered = K._le_bits8(n[0], n[1], n[2], n[3], n[4], n[5], n[6], n[7], f[0], f[1], f[2], f[3], f[4], f[5], f[6], f[7])
        full = K._count_ne8(x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], v)
        return entered, full, (K._lowest(entered) if entered != 0 else 99)

    rng = np.random.default_rng(3)
    special = np.array([np.nan, np.inf, -np.inf, 0.0, -0.0, 1.0], np.float32)
    for _ in range(300):
        n = rng.choice(special, 8) if rng.random() < 0.3 else rng.normal(size=8).astype(np.float32)
        f = np.where(rng.random(8) < 0.3, n, rng.normal(size=8)).astype(np.float32)   # ties, on purpose
        x = rng.choice(np.array([-2, -1, 0, 5], np.int32), 8)
        entered, full, lowest = tricks(n, f, x, np.int32(-2))
        bits = n <= f
        assert entered == int(np.sum(bits.astype(np.int64) << np.arange(8)))
        assert full == int(np.sum(x != -2))
        assert lowest == (int(np.argmax(bits)) if bits.any() else 99)


def test14_prefetching_a_waiting_child_changes_nothing(ref):
    """The traversal asks for a waiting child's row or triangles early (``_fetch_child``); the hint compiles for
    the flat rows and the 2-D triangles, past their ends too (a prefetch cannot fault), and writes nothing."""
    from numba import njit
    K = part(ref, "kernels")

    @njit
    def fetch(nf, ltri, q, cnt):
        K._fetch_child(nf, ltri, q, cnt)
        return nf.sum(), ltri.sum()

    nf = np.arange(128, dtype=np.float32)
    ltri = np.arange(36, dtype=np.float64).reshape(4, 9)
    before = (nf.sum(), ltri.sum())
    for q, cnt in ((0, -1), (1, -1), (0, 4), (3, 1), (10**6, -1), (10**6, 2)):
        assert fetch(nf, ltri, q, cnt) == before
    assert np.array_equal(nf, np.arange(128, dtype=np.float32))


def test15_the_reference_reads_as_numpy_and_asks_for_speed_by_one_hook():
    """No file of the student's reference compiles anything or reaches into the speed layer; its package declares
    the hook once, inside a solution region (so a starter never carries it)."""
    from cs451 import KIT_ROOT
    folder = KIT_ROOT / "reference" / "whitted"
    for file in folder.glob("*.py"):
        imports = [line for line in file.read_text().splitlines() if line.strip().startswith(("import ", "from "))]
        assert not [line for line in imports if "numba" in line or "accel" in line or "cs451.stages" in line], file.name
    init = (folder / "__init__.py").read_text()
    assert init.count("ACCELERATED = True") == 1
    start, hook = init.index("# BEGIN SOLUTION"), init.index("ACCELERATED = True")
    assert start < hook < init.index("# END SOLUTION", start)


def test16_the_hook_is_honoured_for_the_kits_reference_only(ref, tmp_path):
    """A copy of the reference elsewhere (a submission declaring the hook) runs its own code whatever it declares:
    the speed layer does tasks' work, so no submission may have it; and no release or sandbox holds it."""
    import shutil
    from cs451 import instructor_only
    copy = tmp_path / "whitted"
    shutil.copytree(resolve_impl("reference", "whitted"), copy, ignore=shutil.ignore_patterns("__pycache__"))
    theirs = load_impl(copy, "whitted")
    assert theirs.ACCELERATED is True
    own_trace = theirs.trace
    with accel.forced("compiled"), whitted.STAGE.accelerated(theirs):
        assert theirs.trace is own_trace
    with accel.forced("compiled"), whitted.STAGE.accelerated(ref):
        assert ref.trace.__module__ == accel.__name__
    assert ref.trace.__module__ != accel.__name__, "the wrappers go when the block ends"
    assert instructor_only(Path(accel.__file__).parent) and instructor_only(Path(accel.__file__))
