"""Stage 2: the scene as arrays, the reference tracer against closed forms and a rasteriser, its counters,
the bundled mesh, and grading (the starter scores zero; the reference's full marks are a slow test)."""
from __future__ import annotations

import copy
import json

import numpy as np
import pytest

from cs451 import tracescene
from cs451.errors import KitError
from cs451.impl import load_impl, resolve_impl
from cs451.scene import BUNDLED_DIR, load_scene, parse_scene
from cs451.stages import get_stage, whitted


@pytest.fixture(scope="module")
def ref():
    return load_impl(resolve_impl("reference", "whitted"), "whitted")


def scene_dict(name: str) -> dict:
    return json.loads((BUNDLED_DIR / f"{name}.json").read_text())


def traced(ref, data: dict, size, **opts):
    return whitted.render_traced(parse_scene(data, "<test>"), ref, size, **opts)


def test01_cornell_box_as_arrays():
    ts = tracescene.build(load_scene("cornell-box"))
    assert ts.n_spheres == 0 and ts.n_triangles == 30 and ts.n_planes == 0
    assert len(ts.light_position) == 16                     # the area light's samples
    lo, hi = ts.bounds()
    assert np.all(lo <= hi) and lo.shape == (30, 3)
    # the samples lie on the light's rectangle, emitting downwards
    assert np.allclose(ts.light_position[:, 1], 548.7) and np.allclose(ts.light_normal, [0, -1, 0])
    # total power of the samples: radiance · area / π
    assert np.allclose(ts.light_diffuse.sum(axis=0), np.array([17, 12, 4]) * 130 * 105 / np.pi)


def test02_bad_scenes_give_one_line_errors(tmp_path):
    data = scene_dict("whitted")
    data["lights"] = [{"type": "directional", "direction": [0, -1, 0]}]
    with pytest.raises(KitError, match=r"lights\[0\].*point and area"):
        tracescene.build(parse_scene(data, "w.json"))
    data = scene_dict("whitted")
    data["options"] = {"whitted": {"spp": 3}}
    with pytest.raises(KitError, match=r"options\.whitted\.spp: must be a square"):
        whitted.STAGE.options(parse_scene(data, "w.json"))
    data = scene_dict("rippled-torus")
    data["objects"][1]["file"] = "missing.obj"
    with pytest.raises(KitError, match=r"objects\[1\].file: mesh file .*missing.obj not found"):
        tracescene.build(parse_scene(data, "t.json"))


def test03_lambert_sphere_matches_the_closed_form(ref):
    """One diffuse sphere under a point light (no ambient): each pixel is kd·I·max(n·l, 0), n from the exact sphere."""
    data = {"camera": {"eye": [0, 0, 5], "center": [0, 0, 0], "fovy": 30}, "ambient": [0, 0, 0],
            "lights": [{"type": "point", "position": [3, 4, 5], "diffuse": [0.9, 0.8, 0.7], "specular": [0, 0, 0]}],
            "materials": {"m": {"diffuse": [0.5, 0.6, 0.7], "ambient": [0, 0, 0]}},
            "objects": [{"type": "sphere", "radius": 1, "material": "m"}]}
    image, counters = traced(ref, data, (48, 40))
    origins, dirs = ref.camera_rays(parse_scene(data).camera, 48, 40)
    # the closed form: the first hit of each ray with the unit sphere at the origin
    od = np.einsum("ij,ij->i", origins, dirs)
    disc = od ** 2 - (np.einsum("ij,ij->i", origins, origins) - 1)
    hit = disc >= 0
    t = -od - np.sqrt(np.where(hit, disc, 0))
    p = origins + t[:, None] * dirs
    light = np.array([3.0, 4.0, 5.0])
    l = light - p
    l /= np.linalg.norm(l, axis=1, keepdims=True)
    want = np.where(hit[:, None], np.array([0.45, 0.48, 0.49]) * np.maximum(np.einsum("ij,ij->i", p, l), 0)[:, None], 0)
    assert np.abs(image.reshape(-1, 3) - want).max() < 1e-9
    assert counters["camera"] == 48 * 40 and counters["reflection"] == counters["transmission"] == 0


