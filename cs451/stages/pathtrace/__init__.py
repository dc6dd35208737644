"""Stage 5, Monte Carlo path tracing: its interface, and the scaffolding that renders with a student's functions.

Path tracing is the direct answer to diffuse interreflection that the course notes set beside radiosity (§2.2:
distributed ray tracing, costly but general): each pixel's radiance is the mean of random paths. On the diffuse
scenes of stage 4 it converges to the same light as radiosity, which is how the autograder judges it (a
statistical test against stage 4's solution of the Cornell box, not a fixed image). The scaffolding holds no
solution: it turns a scene into arrays (:mod:`.paths`), asks the submission for camera rays through jittered
points of each pixel and for their radiance, and averages the samples. Everything a student writes is called
through :data:`STAGE`, and checked.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from ... import schema
from ...errors import KitError
from ...progress import Progress
from ...scene import AreaLight, Camera, Polygon, Scene, parse_scene
from ...schema import field
from ..base import Out, Probes, Stage, Task, as_array, part
from . import paths, tolerances

N = "len(normals)"
TASKS = (
    Task("P1", "cosine_sample", "Cosine-weighted hemisphere sampling", ("normals", "u"), (Out("directions", (N, 3)),)),
    Task("P2", "direct_light", "Next-event estimation", ("scene", "points", "normals", "albedo", "u"),
         (Out("radiance", ("len(points)", 3)),)),
    Task("P3", "roulette", "Russian roulette", ("weights", "u"),
         (Out("alive", ("len(weights)",), "b"), Out("weights", ("len(weights)", 3)))),
    Task("P4", "radiance", "The path tracer", ("scene", "origins", "directions", "rng"),
         (Out("radiance", ("len(origins)", 3)),)),
    Task("P5", "stratified_direct_light", "Stratified light samples", ("scene", "points", "normals", "albedo", "jitter"),
         (Out("radiance", ("len(points)", 3)),), optional=True),
)


@dataclass(frozen=True)
class PathOptions:
    spp: int = field("Paths per pixel, each through a random point of the pixel.", 16, schema.positive)
    max_depth: int = field("Most bounces of a path (Russian roulette ends nearly all long before).", 32,
                           schema.at_least(1))
    roulette_depth: int = field("The bounce from which Russian roulette may end a path.", 3, schema.at_least(1))
    seed: int = field("The random numbers' seed: the same seed, the same image.", 0, schema.non_negative)


#: bytes per path of a pass of the reference (rays, weights, hits, the brute-force caster's chunk), with margin
PATH_BYTES = 2048


#: paths per second of the reference: 54 thousand measured on a 2-core machine (the Cornell box, 64 × 64, 16 per
#: pixel); halved for a slower laptop
PATHS_PER_S = 25e3


def estimate(scene: Scene, size: tuple[int, int] | None = None) -> list:
    """Memory for one pass of paths; time for every pass."""
    from ...limits import Cost
    w, h = size or (scene.image.width, scene.image.height)
    spp = STAGE.options(scene).spp
    return [Cost("image", PATH_BYTES * w * h, f"{w * h:,} paths at a time ({w}x{h}, one pass per sample)"),
            Cost("options.pathtrace.spp", 0.0, f"{w * h * spp:,} paths ({w}x{h}, {spp:,} per pixel)",
                 seconds=w * h * spp / PATHS_PER_S)]


def prepare(scene: Scene, max_depth: int | None = None, roulette_depth: int | None = None) -> paths.PathScene:
    """The scene as the path tracer's arrays (:class:`paths.PathScene`), with ``options.pathtrace``'s depths unless
    given here (validated either way)."""
    opts = STAGE.options(scene, max_depth=max_depth, roulette_depth=roulette_depth)
    return paths.build(scene, opts.max_depth, opts.roulette_depth)


def pixel_rays(impl: Any, camera: Camera, width: int, height: int, jitter: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The submission's camera rays (given in its starter, ``geometry.camera_rays``), checked."""
    fn = getattr(impl, "camera_rays", None)
    if fn is None:
        raise KitError("camera_rays() is missing from the submission (it is given in the starter's geometry.py)")
    o, d = fn(camera, width, height, jitter)
    n = width * height
    return as_array(o, (n, 3), "camera_rays() origins"), as_array(d, (n, 3), "camera_rays() directions")


