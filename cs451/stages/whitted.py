"""Stage 2, Whitted ray tracing: its interface, and the scaffolding that renders with a student's functions.

The scaffolding holds no solution: it turns a scene into arrays
(:mod:`cs451.raytrace`), asks the submission for a hierarchy when one can pay off,
then for camera rays and their colours, and averages supersamples into pixels.
Everything a student writes is called through :data:`STAGE`, and checked.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import raytrace, schema
from ..errors import KitError
from ..scene import Camera, Scene, parse_scene
from ..schema import Context, field
from .base import Stage, Task, as_array, student_call

TASKS = (
    Task("W1", "camera_rays", "Camera rays", ("camera", "width", "height")),
    Task("W2", "intersect_sphere", "Ray-sphere intersection", ("origins", "directions", "center", "radius")),
    Task("W3", "intersect_triangle", "Watertight ray-triangle intersection", ("origins", "directions", "v0", "v1", "v2")),
    Task("W4", "build_bvh", "The bounding volume hierarchy", ("lo", "hi")),
    Task("W5", "closest_hit", "Closest hit", ("scene", "origins", "directions")),
    Task("W6", "local_shading", "Local shading", ("normals", "to_eye", "to_light", "light_diffuse", "light_specular",
                                                  "diffuse", "specular", "shininess")),
    Task("W7", "shadow_transmission", "Shadow rays", ("scene", "origins", "targets")),
    Task("W8", "reflect", "Reflection", ("directions", "normals")),
    Task("W9", "refract", "Refraction", ("directions", "normals", "eta")),
    Task("W10", "fresnel", "Fresnel reflectance", ("cos_i", "eta")),
    Task("W11", "trace", "Recursive tracing and the cut-off", ("scene", "origins", "directions")),
)


@dataclass(frozen=True)
class WhittedOptions:
    max_depth: int = field("Most bounces (reflections and refractions) after the camera ray.", 5, schema.at_least(0))
    min_weight: float = field("The cut-off: a ray whose weight β (max over RGB) falls below this is not cast.", 0.01,
                              schema.non_negative)
    spp: int = field("Samples per pixel on a regular grid (1, 4, 9, 16, …: a square).", 1, schema.positive)
    light_samples: int = field("Shadow rays per area light and shading point, overriding each light's `samples` (0: keep).",
                               0, schema.non_negative)

    def validate(self, ctx: Context) -> None:
        if math.isqrt(self.spp) ** 2 != self.spp:
            raise ctx.child("spp").error(f"must be a square number (1, 4, 9, 16, …), got {self.spp}")


def options(scene: Scene, **overrides: Any) -> WhittedOptions:
    raw = dict(scene.options.get("whitted", {}))
    raw.update({k: v for k, v in overrides.items() if v is not None})
    return schema.parse_record(WhittedOptions, raw, Context(scene.source or scene.name or "<scene>", "options.whitted"))


# --- calling the student's functions, with checks on what they return --------

def _camera_rays(impl: Any, camera: Camera, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    out = student_call(STAGE, impl, "W1", camera, width, height)
    if not isinstance(out, (tuple, list)) or len(out) != 2:
        raise KitError("W1 camera_rays() must return (origins, directions)")
    n = width * height
    return as_array(out[0], (n, 3), "W1 camera_rays() origins"), as_array(out[1], (n, 3), "W1 camera_rays() directions")


def _build_bvh(impl: Any, lo: np.ndarray, hi: np.ndarray) -> dict[str, np.ndarray]:
    bvh = student_call(STAGE, impl, "W4", lo.copy(), hi.copy())
    if not isinstance(bvh, dict):
        raise KitError(f"W4 build_bvh() must return a dict of arrays, got {type(bvh).__name__}")
    return bvh


def prepare(scene: Scene, impl: Any, max_depth: int | None = None, min_weight: float | None = None,
            light_samples: int | None = None, hierarchy: bool | None = None) -> raytrace.TraceScene:
    """The scene as arrays, with the submission's hierarchy where it can pay off (or where ``hierarchy``)."""
    opts = options(scene, max_depth=max_depth, min_weight=min_weight, light_samples=light_samples)
    ts = raytrace.build(scene, opts.max_depth, opts.min_weight, opts.light_samples or None)
    use = hierarchy if hierarchy is not None else ts.n_bounded > raytrace.HIERARCHY_THRESHOLD
    if use and ts.n_bounded > 0:
        lo, hi = ts.bounds()
        bvh = _build_bvh(impl, lo, hi)
        problems = raytrace.bvh_problems(bvh, lo, hi)
        if problems:
            raise KitError(f"W4 build_bvh(): {problems[0]}")
        ts.bvh = {k: np.asarray(bvh[k]) for k in raytrace.BVH_KEYS}
    return ts


