"""Stage 2 stress tests: no self-intersection or shadow acne at any scale, grazing and degenerate cases,
rays from inside, the numpy and compiled paths agreeing, and Embree (when installed) agreeing on hits."""
from __future__ import annotations

import copy
import importlib
import json

import numpy as np
import pytest

from cs451 import tracescene
from cs451.impl import load_impl, resolve_impl
from cs451.scene import BUNDLED_DIR, load_scene, parse_scene
from cs451.stages import whitted

RNG_SEED = 12345


@pytest.fixture(scope="module")
def ref():
    return load_impl(resolve_impl("reference", "whitted"), "whitted")


def scaled(data: dict, s: float) -> dict:
    """The scene with every length multiplied by s (lights keep their brightness at the same relative place)."""
    d = copy.deepcopy(data)
    cam = d["camera"]
    for k in ("eye", "center"):
        cam[k] = [v * s for v in cam[k]]
    cam["near"], cam["far"] = cam.get("near", 0.1) * s, cam.get("far", 1000) * s
    for light in d["lights"]:
        if light["type"] == "point":
            light["position"] = [v * s for v in light["position"]]
        else:
            for k in ("corner", "edge_u", "edge_v"):
                light[k] = [v * s for v in light[k]]
            light["radiance"] = list(light["radiance"])   # power ∝ area ∝ s², falloff ∝ 1/s²: unchanged
    for obj in d["objects"]:
        if obj["type"] == "sphere":
            obj["center"], obj["radius"] = [v * s for v in obj["center"]], obj["radius"] * s
        elif obj["type"] == "plane":
            obj["point"] = [v * s for v in obj["point"]]
            obj["checker"] = obj.get("checker", 0) * s
        elif obj["type"] == "polygon":
            obj["vertices"] = [[v * s for v in p] for p in obj["vertices"]]
    return d


def bundled(name: str) -> dict:
    return json.loads((BUNDLED_DIR / f"{name}.json").read_text())


@pytest.mark.parametrize("name", ["whitted", "cornell-spheres"])
@pytest.mark.parametrize("s", [1e-4, 1e5])
def test01_huge_and_tiny_scenes_render_the_same_image(ref, name, s):
    base, _ = whitted.render_traced(parse_scene(bundled(name)), ref, (48, 36))
    image, _ = whitted.render_traced(parse_scene(scaled(bundled(name), s)), ref, (48, 36))
    err = np.abs(image - base).max(axis=2)
    # no acne, no lost reflection: every pixel within half an 8-bit step. (At 1e-4 the spawn offset, 1e-9 plus
    # 1e-9·|p|, is 1e-5 of the scene, which moves reflected rays a little: measured differences up to 5e-4.)
    assert err.max() < 2e-3, f"a pixel differs by {err.max():.3g} at scale {s:g}"
    assert (err > 1e-6).mean() < 0.1