def test04_counters_skip_what_a_scene_does_not_need(ref):
    import sys
    sys.path.insert(0, str(BUNDLED_DIR.parent.parent))
    from autograder.whitted.public import LIGHT_BEHIND, mirror_rays, two_mirrors
    _, c = traced(ref, scene_dict("cornell-box"), (24, 24))
    assert c["reflection"] == 0 and c["transmission"] == 0 and c["shadow"] > 0
    image, c = traced(ref, LIGHT_BEHIND, (24, 18))
    assert c["shadow"] == 0 and c["camera"] == 24 * 18
    for r, cut, depth in ((0.5, 0.1, 10), (0.5, 0.01, 10), (0.8, 0.01, 4)):
        _, c = traced(ref, two_mirrors(r, cut, depth), (8, 6))
        assert c["reflection"] == 48 * mirror_rays(r, cut, depth)
    # no hierarchy where it cannot pay off: the Whitted scene has 2 spheres
    _, c = traced(ref, scene_dict("whitted"), (16, 12))
    assert c["nodes_visited"] == 0 and c["tests"] > 0


def test05_index_of_refraction_one_vanishes(ref):
    data = scene_dict("whitted")
    data["materials"]["air"] = {"ambient": [0, 0, 0], "diffuse": [0, 0, 0], "transmittance": [1, 1, 1], "ior": 1.0,
                                "fresnel": True}
    with_air = copy.deepcopy(data)
    with_air["objects"][2]["material"] = "air"
    without = copy.deepcopy(data)
    del without["objects"][2]
    a, ca = traced(ref, with_air, (64, 48))
    b, _ = traced(ref, without, (64, 48))
    assert ca["transmission"] > 0                      # the rays did go through the sphere
    assert np.abs(a - b).max() < 1e-6                 # spawn offsets move the rays by ~1e-9 at each crossing


def test06_primary_visibility_matches_pyrender(ref):
    import sys
    sys.path.insert(0, str(BUNDLED_DIR.parent.parent))
    from autograder.whitted import checks, truth
    p = {"scene": scene_dict("cornell-box"), "size": [64, 64]}
    rays = whitted.probe_primary_rays(ref, **p)
    out = whitted.probe_closest_hit(ref, **p, **rays)
    expected = truth.depth_range(p)
    assert [checks.depth_visibility(out, expected, p), checks.depth_normals(out, expected, p)] == [None, None]
    wrong = dict(out, t=out["t"] * 1.01)               # the check can fail
    assert checks.depth_visibility(wrong, expected, p) is not None


def test07_hierarchy_is_valid_and_agrees_with_brute_force(ref):
    ts = whitted.prepare(load_scene("cornell-box"), ref, hierarchy=True)
    lo, hi = ts.bounds()
    assert tracescene.bvh_problems(ts.bvh, lo, hi) == []
    o, d = ref.camera_rays(load_scene("cornell-box").camera, 40, 40)
    t1, p1, n1 = ref.closest_hit(ts, o, d)
    visited = ts.counters["nodes_visited"]
    flat = whitted.prepare(load_scene("cornell-box"), ref, hierarchy=False)
    t2, p2, n2 = ref.closest_hit(flat, o, d)
    assert np.array_equal(p1, p2) and np.allclose(t1, t2, rtol=1e-12) and np.allclose(n1, n2)
    assert visited > 0 and flat.counters["nodes_visited"] == 0


def test08_bundled_mesh_is_what_the_code_makes():
    from cs451.stages.whitted import mesh as _whitted_mesh
    assert _whitted_mesh.TORUS_OBJ.read_text() == _whitted_mesh.obj_text()
    mesh = _whitted_mesh.rippled_torus()
    assert len(mesh.faces) >= 50_000 and mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0


def test09_renders_every_whitted_scene_without_nan(ref):
    for name in ("whitted", "cornell-spheres", "cornell-box", "rippled-torus"):
        image, counters = whitted.render_traced(load_scene(name), ref, (24, 18))
        assert image.shape == (18, 24, 3) and np.isfinite(image).all() and image.max() > 0
        assert set(counters) == set(tracescene.COUNTERS)
    _, c = whitted.render_traced(load_scene("rippled-torus"), ref, (24, 18))
    assert c["nodes_visited"] > 0                      # 55k triangles: the hierarchy is used


