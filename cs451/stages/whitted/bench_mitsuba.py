"""A stage-2 scene as Mitsuba 3 sees it, for timing a production renderer's frame beside the kit's.

Same camera, image size and samples per pixel; the same spheres and triangles (one PLY mesh per
material, flat normals) and, for each infinite plane, a square 10⁴ times the scene across with the
same checkerboard. Materials map to the nearest Mitsuba BSDF: glass (any transmittance) to
``dielectric``, a mirror (reflectance above 0.5) to ``conductor`` (an ideal mirror), the rest to
``diffuse`` with the diffuse colour. Point lights become ``point`` emitters, area lights emitting
rectangles. Mitsuba is physically based (1/r² falloff, albedo/π), the kit is Whitted's model, so the
two images differ in brightness: the bench compares times, not pixels (the Cornell box's radiometry
is compared in ``tests/whitted/test_whitted_robust.py``). Direct lighting only, with the kit's number of shadow
rays: the ``direct`` integrator with one emitter sample per light sample of the kit (2 for the Whitted
scene's two point lights, 16 for the Cornell light) and no BSDF samples, so a pixel costs a camera ray
and as many shadow rays as the kit casts from a diffuse point; mirrors and glass stay black (Mitsuba
does not follow them in direct lighting; the kit does, and counts those rays).
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from cs451.tracescene import TraceScene
from cs451.scene import AreaLight, PointLight, Scene

VARIANT = "scalar_rgb"   # the LLVM variants do not run on the kit's test machine


def _bsdf(ts: TraceScene, m: int) -> dict:
    if np.any(ts.mat_transmittance[m] > 0):
        return {"type": "dielectric", "int_ior": float(ts.mat_ior[m]), "ext_ior": 1.0}
    if np.max(ts.mat_reflectance[m]) > 0.5:
        return {"type": "conductor", "material": "none"}
    return {"type": "diffuse", "reflectance": {"type": "rgb", "value": np.clip(ts.mat_diffuse[m], 0, 0.99).tolist()}}


def _frame(origin, u, v, n) -> list[list[float]]:
    """The 4×4 matrix taking x, y, z to u, v, n at origin."""
    return np.column_stack([np.append(u, 0), np.append(v, 0), np.append(n, 0), np.append(origin, 1)]).tolist()


def mitsuba_dict(scene: Scene, ts: TraceScene, size: tuple[int, int], spp: int, folder: Path) -> dict[str, Any]:
    """The scene as a ``mitsuba.load_dict`` dictionary; meshes are written to ``folder`` as PLY files."""
    import mitsuba as mi
    import trimesh
    cam = scene.camera
    out: dict[str, Any] = {
        "type": "scene",
        "integrator": {"type": "direct", "emitter_samples": len(ts.light_position), "bsdf_samples": 0},
        "sensor": {"type": "perspective", "fov": cam.fovy, "fov_axis": "y",
                   "to_world": mi.ScalarTransform4f().look_at(origin=list(cam.eye), target=list(cam.center),
                                                              up=list(cam.up)),
                   "film": {"type": "hdrfilm", "width": size[0], "height": size[1], "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": spp, "seed": 1}}}
    for s in range(ts.n_spheres):
        out[f"sphere{s}"] = {"type": "sphere", "center": ts.sphere_center[s].tolist(),
                             "radius": float(ts.sphere_radius[s]), "bsdf": _bsdf(ts, int(ts.prim_material[s]))}
    tri_mat = ts.prim_material[ts.n_spheres:ts.n_bounded]
    tris = np.stack([ts.tri_v0, ts.tri_v1, ts.tri_v2], axis=1)
    for m in np.unique(tri_mat):
        path = folder / f"mesh{m}.ply"
        t = tris[tri_mat == m].reshape(-1, 3)
        trimesh.Trimesh(t, np.arange(len(t)).reshape(-1, 3), process=False).export(path)
        out[f"mesh{m}"] = {"type": "ply", "filename": str(path), "face_normals": True, "bsdf": _bsdf(ts, int(m))}
    lo, hi = (ts.bounds() if ts.n_bounded else (np.zeros((1, 3)), np.ones((1, 3))))
    extent = 1e4 * max(float(np.ptp(np.concatenate([lo, hi, [np.asarray(cam.eye)]]), axis=0).max()), 1.0)
    for p in range(ts.n_planes):
        k = ts.n_bounded + p
        u, v, n = ts.plane_u[p], ts.plane_v[p], ts.plane_normal[p]
        bsdf = _bsdf(ts, int(ts.prim_material[k]))
        size_p = ts.plane_checker[p]
        if size_p > 0 and bsdf["type"] == "diffuse":
            odd = np.clip(ts.mat_diffuse[ts.plane_checker_material[p]], 0, 0.99).tolist()
            bsdf["reflectance"] = {"type": "checkerboard", "color0": bsdf["reflectance"],
                                   "color1": {"type": "rgb", "value": odd},
                                   "to_uv": mi.ScalarTransform4f().scale([extent / size_p] * 3)}
        out[f"plane{p}"] = {"type": "rectangle", "bsdf": bsdf,
                            "to_world": mi.ScalarTransform4f(_frame(ts.plane_point[p], u * extent, v * extent, n))}
    for i, light in enumerate(scene.lights):
        if isinstance(light, PointLight):
            out[f"light{i}"] = {"type": "point", "position": list(light.position),
                                "intensity": {"type": "rgb", "value": list(light.diffuse)}}
        elif isinstance(light, AreaLight):
            c, eu, ev = (np.asarray(x, float) for x in (light.corner, light.edge_u, light.edge_v))
            normal = np.cross(eu, ev)
            out[f"light{i}"] = {"type": "rectangle", "to_world": mi.ScalarTransform4f(
                                    _frame(c + 0.5 * (eu + ev), 0.5 * eu, 0.5 * ev, normal / np.linalg.norm(normal))),
                                "emitter": {"type": "area", "radiance": {"type": "rgb", "value": list(light.radiance)}}}
    return out