def render_traced(scene: Scene, impl: Any, size: tuple[int, int] | None = None, spp: int | None = None,
                  **trace_options: Any) -> tuple[np.ndarray, dict[str, int]]:
    """Render with the submission's tracer; returns the linear image (h, w, 3) and the tracer's counters."""
    opts = options(scene, spp=spp)
    width, height = size or (scene.image.width, scene.image.height)
    k = math.isqrt(opts.spp)
    ts = prepare(scene, impl, **trace_options)
    origins, directions = _camera_rays(impl, scene.camera, width * k, height * k)
    colours = as_array(student_call(STAGE, impl, "W11", ts, origins, directions), (len(origins), 3), "W11 trace()")
    image = colours.reshape(height, k, width, k, 3).mean(axis=(1, 3))
    return image, dict(ts.counters)


def render(scene: Scene, impl: Any, size: tuple[int, int] | None = None, **opts: Any) -> np.ndarray:
    """Render a scene with a submission's tracer: a linear float image (h, w, 3)."""
    return render_traced(scene, impl, size, **opts)[0]


# --- probes: what the autograder's worker asks a submission for ------------------

def _scene(scene: dict) -> Scene:
    return parse_scene(scene, "<probe scene>")


def _rays(value: Any, what: str) -> np.ndarray:
    return np.asarray(value, dtype=np.float64).reshape(-1, 3)


def probe_camera_rays(impl: Any, camera: dict, width: int, height: int) -> dict[str, np.ndarray]:
    cam = schema.parse_record(Camera, camera, Context("<probe>", "camera"))
    origins, directions = _camera_rays(impl, cam, width, height)
    return {"origins": origins, "directions": directions}


def probe_intersect_sphere(impl: Any, origins: list, directions: list, center: list, radius: float) -> dict[str, np.ndarray]:
    o, d = _rays(origins, "origins"), _rays(directions, "directions")
    out = student_call(STAGE, impl, "W2", o, d, np.asarray(center, float), float(radius))
    if not isinstance(out, (tuple, list)) or len(out) != 2:
        raise KitError("W2 intersect_sphere() must return (t0, t1)")
    t0 = np.asarray(out[0], dtype=np.float64)
    t1 = np.asarray(out[1], dtype=np.float64)
    for name, t in (("t0", t0), ("t1", t1)):
        if t.shape != (len(o),):
            raise KitError(f"W2 intersect_sphere() {name} has shape {t.shape}, expected ({len(o)},)")
        if np.isnan(t).any():
            raise KitError(f"W2 intersect_sphere() {name} contains NaN (a miss must be inf)")
    return {"t0": t0, "t1": t1}


def probe_intersect_triangle(impl: Any, origins: list, directions: list, v0: list, v1: list, v2: list) -> dict[str, np.ndarray]:
    o, d = _rays(origins, "origins"), _rays(directions, "directions")
    tri = [np.broadcast_to(np.asarray(v, float), o.shape).copy() for v in (v0, v1, v2)]
    t = np.asarray(student_call(STAGE, impl, "W3", o, d, *tri), dtype=np.float64)
    if t.shape != (len(o),):
        raise KitError(f"W3 intersect_triangle() returned shape {t.shape}, expected ({len(o)},)")
    if np.isnan(t).any():
        raise KitError("W3 intersect_triangle() returned NaN (a miss must be inf)")
    return {"t": t}


def probe_build_bvh(impl: Any, lo: list | None = None, hi: list | None = None, scene: dict | None = None) -> dict[str, np.ndarray]:
    """The submission's hierarchy over boxes given as lists, or over a scene's primitives."""
    if scene is not None:
        ts = raytrace.build(_scene(scene))
        lo_a, hi_a = ts.bounds()
    else:
        lo_a, hi_a = np.asarray(lo, float).reshape(-1, 3), np.asarray(hi, float).reshape(-1, 3)
    bvh = _build_bvh(impl, lo_a, hi_a)
    out = {"box_lo": lo_a, "box_hi": hi_a}
    for k in raytrace.BVH_KEYS:
        if k not in bvh:
            raise KitError(f"W4 build_bvh() returned no {k!r} (keys needed: {', '.join(raytrace.BVH_KEYS)})")
        out[k] = np.asarray(bvh[k])
    return out


def _hits(impl: Any, ts: raytrace.TraceScene, o: np.ndarray, d: np.ndarray) -> dict[str, np.ndarray]:
    out = student_call(STAGE, impl, "W5", ts, o, d)
    if not isinstance(out, (tuple, list)) or len(out) != 3:
        raise KitError("W5 closest_hit() must return (t, prim, normals)")
    t = np.asarray(out[0], dtype=np.float64)
    if t.shape != (len(o),) or np.isnan(t).any():
        raise KitError(f"W5 closest_hit() t must have shape ({len(o)},) without NaN (inf on a miss), got {t.shape}")
    prim = as_array(out[1], (len(o),), "W5 closest_hit() prim", kind="i")
    normals = as_array(out[2], (len(o), 3), "W5 closest_hit() normals")
    return {"t": t, "prim": prim, "normals": normals}


def probe_primary_rays(impl: Any, scene: dict, size: list[int], **_: Any) -> dict[str, np.ndarray]:
    """Trusted camera rays for a test of later tasks (run on the reference only, through ``given``)."""
    origins, directions = _camera_rays(impl, _scene(scene).camera, size[0], size[1])
    return {"origins": origins, "directions": directions}