def test10_supersampling_averages_the_grid(ref):
    data = scene_dict("whitted")
    one, _ = traced(ref, data, (8, 6), spp=1)
    fine, _ = traced(ref, data, (16, 12), spp=1)
    four, _ = traced(ref, data, (8, 6), spp=4)
    assert np.allclose(four, fine.reshape(6, 2, 8, 2, 3).mean(axis=(1, 3)))
    assert not np.allclose(four, one)


def test11_starter_imports_and_every_task_is_a_stub():
    stage = get_stage("whitted")
    module = load_impl(resolve_impl("starter", "whitted"), "whitted")
    for task in stage.tasks:
        with pytest.raises(NotImplementedError, match=task.id):
            getattr(module, task.function)(*[None] * len(task.params))
    with pytest.raises(KitError, match="W4 build_bvh.. is not implemented yet"):
        whitted.render(load_scene("rippled-torus"), module, (8, 6))


def _points_by_task(result):
    out = {}
    for r in result.results:
        out[r.test.task] = out.get(r.test.task, 0.0) + r.score
    return out


@pytest.mark.spawns
@pytest.mark.slow
@pytest.mark.parametrize("file, old, new, task, also", [
    ("camera.py", "y = (1.0 - 2.0 * (np.arange(height) + 0.5) / height) * tan_y",
     "y = (2.0 * (np.arange(height) + 0.5) / height - 1.0) * tan_y", "W1", set()),           # rows from the bottom
    ("optics.py", "t = eta[:, None] * d + (eta * cos_i - cos_t)[:, None] * n",
     "t = eta[:, None] * d - (eta * cos_i - cos_t)[:, None] * n", "W9", set()),               # bent the wrong way
    ("optics.py", "return d - 2.0 * np.einsum(", "return d + 2.0 * np.einsum(", "W8", set()),  # the sign of reflect
    ("optics.py", "rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)", "rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)",
     "W10", set()),                                                                           # r_s written as r_p
    ("bvh.py", "return median_bvh(lo, hi, LEAF_SIZE)", "return median_bvh(lo, hi, 16)", "W4", set()),  # leaves of 16
])
def test15_one_broken_function_loses_its_task_only(make_submission, file, old, new, task, also):
    """Tests of later tasks get the reference's parts (camera rays, hierarchy, reflect/refract/fresnel answers
    for W11), so a bug costs its own task only."""
    from cs451.grading.runner import grade
    result = grade("whitted", make_submission("whitted", file, old, new), show_progress=False)
    got = _points_by_task(result)
    full = {t.id: 0.0 for t in get_stage("whitted").tasks}
    from cs451.grading.runner import load_tests
    for t in load_tests("whitted"):
        full[t.task] += t.points
    assert got[task] < full[task]
    assert {k: v for k, v in got.items() if k != task and k not in also} == \
        {k: v for k, v in full.items() if k != task and k not in also}


def test16_trace_tests_answer_reflect_with_the_references_answers(make_submission, ref):
    """W11's trusted parts: a reflect with the wrong sign is answered by the reference where the reference's own
    trace asked, so the image and the counters are the reference's; without them they are not."""
    from autograder.whitted.public import two_mirrors
    broken = load_impl(resolve_impl(make_submission("whitted", "optics.py", "return d - 2.0 * np.einsum(",
                                                    "return d + 2.0 * np.einsum("), "whitted"), "whitted")
    for scene, size in ((scene_dict("whitted"), [24, 18]), (two_mirrors(0.5, 0.1, 10), [8, 6])):
        parts = whitted.probe_trace_parts(ref, scene, size)
        want = whitted.probe_render(ref, scene, size, **parts)
        got = whitted.probe_render(broken, scene, size, **parts)
        assert np.array_equal(got["image"], want["image"]) and got["reflection"] == want["reflection"] > 0
        alone = whitted.probe_render(broken, scene, size, origins=parts["origins"], directions=parts["directions"])
        assert alone["reflection"] != want["reflection"]
    assert np.array_equal(broken.reflect(np.array([[0.0, 0.0, -1.0]]), np.array([[0.0, 0.0, 1.0]])), [[0.0, 0.0, -3.0]])
