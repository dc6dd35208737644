"""Stage 2, Whitted ray tracing: its interface, and the scaffolding that renders with a student's functions.

The scaffolding holds no solution: it turns a scene into arrays
(:mod:`cs451.raytrace`), asks the submission for a hierarchy when one can pay off,
then for camera rays and their colours, and averages supersamples into pixels.
Everything a student writes is called through :data:`STAGE`, and checked.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from .. import raytrace, schema
from ..errors import KitError
from ..scene import Camera, Scene, parse_scene
from ..schema import Context, field
from .base import Stage, Task, as_array, functions_replaced, student_call

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
            light_samples: int | None = None, hierarchy: bool | None = None,
            bvh: dict[str, np.ndarray] | None = None) -> raytrace.TraceScene:
    """The scene as arrays, with the submission's hierarchy where it can pay off (or where ``hierarchy``).

    ``bvh``: a trusted hierarchy (the reference's, from the grader) to use instead of the submission's W4.
    """
    opts = options(scene, max_depth=max_depth, min_weight=min_weight, light_samples=light_samples)
    ts = raytrace.build(scene, opts.max_depth, opts.min_weight, opts.light_samples or None)
    use = hierarchy if hierarchy is not None else ts.n_bounded > raytrace.HIERARCHY_THRESHOLD
    if bvh is not None:
        ts.bvh = {k: np.asarray(bvh[k]) for k in raytrace.BVH_KEYS}
    elif use and ts.n_bounded > 0:
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


# --- trusted parts for the tests of later tasks ---------------------------------------
#
# A test of W5 or W11 should judge that task, not the earlier ones it calls. The grader runs the
# reference first (through ``given``) and hands the submission arrays: the camera rays, the
# reference's hierarchy, and the reference's answers to reflect, refract and fresnel for the
# queries its own trace made. While the submission's trace runs, its W8 to W10 are answered from
# those arrays wherever it asks what the reference asked (a correct trace asks exactly that), and
# left to the submission's own functions elsewhere: a bug in W8 then costs W8's points only.

BVH_GIVEN = {k: f"bvh_{k}" for k in raytrace.BVH_KEYS}
#: Per optics task: the per-ray arrays of a query and of its answer (given as answer_<function>_<name>),
#: and whether each holds a vector (3 columns) per ray.
OPTICS = {"W8": ((("d", 3), ("n", 3)), (("r", 3),)), "W9": ((("d", 3), ("n", 3), ("eta", 1)), (("t", 3), ("tir", 1))),
          "W10": ((("cos", 1), ("eta", 1)), (("f", 1),))}
#: Queries match when they agree to this, after rounding: far above the rounding of a correct trace's rays.
ANSWER_DIGITS = 1e-9


def _given_bvh(given: dict[str, np.ndarray]) -> dict[str, np.ndarray] | None:
    if not all(name in given for name in BVH_GIVEN.values()):
        return None
    return {k: given[name] for k, name in BVH_GIVEN.items()}


def _query(task: str, args: tuple) -> tuple[np.ndarray, list[np.ndarray]]:
    """One row per ray of what an optics call asks, as floats (the key), and the arguments broadcast per ray.

    Raises ValueError for a call that is not a batch of rays as the interface has it ((n,) or (n, 3) arrays).
    """
    if task == "W10":
        cos = np.asarray(args[0], dtype=np.float64)
        if cos.ndim != 1:
            raise ValueError("not a batch")
        eta = np.broadcast_to(np.asarray(args[1], dtype=np.float64), cos.shape)
        return np.column_stack([cos, eta]), [cos, eta]
    d = np.asarray(args[0], dtype=np.float64)
    n = np.asarray(args[1], dtype=np.float64)
    if d.ndim != 2 or d.shape[1:] != (3,) or n.shape != d.shape:
        raise ValueError("not a batch")
    if task == "W8":  # the mirror direction is the same about -n: key the normal facing the ray
        facing = np.where((np.einsum("ij,ij->i", d, n) > 0)[:, None], -n, n)
        return np.column_stack([d, facing]), [d, n]
    eta = np.broadcast_to(np.asarray(args[2], dtype=np.float64), (len(d),))
    return np.column_stack([d, n, eta]), [d, n, eta]


def _keys(rows: np.ndarray) -> list[bytes]:
    return [r.tobytes() for r in np.round(rows / ANSWER_DIGITS).astype(np.int64)]


class _Answers:
    """The reference's answers to one optics task, looked up by query."""

    def __init__(self, task: str, queries: list[np.ndarray], answers: list[np.ndarray]):
        self.task, self.answers = task, answers
        self.index = {k: i for i, k in enumerate(_keys(_query(task, tuple(queries))[0]))}

    def wrap(self, own: Any) -> Any:
        def answered(*args: Any) -> Any:
            try:
                query, per_ray = _query(self.task, args)
            except (TypeError, ValueError, IndexError):
                return own(*args)               # not a batch of rays: the submission's own answer
            found = np.array([self.index.get(k, -1) for k in _keys(query)], dtype=np.int64)
            missing = found < 0
            parts = [a[found[~missing]] for a in self.answers]
            if missing.any():                   # rays the reference never cast: the submission's own function
                mine = own(*[a[missing] for a in per_ray])
                mine = mine if isinstance(mine, (tuple, list)) else (mine,)
                parts = [_merge(p, np.asarray(m), missing) for p, m in zip(parts, mine)]
            return tuple(parts) if len(parts) > 1 else parts[0]
        return answered


def _merge(found: np.ndarray, mine: np.ndarray, missing: np.ndarray) -> np.ndarray:
    out = np.zeros((len(missing),) + found.shape[1:], dtype=np.result_type(found, mine))
    out[~missing], out[missing] = found, mine
    return out


def _answer_names(task: str) -> tuple[list[str], list[str]]:
    name = STAGE.task(task).function
    queries, results = OPTICS[task]
    return [f"answer_{name}_{q}" for q, _ in queries], [f"answer_{name}_{r}" for r, _ in results]


def _answers_from(given: dict[str, np.ndarray]) -> dict[str, _Answers]:
    out = {}
    for task in OPTICS:
        queries, results = _answer_names(task)
        if all(k in given for k in queries + results):
            out[task] = _Answers(task, [given[k] for k in queries], [np.asarray(given[k]) for k in results])
    return out


def _recorder(task: str, log: dict[str, list]) -> Callable[[Any], Any]:
    def wrap(own: Any) -> Any:
        def recording(*args: Any) -> Any:
            out = own(*args)
            _, per_ray = _query(task, args)
            log[task].append((per_ray, out if isinstance(out, (tuple, list)) else (out,)))
            return out
        return recording
    return wrap


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


def probe_hit_parts(impl: Any, scene: dict, size: list[int] | None = None, hierarchy: bool | None = None,
                    rays: dict | None = None, **opts: Any) -> dict[str, np.ndarray]:
    """Trusted inputs of a W5 or W11 test (run on the reference only): camera rays, and the reference's
    hierarchy where the scene gets one."""
    ts = prepare(_scene(scene), impl, hierarchy=hierarchy, **opts)
    out = probe_primary_rays(impl, scene, size) if size is not None else {}
    if ts.bvh is not None:
        out.update({BVH_GIVEN[k]: np.asarray(v) for k, v in ts.bvh.items()})
    return out


def probe_trace_parts(impl: Any, scene: dict, size: list[int], **opts: Any) -> dict[str, np.ndarray]:
    """Trusted inputs of a W11 test (run on the reference only): those of :func:`probe_hit_parts`, and every
    query the reference's trace put to reflect, refract and fresnel on this scene, with its answers."""
    out = probe_hit_parts(impl, scene, size, **opts)
    log: dict[str, list] = {task: [] for task in OPTICS}
    with functions_replaced(STAGE, impl, {task: _recorder(task, log) for task in OPTICS}):
        probe_render(impl, scene, size, **opts, **out)
    for task, (queries, results) in OPTICS.items():
        query_names, result_names = _answer_names(task)
        for side, spec, names in ((0, queries, query_names), (1, results, result_names)):
            for k, ((_, columns), name) in enumerate(zip(spec, names)):
                parts = [np.asarray(call[side][k]).reshape(-1, columns) for call in log[task]]
                array = np.concatenate(parts) if parts else np.zeros((0, columns))
                out[name] = array if columns == 3 else array.reshape(-1)
    return out


def probe_closest_hit(impl: Any, scene: dict, size: list[int] | None = None, hierarchy: bool | None = None,
                      rays: dict | None = None, origins: np.ndarray | None = None,
                      directions: np.ndarray | None = None, **given: np.ndarray) -> dict[str, np.ndarray]:
    """Closest hits of the given rays (``rays`` in the parameters, or trusted camera rays as inputs), through
    the trusted hierarchy when the test gives one."""
    ts = prepare(_scene(scene), impl, hierarchy=hierarchy, bvh=_given_bvh(given))
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
    """Trace a scene with the submission's W11. Trusted parts (:func:`probe_trace_parts`) come in as arrays when
    the test gives them: the camera rays, the reference's hierarchy, and answers for reflect, refract and fresnel."""
    given = {k: opts.pop(k) for k in list(opts) if k.startswith(("bvh_", "answer_"))}
    sc = _scene(scene)
    width, height = size
    ts = prepare(sc, impl, bvh=_given_bvh(given), **opts)
    if origins is None or directions is None:
        origins, directions = _camera_rays(impl, sc.camera, width, height)
    answers = _answers_from(given)
    with functions_replaced(STAGE, impl, {task: a.wrap for task, a in answers.items()}):
        colours = as_array(student_call(STAGE, impl, "W11", ts, origins, directions), (len(origins), 3), "W11 trace()")
    out = {"image": colours.reshape(height, width, 3)}
    out.update({k: np.array(v) for k, v in ts.counters.items()})
    return out


STAGE = Stage(
    name="whitted", number=2, title="Whitted ray tracing", handout="02-whitted", tasks=TASKS, render=render,
    probes={"camera_rays": probe_camera_rays, "intersect_sphere": probe_intersect_sphere,
            "intersect_triangle": probe_intersect_triangle, "build_bvh": probe_build_bvh,
            "primary_rays": probe_primary_rays, "hit_parts": probe_hit_parts, "trace_parts": probe_trace_parts,
            "closest_hit": probe_closest_hit, "local_shading": probe_local_shading,
            "shadow_transmission": probe_shadow_transmission, "reflect": probe_reflect, "refract": probe_refract,
            "fresnel": probe_fresnel, "render": probe_render},
)