def probe_closest_hit(impl: Any, scene: dict, size: list[int] | None = None, hierarchy: bool | None = None,
                      rays: dict | None = None, origins: np.ndarray | None = None,
                      directions: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """Closest hits of the given rays (``rays`` in the parameters, or trusted camera rays as inputs)."""
    ts = prepare(_scene(scene), impl, hierarchy=hierarchy)
    if rays is not None:
        origins, directions = _rays(rays["origins"], "origins"), _rays(rays["directions"], "directions")
    assert origins is not None and directions is not None
    out = _hits(impl, ts, origins, directions)
    out["nodes_visited"] = np.array(ts.counters["nodes_visited"])
    out["tests"] = np.array(ts.counters["tests"])
    out["primitives"] = np.array(ts.n_bounded + ts.n_planes)
    return out


def probe_local_shading(impl: Any, normals: list, to_eye: list, to_light: list, light_diffuse: list,
                        light_specular: list, diffuse: list, specular: list, shininess: list) -> dict[str, np.ndarray]:
    args = [np.asarray(a, dtype=np.float64) for a in (normals, to_eye, to_light, light_diffuse, light_specular,
                                                      diffuse, specular)]
    n = len(args[0])
    out = student_call(STAGE, impl, "W6", *args, np.asarray(shininess, dtype=np.float64))
    return {"colour": as_array(out, (n, 3), "W6 local_shading()")}


def probe_shadow_transmission(impl: Any, scene: dict, origins: list, targets: list) -> dict[str, np.ndarray]:
    ts = prepare(_scene(scene), impl)
    o, x = _rays(origins, "origins"), _rays(targets, "targets")
    out = as_array(student_call(STAGE, impl, "W7", ts, o, x), (len(o), 3), "W7 shadow_transmission()")
    return {"transmission": out, "shadow": np.array(ts.counters["shadow"])}


def probe_reflect(impl: Any, directions: list, normals: list) -> dict[str, np.ndarray]:
    d, n = _rays(directions, "directions"), _rays(normals, "normals")
    return {"r": as_array(student_call(STAGE, impl, "W8", d, n), (len(d), 3), "W8 reflect()")}


def probe_refract(impl: Any, directions: list, normals: list, eta: Any) -> dict[str, np.ndarray]:
    d, n = _rays(directions, "directions"), _rays(normals, "normals")
    out = student_call(STAGE, impl, "W9", d, n, np.asarray(eta, dtype=np.float64))
    if not isinstance(out, (tuple, list)) or len(out) != 2:
        raise KitError("W9 refract() must return (directions, tir)")
    tir = np.asarray(out[1])
    if tir.shape != (len(d),) or tir.dtype.kind not in "bui":
        raise KitError(f"W9 refract() tir must be a ({len(d)},) boolean array, got {tir.dtype} {tir.shape}")
    t = np.asarray(out[0], dtype=np.float64)
    if t.shape != d.shape:
        raise KitError(f"W9 refract() directions have shape {t.shape}, expected {d.shape}")
    t = np.where(tir.astype(bool)[:, None], 0.0, t)
    return {"t": as_array(t, (len(d), 3), "W9 refract() directions"), "tir": tir.astype(bool)}


def probe_fresnel(impl: Any, cos_i: list, eta: Any) -> dict[str, np.ndarray]:
    c = np.asarray(cos_i, dtype=np.float64)
    return {"f": as_array(student_call(STAGE, impl, "W10", c, np.asarray(eta, dtype=np.float64)), (len(c),), "W10 fresnel()")}


def probe_render(impl: Any, scene: dict, size: list[int], origins: np.ndarray | None = None,
                 directions: np.ndarray | None = None, **opts: Any) -> dict[str, np.ndarray]:
    """Trace a scene; camera rays come in trusted (from the reference) when the test gives them."""
    sc = _scene(scene)
    width, height = size
    ts = prepare(sc, impl, **opts)
    if origins is None or directions is None:
        origins, directions = _camera_rays(impl, sc.camera, width, height)
    colours = as_array(student_call(STAGE, impl, "W11", ts, origins, directions), (len(origins), 3), "W11 trace()")
    out = {"image": colours.reshape(height, width, 3)}
    out.update({k: np.array(v) for k, v in ts.counters.items()})
    return out


STAGE = Stage(
    name="whitted", number=2, title="Whitted ray tracing", handout="02-whitted", tasks=TASKS, render=render,
    probes={"camera_rays": probe_camera_rays, "intersect_sphere": probe_intersect_sphere,
            "intersect_triangle": probe_intersect_triangle, "build_bvh": probe_build_bvh,
            "primary_rays": probe_primary_rays, "closest_hit": probe_closest_hit, "local_shading": probe_local_shading,
            "shadow_transmission": probe_shadow_transmission, "reflect": probe_reflect, "refract": probe_refract,
            "fresnel": probe_fresnel, "render": probe_render},
)