def render_traced(scene: Scene, impl: Any, size: tuple[int, int] | None = None, spp: int | None = None,
                  seed: int | None = None, on_pass: Callable[[int, np.ndarray], None] | None = None,
                  **trace_options: Any) -> tuple[np.ndarray, dict[str, int]]:
    """The mean of ``spp`` passes, each one path per pixel through a random point of it; returns the linear image
    (h, w, 3) and the tracer's counters. ``on_pass(k, mean)`` after each pass (the demo's progressive picture)."""
    opts = STAGE.options(scene, spp=spp, seed=seed)
    width, height = size or (scene.image.width, scene.image.height)
    ps = prepare(scene, **trace_options)
    rng = np.random.default_rng(opts.seed)
    total = np.zeros((width * height, 3))
    bar = Progress(f"path tracing {width}x{height}", opts.spp, unit="spp")
    try:
        for k in range(opts.spp):
            o, d = pixel_rays(impl, scene.camera, width, height, rng.random((width * height, 2)))
            total += STAGE.call(impl, "P4", ps, o, d, rng)
            bar.advance()
            if on_pass is not None:
                on_pass(k + 1, (total / (k + 1)).reshape(height, width, 3))
    finally:
        bar.close()
    return (total / opts.spp).reshape(height, width, 3), dict(ps.counters)


def render(scene: Scene, impl: Any, size: tuple[int, int] | None = None, **opts: Any) -> np.ndarray:
    """Render a scene with a submission's path tracer: a linear float image (h, w, 3) of radiance."""
    return render_traced(scene, impl, size, **opts)[0]


# --- probes: what the autograder's worker asks a submission for -----------------------

PROBES = Probes()


def _scene(scene: dict) -> paths.PathScene:
    return paths.build(parse_scene(scene, "<test scene>"))


def _array(value: Any, shape: tuple[int | None, ...], what: str) -> np.ndarray:
    return as_array(value, shape, what)


@PROBES.register
def probe_cosine_sample(impl: Any, normals: list, samples: int = 1, seed: int = 0) -> dict[str, np.ndarray]:
    """Each normal ``samples`` times (:func:`paths.repeated`), with uniform numbers from ``seed``; asked twice."""
    n = paths.repeated(_array(normals, (None, 3), "normals"), samples)
    u = paths.uniforms(seed, len(n), 2)
    first = STAGE.call(impl, "P1", n, u)
    again = STAGE.call(impl, "P1", n.copy(), u.copy())
    return {"directions": first, "repeatable": np.array(np.array_equal(first, again))}


@PROBES.register
def probe_direct_light(impl: Any, scene: dict, points: list, normals: list, albedo: list, samples: int = 1,
                       seed: int = 0) -> dict[str, np.ndarray]:
    """P2 at each point ``samples`` times, with light samples from ``seed``; the shadow rays it cast."""
    ps = _scene(scene)
    x = paths.repeated(_array(points, (None, 3), "points"), samples)
    n = paths.repeated(_array(normals, (None, 3), "normals"), samples)
    rho = paths.repeated(_array(albedo, (None, 3), "albedo"), samples)
    out = STAGE.call(impl, "P2", ps, x, n, rho, paths.uniforms(seed, len(x), 2))
    return {"radiance": out, "shadow": np.array(ps.counters["shadow"])}


@PROBES.register
def probe_stratified(impl: Any, scene: dict, points: list, normals: list, albedo: list, strata: int, seed: int = 0
                     ) -> dict[str, np.ndarray]:
    """P5 at each point over ``strata`` × ``strata`` cells, jittered from ``seed``; the shadow rays it cast."""
    ps = _scene(scene)
    x = _array(points, (None, 3), "points")
    jitter = paths.uniforms(seed, len(x) * strata * strata, 2).reshape(len(x), strata, strata, 2)
    out = STAGE.call(impl, "P5", ps, x, _array(normals, (len(x), 3), "normals"), _array(albedo, (len(x), 3), "albedo"),
                     jitter)
    return {"radiance": out, "shadow": np.array(ps.counters["shadow"])}


