"""Stage 2, Whitted ray tracing: its interface, and the scaffolding that renders with a student's functions.

The scaffolding holds no solution: it turns a scene into arrays
(:mod:`cs451.tracescene`), asks the submission for a hierarchy when one can pay off,
then for camera rays and their colours, and averages supersamples into pixels.
Everything a student writes is called through :data:`STAGE`, and checked.
"""
from __future__ import annotations

import math
from typing import Any, Callable

import numpy as np

from ... import tracescene, schema
from ...progress import Progress
from ...errors import KitError
from ...scene import AreaLight, Camera, Mesh, Plane, PointLight, Polygon, Scene, Sphere, parse_scene
from ...schema import Context
from ..base import Out, Probes, Stage, Task, as_array, functions_replaced, part
from . import cost, trusted
from .options import MAX_DEPTH, WhittedOptions

RAYS = "len(origins)"
TASKS = (
    Task("W1", "camera_rays", "Camera rays", ("camera", "width", "height"),
         (Out("origins", ("width * height", 3)), Out("directions", ("width * height", 3)))),
    Task("W2", "intersect_sphere", "Ray-sphere intersection", ("origins", "directions", "center", "radius"),
         (Out("t0", (RAYS,), "f+inf"), Out("t1", (RAYS,), "f+inf"))),
    Task("W3", "intersect_triangle", "Watertight ray-triangle intersection", ("origins", "directions", "v0", "v1", "v2"),
         (Out("t", (RAYS,), "f+inf"),)),
    Task("W4", "build_bvh", "The bounding volume hierarchy", ("lo", "hi"), (Out("hierarchy", kind="dict"),)),
    Task("W5", "closest_hit", "Closest hit", ("scene", "origins", "directions"),
         (Out("t", (RAYS,), "f+inf"), Out("prim", (RAYS,), "i"), Out("normals", (RAYS, 3)))),
    Task("W6", "local_shading", "Local shading", ("normals", "to_eye", "to_light", "light_diffuse", "light_specular",
                                                  "diffuse", "specular", "shininess"), (Out("colour", ("len(normals)", 3)),)),
    Task("W7", "shadow_transmission", "Shadow rays", ("scene", "origins", "targets"), (Out("transmission", (RAYS, 3)),)),
    Task("W8", "reflect", "Reflection", ("directions", "normals"), (Out("r", ("len(directions)", 3)),)),
    Task("W9", "refract", "Refraction", ("directions", "normals", "eta"),
         (Out("directions", kind="any"), Out("tir", ("len(directions)",), "b"))),
    Task("W10", "fresnel", "Fresnel reflectance", ("cos_i", "eta"), (Out("f", ("len(cos_i)",)),)),
    Task("W11", "trace", "Recursive tracing and the cut-off", ("scene", "origins", "directions"),
         (Out("colour", (RAYS, 3)),)),
    Task("W12", "thin_lens", "Depth of field", ("camera", "directions", "aperture", "focus", "u"),
         (Out("origins", ("len(directions)", 3)), Out("directions", ("len(directions)", 3))), optional=True),
)


def estimate(scene: Scene, size: tuple[int, int] | None = None) -> list:
    """The memory and time a render needs, from the scene and its options alone (:func:`.cost.estimate`)."""
    return cost.estimate(scene, size, STAGE.options(scene))


# --- calling the student's functions, with checks on what they return --------

