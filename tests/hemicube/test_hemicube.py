"""Stage 3 end to end: the item buffer against ray casting, rendering, and grading (full marks, zero, broken tasks)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from autograder.hemicube import truth
from cs451.errors import InputError, KitError
from cs451.formfactors import HemicubeFormFactors
from cs451.grading.runner import grade, load_tests
from cs451.impl import load_impl, resolve_impl
from cs451.patches import patch_normals, patch_triangles, scene_polygons
from cs451.scene import BUNDLED_DIR, load_scene, parse_scene
from cs451.stages import get_stage, stage_names
from cs451.stages.hemicube import calls


@pytest.fixture(scope="module")
def ref():
    return load_impl(resolve_impl("reference", "hemicube"), "hemicube")


def points_by_task(result):
    out = {}
    for r in result.results:
        out[r.test.task] = out.get(r.test.task, 0.0) + r.score
    return out


def raycast_item_buffer(quads, views, resolution):
    """Ids seen through each cell centre of the five faces, by Embree: what the item buffer must hold."""
    mc = pytest.importorskip("embreex.mesh_construction")   # an optional peer: `pip install -e '.[peers]'`
    rtcs = pytest.importorskip("embreex.rtcore_scene")
    tris, ids = patch_triangles(quads)
    scene = rtcs.EmbreeScene()
    mc.TriangleMesh(scene, tris.astype(np.float32))
    normals = patch_normals(quads)
    r = resolution
    c = -1 + (np.arange(r) + 0.5) * 2 / r
    out = []
    for f in range(5):
        rot, t = views[f][:3, :3], views[f][:3, 3]
        eye = -rot.T @ t - 1e-3 * views[0][2, :3]        # a hair above the patch, so its rays miss the patch itself
        rows = c if f == 0 else (np.arange(r // 2) + 0.5) * 2 / r
        Y, X = np.meshgrid(rows, c, indexing="ij")
        d_eye = np.stack([X, Y, -np.ones_like(X)], axis=-1).reshape(-1, 3)
        d = d_eye @ rot                                  # R^T d for each row vector
        hit = np.asarray(scene.run(np.tile(eye, (len(d), 1)).astype(np.float32), d.astype(np.float32)))
        j = ids[np.maximum(hit, 0)]
        front = (hit >= 0) & (np.einsum("ij,ij->i", d, normals[j]) < 0)
        out.append(np.where(front, j + 1, 0).reshape(Y.shape))
    return out


@pytest.mark.parametrize("patch", [0, 2, 5, 12, 15])
def test01_item_buffer_matches_ray_casting_through_cell_centres(ref, patch):
    quads, _, _ = scene_polygons(load_scene("cornell-box"))
    ff = HemicubeFormFactors(quads, calls(ref), resolution=64, rotate=True, seed=3)
    views = ff.views_for(patch)
    top, sides = ff.renderer.render(views[None])[0]
    want = raycast_item_buffer(quads, views, 64)
    got = [top] + list(sides)
    bad = sum(int((g != w).sum()) for g, w in zip(got, want))
    total = sum(w.size for w in want)
    assert bad / total < 0.01, f"{bad} of {total} cells differ from ray casting"


def test02_stage_is_registered_with_its_tasks():
    assert "hemicube" in stage_names()
    stage = get_stage("hemicube")
    assert [t.id for t in stage.tasks] == ["H1", "H2", "H3", "H4", "H5", "H6", "H7"]
    assert [t.id for t in stage.tasks if t.optional] == ["H7"]


def test03_render_the_item_buffer_and_the_form_factors(ref):
    scene = load_scene("cornell-box")
    image = get_stage("hemicube").render(scene, ref, (96, 64))
    assert image.shape == (64, 96, 3) and np.isfinite(image).all() and image.max() > 0
    data = json.loads((BUNDLED_DIR / "cornell-box.json").read_text())
    data["options"] = {"hemicube": {"patch": 15, "view": "formfactors"}}
    image = get_stage("hemicube").render(parse_scene(data, "cb"), ref, (64, 64))
    assert image.shape == (64, 64, 3) and image.max() == pytest.approx(1.0, abs=1e-6)


@pytest.mark.parametrize("options, message", [({"patch": 99}, "patch"), ({"resolution": 33}, "even"),
                                              ({"view": "x"}, "view")])
def test04_bad_options_name_the_field(ref, options, message):
    data = json.loads((BUNDLED_DIR / "cornell-box.json").read_text())
    data["options"] = {"hemicube": options}
    with pytest.raises((InputError, KitError), match=message):
        get_stage("hemicube").render(parse_scene(data, "cb"), ref, (32, 32))


def test05_tests_are_declared_with_points_and_tolerances():
    tests = load_tests("hemicube")
    assert sum(t.points for t in tests if not t.extension) == 100
    assert {t.task for t in tests} == {f"H{i}" for i in range(1, 8)}
    assert {t.task for t in tests if t.extension} == {"H7"}     # the optional extension, outside the 100
    assert all(t.tolerance for t in tests) and any(t.hidden for t in tests)


def test06_truth_quotes_are_what_the_tests_expect():
    assert round(truth.howell_c11(1, 1, 1), 5) == 0.19982 and round(truth.howell_c14(1, 1, 1), 5) == 0.20004


@pytest.mark.spawns
@pytest.mark.slow
@pytest.mark.parametrize("file, old, new, task, message", [
    ("tables.py", "top = area / (np.pi * (x * x + y * y + 1.0) ** 2)", "top = area / (np.pi * (x * x + y * y + 1.0))", "H1", "cell"),
    ("views.py", "looks = [(n, u), (u, n), (-u, n), (s, n), (-s, n)]", "looks = [(n, u), (u, n), (-u, n), (s, n), (-s, -n)]", "H2", "view"),
    ("itembuffer.py", "item = gl_FrontFacing ? v_id + 1u : 0u;", "item = v_id + 1u", "H4", "does not compile"),
    ("itembuffer.py", "item = gl_FrontFacing ? v_id + 1u : 0u;", "item = v_id + 1u;", "H4", "image differs"),  # back faces
    ("itembuffer.py", "    return row[1:n + 1]", "    return row[:n]", "H5", ""),
    ("contour.py", "return float(abs(total) / (2 * np.pi))", "return float(abs(total) / np.pi)", "H6", ""),
])
def test09_one_broken_function_loses_points_there_only(make_submission, file, old, new, task, message):
    """Each task's tests get the reference's parts for the rest (views for H4, item buffers and tables for H5,
    hemicube rows for H6): a broken H4 no longer hides whether H5 and H6 are right."""
    result = grade("hemicube", make_submission("hemicube", file, old, new), show_progress=False)
    got = points_by_task(result)
    full = {t: sum(x.points for x in load_tests("hemicube") if x.task == t) for t in got}
    assert got[task] < full[task]
    broken = [r for r in result.results if r.test.task == task and r.score < r.test.points]
    assert broken and message in broken[0].verdict.message
    assert {k: v for k, v in got.items() if k != task} == {k: v for k, v in full.items() if k != task}


def test10_wrong_shape_from_the_tables_is_one_line(make_submission):
    root = make_submission("hemicube", "tables.py", "    return top, side", "    return top, side.T")
    module = load_impl(resolve_impl(root, "hemicube"), "hemicube")
    with pytest.raises(KitError, match=r"H1 delta_form_factors\(\) side returned shape \(8, 4\), expected \(4, 8\)"):
        HemicubeFormFactors(truth.cube(1), calls(module), resolution=8).row(0)


@pytest.mark.parametrize("file, old, new, message", [
    ("itembuffer.py", "v_id + 1u : 0u", "v_id + 1 : 0u",
     r"^H4: the fragment shader does not compile: line 4, column \d+: error: "),      # int + uint
    ("itembuffer.py", "void main() {\n    gl_Position", "void mane() {\n    gl_Position",
     r"^H4: the vertex shader does not compile: in the kit's code after your source \(is main\(\) there\?\)"),
])
def test11_shader_errors_name_the_shader_and_count_the_students_own_lines(make_submission, file, old, new, message):
    module = load_impl(resolve_impl(make_submission("hemicube", file, old, new), "hemicube"), "hemicube")
    with pytest.raises(KitError, match=message):
        HemicubeFormFactors(truth.cube(1), calls(module), resolution=8).row(0)