@pytest.mark.parametrize("s", [1e-4, 1.0, 1e5])
def test02_no_shadow_acne_on_a_grazing_lit_plane(ref, s):
    """A plane lit almost edge-on: every pixel is kd·I·cosθ exactly (one speckle of self-shadowing would show)."""
    data = {"camera": {"eye": [0, 2 * s, 6 * s], "center": [0, 0, 0], "fovy": 50, "near": 0.01 * s, "far": 100 * s},
            "ambient": [0, 0, 0],
            "lights": [{"type": "point", "position": [30 * s, 0.05 * s, 0], "specular": [0, 0, 0]}],
            "materials": {"m": {"diffuse": [0.8, 0.8, 0.8], "ambient": [0, 0, 0]}},
            "objects": [{"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0], "material": "m"},
                        {"type": "polygon", "material": "m",
                         "vertices": [[-1 * s, 0.3 * s, 1 * s], [1 * s, 0.3 * s, 1 * s], [1 * s, 0.3 * s, -1 * s], [-1 * s, 0.3 * s, -1 * s]]}]}
    sc = parse_scene(data)
    image, counters = whitted.render_traced(sc, ref, (64, 48))
    o, d = ref.camera_rays(sc.camera, 64, 48)
    t_plane = -o[:, 1] / d[:, 1]
    t_quad = (0.3 * s - o[:, 1]) / d[:, 1]
    p_quad = o + t_quad[:, None] * d
    on_quad = (t_quad > 0) & (np.abs(p_quad[:, 0]) <= s) & (np.abs(p_quad[:, 2]) <= s)
    p = o + np.where(on_quad, t_quad, t_plane)[:, None] * d
    to_light = np.array([30 * s, 0.05 * s, 0]) - p
    cos = to_light[:, 1] / np.linalg.norm(to_light, axis=1)
    cos = np.where(on_quad, np.where(to_light[:, 1] > 0, cos, 0), cos)
    # the quad shadows part of the plane: check only plane pixels the quad cannot shadow (x > s)
    free = on_quad | (p[:, 0] > 1.01 * s)
    want = 0.8 * np.maximum(cos, 0)
    got = image.reshape(-1, 3)[:, 0]
    hit = t_plane > 0
    assert np.abs(got - want)[free & hit].max() < 1e-9
    assert counters["shadow"] > 0


def test03_spawned_rays_never_rehit_their_own_triangle(ref):
    """pbrt-v4's Reintersect test: from random points of 1000 random triangles, rays leave on either side."""
    sc = load_scene("rippled-torus")
    ts = whitted.prepare(sc, ref)
    rng = np.random.default_rng(RNG_SEED)
    k = rng.choice(ts.n_triangles, 1000, replace=False)
    v0, v1, v2 = ts.tri_v0[k], ts.tri_v1[k], ts.tri_v2[k]
    u = rng.random((1000, 2))
    u = np.where(u.sum(axis=1, keepdims=True) > 1, 1 - u, u)
    p = v0 + u[:, :1] * (v1 - v0) + u[:, 1:] * (v2 - v0)
    n = np.cross(v1 - v0, v2 - v0)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    d = rng.normal(size=(1000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    for side in (1, -1):
        dd = np.where((np.einsum("ij,ij->i", d, n) * side)[:, None] > 0, d, -d)
        t, prim, _ = ref.closest_hit(ts, tracescene.spawn(p, n, dd), dd)
        assert not np.any(prim == k + ts.n_spheres), "a spawned ray hit its own triangle"


def test04_spheres_inside_and_out(ref):
    """From points on a sphere: outward rays never hit it again; inward rays cross it, at the chord length."""
    data = {"camera": {"eye": [0, 0, 10], "center": [0, 0, 0]},
            "objects": [{"type": "sphere", "center": [1e3, -2e3, 5e2], "radius": 0.5}]}
    ts = tracescene.build(parse_scene(data))
    rng = np.random.default_rng(RNG_SEED)
    n = rng.normal(size=(2000, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    c = ts.sphere_center[0]
    p = c + 0.5 * n
    d = rng.normal(size=(2000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    out = np.where(np.einsum("ij,ij->i", d, n)[:, None] > 0, d, -d)
    t, prim, _ = ref.closest_hit(ts, tracescene.spawn(p, n, out), out)
    assert np.all(prim == -1)
    inward = -out
    start = tracescene.spawn(p, n, inward)
    t, prim, _ = ref.closest_hit(ts, start, inward)
    exit_point = start + t[:, None] * inward
    chord = 2 * 0.5 * np.einsum("ij,ij->i", -inward, n)
    assert np.all(prim == 0)
    assert np.allclose(np.linalg.norm(exit_point - c, axis=1), 0.5, rtol=0, atol=1e-9)   # on the far side
    assert np.all(t > 0.5 * chord)                       # not the near side again, however grazing


def test05_grazing_and_parallel_rays_give_no_nan(ref):
    ts = tracescene.build(parse_scene({"camera": {"eye": [0, 0, 10], "center": [0, 0, 0]},
                                     "objects": [{"type": "sphere", "radius": 1},
                                                 {"type": "plane", "point": [0, -1, 0], "normal": [0, 1, 0]}]}))
    o = np.array([[-5, 1, 0], [-5, -1, 0], [-5, 1 + 1e-12, 0], [-5, 1 - 1e-12, 0], [0, -1, 5]], float)
    d = np.array([[1, 0, 0], [1, 0, 0], [1, 0, 0], [1, 0, 0], [0, 0, -1]], float)
    t, prim, normals = ref.closest_hit(ts, o, d)
    assert not np.isnan(t).any() and not np.isnan(normals).any()
    assert prim[2] == -1 and prim[3] == 0          # just above the sphere misses, just below hits
    t0, t1 = ref.intersect_sphere(o, d, np.zeros(3), 1.0)
    assert not np.isnan(t0).any() and np.isclose(t0[0], 5.0) and np.isclose(t1[0], 5.0)  # tangent: one double root


def test06_degenerate_triangles_are_never_hit(ref, tmp_path):
    obj = tmp_path / "degenerate.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nv 0 0 0\n"
                   "f 1 2 3\nf 1 1 4\nf 1 5 4\nf 1 2 4\n")   # collinear, repeated vertex, coincident, one good
    data = {"camera": {"eye": [0.3, 0.2, 3], "center": [0.3, 0.2, 0]},
            "objects": [{"type": "mesh", "file": str(obj)}]}
    sc = parse_scene(data, str(tmp_path / "s.json"), source=str(tmp_path / "s.json"))
    ts = tracescene.build(sc)
    o = np.tile([[0.5, 0.0, 1.0]], (4, 1)) + np.array([[0, 0, 0], [0.1, 0, 0], [-0.5, 0.5, 0], [-0.2, 0.2, 0]])
    d = np.tile([[0, 0, -1.0]], (4, 1))
    t, prim, normals = ref.closest_hit(ts, o, d)
    assert np.all((prim == -1) | (prim == 3)) and not np.isnan(normals).any()
    image, _ = whitted.render_traced(sc, ref, (16, 16))
    assert np.isfinite(image).all()


def test07_camera_inside_a_glass_sphere(ref):
    data = bundled("whitted")
    data["camera"]["eye"] = data["objects"][2]["center"]
    data["camera"]["center"] = [0, 0.5, -3]
    image, counters = whitted.render_traced(parse_scene(data), ref, (32, 24))
    assert np.isfinite(image).all() and counters["transmission"] > 0


def both_paths(ref, ts, o, d) -> tuple[tuple, tuple]:
    """(t, primitive, normal, shadow transmittance) of each ray by the numpy path and by the compiled kernels;
    the shadow rays run from halfway to each hit (or one unit along a miss) to the first light."""
    from cs451.stages.whitted import accel
    wave = importlib.import_module(ref.__name__ + ".wavefront")
    with accel.forced("compiled"), whitted.STAGE.accelerated(ref):
        t2, p2, n2 = ref.closest_hit(ts, o, d)
        x = o + np.where(np.isfinite(t2), t2 * 0.5, 1.0)[:, None] * d
        target = np.tile(ts.light_position[0], (len(o), 1))
        s2 = ref.shadow_transmission(ts, x, target)
    t1, p1, n1, _, _ = wave.closest(ts, o, d)
    seg = target - x
    dist = np.linalg.norm(seg, axis=1)
    s1, _, _ = wave.transmission(ts, x, seg / dist[:, None], dist)
    return (t1, p1, n1, s1), (t2, p2, n2, s2)


def test08_numpy_and_compiled_paths_agree(ref):
    for name in ("rippled-torus", "whitted", "cornell-box"):
        sc = load_scene(name)
        ts = whitted.prepare(sc, ref)
        o, d = ref.camera_rays(sc.camera, 64, 48)
        (t1, p1, n1, s1), (t2, p2, n2, s2) = both_paths(ref, ts, o, d)
        assert np.array_equal(p1, p2) and np.allclose(t1, t2, rtol=1e-12) and np.allclose(n1, n2)
        assert np.allclose(s1, s2)


def test09_embree_finds_the_same_closest_hits(ref):
    rtcs = pytest.importorskip("embreex.rtcore_scene")
    from embreex.mesh_construction import TriangleMesh
    sc = load_scene("rippled-torus")
    ts = whitted.prepare(sc, ref)
    o, d = ref.camera_rays(sc.camera, 160, 120)
    t, prim, _ = ref.closest_hit(ts, o, d)
    scene = rtcs.EmbreeScene()
    TriangleMesh(scene, np.stack([ts.tri_v0, ts.tri_v1, ts.tri_v2], axis=1).astype(np.float32))
    res = scene.run(o.astype(np.float32), d.astype(np.float32), output=1)
    tri = (prim >= ts.n_spheres) & (prim < ts.n_bounded)
    ours = np.where(tri, prim - ts.n_spheres, -1)
    # where our nearest hit is the mesh, Embree (mesh only) must hit the same triangle at the same distance
    same = res["primID"][tri] == ours[tri]
    assert same.mean() > 0.999
    assert np.allclose(res["tfar"][tri][same], t[tri][same], rtol=1e-5)


def test10_area_light_matches_mitsuba_direct_lighting(ref, tmp_path):
    """The Cornell box's direct light (the area light's radiometry: L·cosθ·cosθ'/r², albedo/π) against
    Mitsuba 3's path tracer limited to direct lighting (max_depth 2), same camera, box filter."""
    mi = pytest.importorskip("mitsuba")
    import trimesh
    mi.set_variant("scalar_rgb")
    sc = load_scene("cornell-box")
    ts = tracescene.build(sc)
    shapes = {}
    mats = ts.prim_material[ts.n_spheres:ts.n_bounded]
    for m in np.unique(mats):
        tris = np.stack([ts.tri_v0, ts.tri_v1, ts.tri_v2], axis=1)[mats == m]
        path = tmp_path / f"m{m}.obj"
        trimesh.Trimesh(tris.reshape(-1, 3), np.arange(3 * len(tris)).reshape(-1, 3), process=False).export(path)
        shapes[f"m{m}"] = {"type": "obj", "filename": str(path), "face_normals": True,
                           "bsdf": {"type": "twosided", "material": {"type": "diffuse", "reflectance": {
                               "type": "rgb", "value": ts.mat_diffuse[m].tolist()}}}}
    light = sc.lights[0]
    c, eu, ev = (np.asarray(v, float) for v in (light.corner, light.edge_u, light.edge_v))
    path = tmp_path / "light.obj"
    trimesh.Trimesh(np.array([c, c + eu, c + eu + ev, c + ev]), [[0, 1, 2], [0, 2, 3]], process=False).export(path)
    shapes["light"] = {"type": "obj", "filename": str(path), "face_normals": True,
                       "emitter": {"type": "area", "radiance": {"type": "rgb", "value": list(light.radiance)}}}
    cam, w = sc.camera, 32
    scene = mi.load_dict({"type": "scene", "integrator": {"type": "path", "max_depth": 2},
                          "sensor": {"type": "perspective", "fov": cam.fovy, "fov_axis": "y",
                                     "to_world": mi.ScalarTransform4f().look_at(origin=list(cam.eye), target=list(cam.center),
                                                                                up=list(cam.up)),
                                     "film": {"type": "hdrfilm", "width": w, "height": w, "rfilter": {"type": "box"}},
                                     "sampler": {"type": "independent", "sample_count": 256, "seed": 1}}, **shapes})
    theirs = np.array(mi.render(scene))[..., :3]
    ours, _ = whitted.render_traced(sc, ref, (w, w), spp=16, light_samples=256)
    # the emitter is visible to Mitsuba's camera and not to ours: leave it and its neighbours out
    emitter = (theirs > 1.0).any(axis=2)
    near = np.zeros_like(emitter)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            near |= np.roll(np.roll(emitter, dy, 0), dx, 1)
    keep = ~near
    assert keep.mean() > 0.95
    assert np.allclose(theirs[keep].mean(axis=0), ours[keep].mean(axis=0), rtol=0.03)
    blocks = lambda x: (x * keep[..., None]).reshape(8, 4, 8, 4, 3).sum(axis=(1, 3))
    full = keep.reshape(8, 4, 8, 4).all(axis=(1, 3))
    rel = np.abs(blocks(theirs) - blocks(ours)) / np.maximum(blocks(ours), 0.16)
    assert np.median(rel[full]) < 0.02 and np.percentile(rel[full], 90) < 0.08


def translated(data: dict, offset: float) -> dict:
    """The scene moved by (offset, offset, offset): camera, light, plane, sphere and mesh alike."""
    d = copy.deepcopy(data)
    move = lambda p: [v + offset for v in p]   # noqa: E731
    d["camera"]["eye"], d["camera"]["center"] = move(d["camera"]["eye"]), move(d["camera"]["center"])
    for light in d["lights"]:
        light["position"] = move(light["position"])
    for obj in d["objects"]:
        key = {"plane": "point", "sphere": "center", "mesh": "translate"}[obj["type"]]
        obj[key] = move(obj.get(key, [0, 0, 0]))
    return d


@pytest.mark.parametrize("offset", [0.0, 1e6])
def test11_the_float32_box_test_loses_no_hit(ref, offset):
    """The compiled traversal tests its boxes in float32, widened by the test's error bound. Far from the origin a
    float32 step (0.06 at 1e6) is wider than the torus's triangles, and axis-parallel rays aimed at the mesh's
    vertices run along box faces with exact zeros in their directions: every hit must still be the float64
    numpy path's, and every shadow ray's transmittance too."""
    sc = parse_scene(translated(bundled("rippled-torus"), offset), "rippled-torus moved")
    ts = whitted.prepare(sc, ref)
    assert ts.bvh is not None
    o, d = ref.camera_rays(sc.camera, 160, 120)
    rng = np.random.default_rng(RNG_SEED)
    vertex = ts.tri_v1[rng.choice(ts.n_triangles, 6000, replace=False)]
    axis = np.repeat(np.eye(3), 2000, axis=0) * rng.choice([-1.0, 1.0], (6000, 1))
    o = np.concatenate([o, vertex - 0.5 * axis])       # aimed at a vertex along x, y or z, grazing box faces
    d = np.concatenate([d, axis])
    (t1, p1, _, s1), (t2, p2, _, s2) = both_paths(ref, ts, o, d)
    hit1, hit2 = np.isfinite(t1), np.isfinite(t2)
    assert hit2[-6000:].mean() > 0.75                   # most vertex rays hit (some only graze the surface)
    assert np.array_equal(hit1, hit2), f"{np.sum(hit1 != hit2)} rays hit in one path and not the other"
    assert np.allclose(t1[hit1], t2[hit1], rtol=1e-12, atol=0)
    camera = slice(0, len(o) - 6000)                    # (a vertex is shared: any of its triangles may be named)
    assert np.mean(p1[camera] == p2[camera]) > 0.999
    assert np.array_equal(s1, s2)