@PROBES.register
def probe_roulette(impl: Any, weights: list, u: list) -> dict[str, np.ndarray]:
    """P3 on given weights ``(n, 3)`` and uniform numbers ``(n,)``: which paths go on ``(n,) bool`` and their new
    weights ``(n, 3)``, checked exactly against the rule."""
    beta = _array(weights, (None, 3), "weights")
    alive, out = STAGE.call(impl, "P3", beta, _array(u, (len(beta),), "u"))
    return {"alive": alive, "weights": out}


@PROBES.register
def probe_rays(impl: Any, scene: dict, origins: list, directions: list, seed: int = 0,
               one_at_a_time: bool = False) -> dict[str, np.ndarray]:
    """P4 on given rays (one path each), all in one call or (``one_at_a_time``) one call per ray."""
    ps = _scene(scene)
    o, d = _array(origins, (None, 3), "origins"), _array(directions, (None, 3), "directions")
    rng = np.random.default_rng(seed)
    if one_at_a_time:
        out = np.concatenate([STAGE.call(impl, "P4", ps, o[k:k + 1], d[k:k + 1], rng) for k in range(len(o))])
    else:
        out = STAGE.call(impl, "P4", ps, o, d, rng)
    return {"radiance": out, **{k: np.array(v) for k, v in ps.counters.items()}}


@PROBES.register
def probe_polygon_radiance(impl: Any, scene: dict, polygons: list[int], samples: int, seed: int,
                           **trace_options: Any) -> dict[str, np.ndarray]:
    """The submission's radiance (P4) leaving uniform random points of some polygons (numbered as stage 4 numbers
    the scene's surfaces): rays aimed at each point from just in front of it. Per polygon, the mean and its standard
    error, the statistics the autograder's test compares with radiosity."""
    sc = parse_scene(scene, "<test scene>")
    ps = prepare(sc, **trace_options)
    rng = np.random.default_rng(seed)
    points, normals = paths.points_on_polygons(sc, polygons, samples, rng)
    start = points + normals * (tolerances.AIM * ps.size)
    colour = STAGE.call(impl, "P4", ps, start, -normals, rng).reshape(len(polygons), samples, 3)
    return {"mean": colour.mean(axis=1), "error": colour.std(axis=1, ddof=1) / np.sqrt(samples),
            "bounce": np.array(ps.counters["bounce"])}


@PROBES.register
def probe_render(impl: Any, scene: dict, size: list[int], spp: int, seed: int = 0) -> dict[str, np.ndarray]:
    """The whole renderer on the submission (its camera rays and P4): the mean image ``(h, w, 3)`` of ``spp`` passes
    at ``size``, and the tracer's counters."""
    image, counters = render_traced(parse_scene(scene, "<test scene>"), impl, (int(size[0]), int(size[1])), spp, seed)
    return {"image": image, **{k: np.array(v) for k, v in counters.items()}}


def run_demo(module: Any, output: Any, window: bool, frames: int | None, scene: str = "cornell-box",
             size: tuple[int, int] | None = None, screenshot: Any = None) -> list:
    """The picture refining pass by pass, with its sample count and the paths' mean length (:mod:`.demo`)."""
    return part(__name__, "demo").demo(module, output, window, frames, scene=scene, size=size, screenshot=screenshot)


#: the demo's keys
DEMO_KEYS = (("space", "pauses"), ("r", "restarts"), ("d", "direct light only"), ("q", "quits"))

STAGE = Stage(
    name="pathtrace", number=5, title="Monte Carlo path tracing", handout="05-pathtrace", tasks=TASKS, render=render,
    probes=PROBES, demo=run_demo, demo_keys=DEMO_KEYS, options_type=PathOptions, draws=(Polygon, AreaLight),
    estimate=estimate, scene_check=paths.check_lighting,
)