def _camera_rays(impl: Any, camera: Camera, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    return STAGE.call(impl, "W1", camera, width, height)


def _build_bvh(impl: Any, lo: np.ndarray, hi: np.ndarray) -> dict[str, np.ndarray]:
    return STAGE.call(impl, "W4", lo.copy(), hi.copy())


def prepare(scene: Scene, impl: Any, max_depth: int | None = None, min_weight: float | None = None,
            light_samples: int | None = None, hierarchy: bool | None = None,
            bvh: dict[str, np.ndarray] | None = None) -> tracescene.TraceScene:
    """The scene as arrays, with the submission's hierarchy where it can pay off (or where ``hierarchy``).

    ``bvh``: a trusted hierarchy (the reference's, from the grader) to use instead of the submission's W4.
    """
    opts = STAGE.options(scene, max_depth=max_depth, min_weight=min_weight, light_samples=light_samples)
    ts = tracescene.build(scene, opts.max_depth, opts.min_weight, opts.light_samples or None)
    use = hierarchy if hierarchy is not None else ts.n_bounded > tracescene.HIERARCHY_THRESHOLD
    if bvh is not None:
        ts.bvh = {k: np.asarray(bvh[k]) for k in tracescene.BVH_KEYS}
    elif use and ts.n_bounded > 0:
        lo, hi = ts.bounds()
        bvh = _build_bvh(impl, lo, hi)
        problems = tracescene.bvh_problems(bvh, lo, hi)
        if problems:
            raise KitError(f"W4 build_bvh(): {problems[0]}")
        ts.bvh = {k: np.asarray(bvh[k]) for k in tracescene.BVH_KEYS}
    return ts


def render_traced(scene: Scene, impl: Any, size: tuple[int, int] | None = None, spp: int | None = None,
                  **trace_options: Any) -> tuple[np.ndarray, dict[str, int]]:
    """Render with the submission's tracer; returns the linear image (h, w, 3) and the tracer's counters."""
    opts = STAGE.options(scene, spp=spp)
    width, height = size or (scene.image.width, scene.image.height)
    k = math.isqrt(opts.spp)
    rays = width * k * height * k
    parts = cost.bands(rays, cost.trace_seconds(scene, rays, opts))
    bar = Progress(f"ray tracing {width}x{height}", rays, unit="ray") if len(parts) > 1 else None
    try:
        ts = prepare(scene, impl, **trace_options)
        origins, directions = _camera_rays(impl, scene.camera, width * k, height * k)
        colours = []
        for part_ in parts:   # a long render in bands, so that its bar moves; a short one in one call
            colours.append(STAGE.call(impl, "W11", ts, origins[part_], directions[part_]))
            if bar:
                bar.advance(part_.stop - part_.start)
    finally:
        if bar:
            bar.close()
    image = np.concatenate(colours).reshape(height, k, width, k, 3).mean(axis=(1, 3))
    return image, dict(ts.counters)


def render(scene: Scene, impl: Any, size: tuple[int, int] | None = None, **opts: Any) -> np.ndarray:
    """Render a scene with a submission's tracer: a linear float image (h, w, 3)."""
    return render_traced(scene, impl, size, **opts)[0]


# --- probes: what the autograder's worker asks a submission for ------------------

PROBES = Probes()

def _scene(scene: dict) -> Scene:
    return parse_scene(scene, "<probe scene>")


def _rays(value: Any, what: str) -> np.ndarray:
    return np.asarray(value, dtype=np.float64).reshape(-1, 3)


@PROBES.register
def probe_camera_rays(impl: Any, camera: dict, width: int, height: int) -> dict[str, np.ndarray]:
    """W1 alone for a given camera: origins and directions ``(w·h, 3)``, checked for unit length and pyrender's
    pixel centres."""
    cam = schema.parse_record(Camera, camera, Context("<probe>", "camera"))
    origins, directions = _camera_rays(impl, cam, width, height)
    return {"origins": origins, "directions": directions}


@PROBES.register
def probe_thin_lens(impl: Any, camera: dict, directions: list, aperture: float, focus: float, u: list
                    ) -> dict[str, np.ndarray]:
    """W12 alone on given directions and lens samples ``u`` ``(n, 2)``: the new origins and directions ``(n, 3)``,
    compared with the truth's."""
    cam = schema.parse_record(Camera, camera, Context("<probe>", "camera"))
    d = _rays(directions, "directions")
    origins, out = STAGE.call(impl, "W12", cam, d, float(aperture), float(focus), as_array(u, (len(d), 2), "u"))
    return {"origins": origins, "directions": out}


@PROBES.register
def probe_intersect_sphere(impl: Any, origins: list, directions: list, center: list, radius: float) -> dict[str, np.ndarray]:
    """W2 alone on given rays and one sphere: both roots ``t0`` and ``t1`` ``(n,)``, inf on a miss."""
    o, d = _rays(origins, "origins"), _rays(directions, "directions")
    t0, t1 = STAGE.call(impl, "W2", o, d, np.asarray(center, float), float(radius))
    return {"t0": t0, "t1": t1}


@PROBES.register
def probe_intersect_triangle(impl: Any, origins: list, directions: list, v0: list, v1: list, v2: list) -> dict[str, np.ndarray]:
    """W3 alone: ray k against triangle k (a single triangle given is repeated for every ray); ``t`` ``(n,)``, inf
    on a miss, for the hit and the no-gap tests."""
    o, d = _rays(origins, "origins"), _rays(directions, "directions")
    tri = [np.broadcast_to(np.asarray(v, float), o.shape).copy() for v in (v0, v1, v2)]
    return {"t": STAGE.call(impl, "W3", o, d, *tri)}


@PROBES.register
def probe_build_bvh(impl: Any, lo: list | None = None, hi: list | None = None, scene: dict | None = None) -> dict[str, np.ndarray]:
    """The submission's hierarchy over boxes given as lists, or over a scene's primitives."""
    if scene is not None:
        ts = tracescene.build(_scene(scene))
        lo_a, hi_a = ts.bounds()
    else:
        lo_a, hi_a = np.asarray(lo, float).reshape(-1, 3), np.asarray(hi, float).reshape(-1, 3)
    bvh = _build_bvh(impl, lo_a, hi_a)
    out = {"box_lo": lo_a, "box_hi": hi_a}
    for k in tracescene.BVH_KEYS:
        if k not in bvh:
            raise KitError(f"W4 build_bvh() returned no {k!r} (keys needed: {', '.join(tracescene.BVH_KEYS)})")
        out[k] = np.asarray(bvh[k])
    return out


def _hits(impl: Any, ts: tracescene.TraceScene, o: np.ndarray, d: np.ndarray) -> dict[str, np.ndarray]:
    t, prim, normals = STAGE.call(impl, "W5", ts, o, d)
    return {"t": t, "prim": prim, "normals": normals}


@PROBES.register
def probe_primary_rays(impl: Any, scene: dict, size: list[int], **_: Any) -> dict[str, np.ndarray]:
    """Trusted camera rays for a test of later tasks (run on the reference only, through ``given``)."""
    origins, directions = _camera_rays(impl, _scene(scene).camera, size[0], size[1])
    return {"origins": origins, "directions": directions}


@PROBES.register
def probe_hit_parts(impl: Any, scene: dict, size: list[int] | None = None, hierarchy: bool | None = None,
                    rays: dict | None = None, **opts: Any) -> dict[str, np.ndarray]:
    """Trusted inputs of a W5 or W11 test (run on the reference only): camera rays, and the reference's
    hierarchy where the scene gets one."""
    ts = prepare(_scene(scene), impl, hierarchy=hierarchy, **opts)
    out = probe_primary_rays(impl, scene, size) if size is not None else {}
    if ts.bvh is not None:
        out.update({trusted.BVH_GIVEN[k]: np.asarray(v) for k, v in ts.bvh.items()})
    return out


@PROBES.register
def probe_trace_parts(impl: Any, scene: dict, size: list[int], **opts: Any) -> dict[str, np.ndarray]:
    """Trusted inputs of a W11 test (run on the reference only): those of :func:`probe_hit_parts`, and every
    query the reference's trace put to reflect, refract and fresnel on this scene, with its answers."""
    out = probe_hit_parts(impl, scene, size, **opts)
    log: dict[str, list] = {task: [] for task in trusted.OPTICS}
    with functions_replaced(STAGE, impl, {task: trusted.recorder(task, log) for task in trusted.OPTICS}):
        probe_render(impl, scene, size, **opts, **out)
    for task, (queries, results) in trusted.OPTICS.items():
        query_names, result_names = trusted.answer_names(task)
        for side, spec, names in ((0, queries, query_names), (1, results, result_names)):
            for k, ((_, columns), name) in enumerate(zip(spec, names)):
                parts = [np.asarray(call[side][k]).reshape(-1, columns) for call in log[task]]
                array = np.concatenate(parts) if parts else np.zeros((0, columns))
                out[name] = array if columns == 3 else array.reshape(-1)
    return out


@PROBES.register
def probe_closest_hit(impl: Any, scene: dict, size: list[int] | None = None, hierarchy: bool | None = None,
                      rays: dict | None = None, origins: np.ndarray | None = None,
                      directions: np.ndarray | None = None, **given: np.ndarray) -> dict[str, np.ndarray]:
    """Closest hits of the given rays (``rays`` in the parameters, or trusted camera rays as inputs), through
    the trusted hierarchy when the test gives one."""
    ts = prepare(_scene(scene), impl, hierarchy=hierarchy, bvh=trusted.given_bvh(given))
    if rays is not None:
        origins, directions = _rays(rays["origins"], "origins"), _rays(rays["directions"], "directions")
    assert origins is not None and directions is not None
    out = _hits(impl, ts, origins, directions)
    out["nodes_visited"] = np.array(ts.counters["nodes_visited"])
    out["tests"] = np.array(ts.counters["tests"])
    out["primitives"] = np.array(ts.n_bounded + ts.n_planes)
    return out


@PROBES.register
def probe_local_shading(impl: Any, normals: list, to_eye: list, to_light: list, light_diffuse: list,
                        light_specular: list, diffuse: list, specular: list, shininess: list) -> dict[str, np.ndarray]:
    """W6 alone on given vectors, lights and materials per point: the colour ``(n, 3)``, against the formula."""
    args = [np.asarray(a, dtype=np.float64) for a in (normals, to_eye, to_light, light_diffuse, light_specular,
                                                      diffuse, specular)]
    return {"colour": STAGE.call(impl, "W6", *args, np.asarray(shininess, dtype=np.float64))}


@PROBES.register
def probe_shadow_transmission(impl: Any, scene: dict, origins: list, targets: list) -> dict[str, np.ndarray]:
    """W7 alone in a given scene: the transmission ``(n, 3)`` from each origin to its target, and how many
    shadow rays were cast."""
    ts = prepare(_scene(scene), impl)
    o, x = _rays(origins, "origins"), _rays(targets, "targets")
    out = STAGE.call(impl, "W7", ts, o, x)
    return {"transmission": out, "shadow": np.array(ts.counters["shadow"])}


@PROBES.register
def probe_reflect(impl: Any, directions: list, normals: list) -> dict[str, np.ndarray]:
    """W8 alone: the reflected directions ``r`` ``(n, 3)`` of given directions and normals."""
    d, n = _rays(directions, "directions"), _rays(normals, "normals")
    return {"r": STAGE.call(impl, "W8", d, n)}


@PROBES.register
def probe_refract(impl: Any, directions: list, normals: list, eta: Any) -> dict[str, np.ndarray]:
    """W9 alone: the refracted directions ``t`` ``(n, 3)`` (their shape checked here, which the task leaves open)
    and the total internal reflection mask ``tir`` ``(n,)``."""
    d, n = _rays(directions, "directions"), _rays(normals, "normals")
    directions, tir = STAGE.call(impl, "W9", d, n, np.asarray(eta, dtype=np.float64))
    try:
        t = np.asarray(directions, dtype=np.float64)
    except (TypeError, ValueError):
        t = np.zeros(0)
    if t.shape != d.shape:
        raise KitError(f"W9 refract() directions has shape {t.shape}, expected {d.shape}")
    return {"t": as_array(t, (len(d), 3), "W9 refract() directions"), "tir": tir}


@PROBES.register
def probe_fresnel(impl: Any, cos_i: list, eta: Any) -> dict[str, np.ndarray]:
    """W10 alone: the reflectance ``f`` ``(n,)`` for given cosines and ``eta``, against Fresnel's equations."""
    c = np.asarray(cos_i, dtype=np.float64)
    return {"f": STAGE.call(impl, "W10", c, np.asarray(eta, dtype=np.float64))}


@PROBES.register
def probe_render(impl: Any, scene: dict, size: list[int], origins: np.ndarray | None = None,
                 directions: np.ndarray | None = None, **opts: Any) -> dict[str, np.ndarray]:
    """Trace a scene with the submission's W11. Trusted parts (:func:`probe_trace_parts`) come in as arrays when
    the test gives them: the camera rays, the reference's hierarchy, and answers for reflect, refract and fresnel."""
    given = {k: opts.pop(k) for k in list(opts) if k.startswith(("bvh_", "answer_"))}
    sc = _scene(scene)
    width, height = size
    ts = prepare(sc, impl, bvh=trusted.given_bvh(given), **opts)
    if origins is None or directions is None:
        origins, directions = _camera_rays(impl, sc.camera, width, height)
    answers = trusted.answers_from(given)
    with functions_replaced(STAGE, impl, {task: a.wrap for task, a in answers.items()}):
        colours = STAGE.call(impl, "W11", ts, origins, directions)
    out = {"image": colours.reshape(height, width, 3)}
    out.update({k: np.array(v) for k, v in ts.counters.items()})
    return out


def run_demo(module: Any, output: Any, window: bool, frames: int | None, scene: str = "whitted",
         size: tuple[int, int] | None = None, screenshot: Any = None) -> list:
    """The tracer refining in a window, its switches and a pixel's ray tree (:mod:`cs451.stages.whitted.demo`)."""
    run = part(__name__, "demo").demo
    return run(module, output, window, frames, scene=scene, size=size, screenshot=screenshot)


#: Camera rays at this size make batches large enough for an implementation's compiled path (the reference's
#: speed layer takes batches of 10,000 rays and more: accel/__init__.py).
WARM_SIZE = (160, 120)


def warm(impl: Any) -> list[tuple[str, Callable[[], Any]]]:
    """What a first render or demo compiles in the reference (numba kernels; a numpy submission compiles
    nothing): a frame without a hierarchy and one with it, then closest hits (W5) and shadow rays (W7) on
    their own, which the demo's ray trees and switches cast bounce by bounce."""
    from ...scene import load_scene

    def frame(name: str) -> None:
        render(load_scene(name), impl, size=WARM_SIZE)

    def queries() -> None:
        scene = load_scene("rippled-torus")
        ts = prepare(scene, impl)
        origins, directions = _camera_rays(impl, scene.camera, *WARM_SIZE)
        STAGE.call(impl, "W5", ts, origins, directions)
        STAGE.call(impl, "W7", ts, origins, origins + directions)

    return [("a frame of spheres", lambda: frame("whitted")),
            ("a frame of a mesh, with its hierarchy", lambda: frame("rippled-torus")),
            ("closest hits and shadow rays, as the demo casts them", queries)]


#: the demo's keys
DEMO_KEYS = (("s", "shadows"), ("r", "reflection"), ("t", "refraction"), ("c", "the β cut-off"), ("+ -", "depth"),
             ("click", "a pixel's ray tree"), ("x", "clears it"), ("q", "quits"))


STAGE = Stage(
    name="whitted", number=2, title="Whitted ray tracing", handout="02-whitted", tasks=TASKS, render=render,
    probes=PROBES, demo=run_demo, options_type=WhittedOptions, draws=(Sphere, Plane, Polygon, Mesh, PointLight, AreaLight),
    demo_keys=DEMO_KEYS,
    estimate=estimate, warm=warm, accelerator=f"{__name__}.accel",
)
