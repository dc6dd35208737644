"""Whole Whitted frames against the kernels their rays go through, and against Mitsuba 3's frame.

For each bundled Whitted scene at 320×240, 1 sample per pixel, on 1 and 2 threads, interleaved so that
the machine's load weighs on every column alike (best of the repetitions):

- frame: camera rays, the recursion (shading, shadow rays, reflection, refraction) and the pixels, on a
  scene already turned into arrays: what each frame of a demo costs;
- render: ``render_traced``, the scene turned into arrays as well (``cs451 render``'s work after warm-up);
- kernel: the closest-hit kernel alone on the frame's camera rays (the issue's yardstick), and on the
  frame's own rays (every closest-hit query and every shadow ray it casts, each through its kernel);
- Mitsuba 3 (``scalar_rgb``): the same scene's direct-lighting frame, same size and samples, as many
  shadow rays per point as the kit (``whitted_mitsuba``);
- where the frame's time goes: the same frame with no lights and no recursion (camera rays only: the
  frame's own overhead per ray, against the kernel on the same rays), then with the recursion but no
  lights, so that the rest is the lights' shadow rays and shading.
"""
from __future__ import annotations

import dataclasses
import math
import tempfile
from pathlib import Path
from types import ModuleType


from cs451.progress import Progress
from cs451.scene import load_scene
from cs451.stages import whitted as stage

from .bench_kernels import best_of, closest_queries, frame_rays, reference_parts, shadow_queries, threads

SIZE = (320, 240)
RAY_KINDS = ("camera", "shadow", "reflection", "transmission")
#: The light samples' arrays: emptied for the frame with no lights (where its time goes).
LIGHT_FIELDS = ("light_position", "light_diffuse", "light_specular", "light_attenuation", "light_normal")


def _mitsuba_frame(scene, ts, spp: int, folder: Path):
    """A function rendering the scene's Mitsuba frame on n threads; None without Mitsuba."""
    try:
        import drjit as dr
        import mitsuba as mi
    except ImportError:
        return None
    from .bench_mitsuba import VARIANT, mitsuba_dict
    mi.set_variant(VARIANT)
    mscene = mi.load_dict(mitsuba_dict(scene, ts, SIZE, spp, folder))
    default = dr.thread_count()

    def render(n: int) -> None:
        dr.set_thread_count(n)
        try:
            mi.render(mscene, spp=spp)
        finally:
            dr.set_thread_count(default)
    return render


def _timers(impl: ModuleType, ref, scene, ts, spp: int, mitsuba) -> tuple[dict, int, int]:
    """What is timed for one scene, by column (each takes the thread count), the number of camera rays and the
    number of rays the frame casts, recorded."""
    k = math.isqrt(spp)
    w, h = SIZE
    o, d = impl.camera_rays(scene.camera, w * k, h * k)   # the frame's camera rays, k × k a pixel
    closest, shadow = closest_queries(ref, ts), shadow_queries(ref, ts)
    own = frame_rays(ref, ts, o, d)

    def frame(_: int) -> None:
        origins, directions = impl.camera_rays(scene.camera, w * k, h * k)
        impl.trace(ts, origins, directions).reshape(h, k, w, k, 3).mean(axis=(1, 3))

    def own_rays(_: int) -> None:
        closest(*own["closest"])
        shadow(*own["shadow"])

    dark = dataclasses.replace(ts, counters=dict.fromkeys(ts.counters, 0), **{f: getattr(ts, f)[:0] for f in LIGHT_FIELDS})
    flat = dataclasses.replace(dark, max_depth=0)
    timers = {"frame": frame, "render": lambda _: stage.render_traced(scene, impl, SIZE, spp=spp),
              "kernel": lambda _: closest(o, d), "own_rays": own_rays,
              "camera_only": lambda _: impl.trace(flat, o, d), "no_lights": lambda _: impl.trace(dark, o, d)}
    if mitsuba is not None:
        timers["mitsuba"] = mitsuba
    return timers, len(o), len(own["closest"][0]) + len(own["shadow"][0])


def frames(impl: ModuleType, quick: bool, spp: int = 1) -> list[dict]:
    """One row per scene: seconds and rays per second of each column, on 1 and 2 threads, and the ratios."""
    ref = reference_parts(impl)
    repeats = 1 if quick else 7
    rows = []
    names = ("whitted", "cornell-spheres", "rippled-torus")
    bar = Progress("whole frames", len(names) * repeats)
    for name in names:
        scene = load_scene(name)
        _, counters = stage.render_traced(scene, impl, SIZE, spp=spp)   # warm up: compile, caches
        rays = sum(counters[k] for k in RAY_KINDS)
        ts = stage.prepare(scene, impl)
        with tempfile.TemporaryDirectory() as tmp:
            timers, camera_rays, own_rays = _timers(impl, ref, scene, ts, spp, _mitsuba_frame(scene, ts, spp, Path(tmp)))
            best: dict[str, float] = {}
            for _ in range(repeats):
                for n in (1, 2):
                    with threads(ref, n):
                        for label, fn in timers.items():
                            key = f"{label}_{n}t_s"
                            best[key] = min(best.get(key, math.inf), best_of(lambda: fn(n), 1))
                bar.advance(note=name)
        assert own_rays == rays, f"{name}: the frame cast {rays} rays, the recording found {own_rays}"
        row = {"scene": name, "width": SIZE[0], "height": SIZE[1], "spp": spp, "rays": rays, "camera_rays": camera_rays,
               **counters, **best}
        for n in (1, 2):
            row[f"frame_{n}t_Mrays"] = rays / best[f"frame_{n}t_s"] / 1e6
            row[f"kernel_{n}t_Mrays"] = camera_rays / best[f"kernel_{n}t_s"] / 1e6
            row[f"own_rays_{n}t_Mrays"] = rays / best[f"own_rays_{n}t_s"] / 1e6
            row[f"frame_over_kernel_{n}t"] = row[f"frame_{n}t_Mrays"] / row[f"kernel_{n}t_Mrays"]
            row[f"frame_over_own_rays_{n}t"] = row[f"frame_{n}t_Mrays"] / row[f"own_rays_{n}t_Mrays"]
            # the frame's ratio to the camera-ray kernel if its shading and bookkeeping cost nothing
            row[f"own_rays_over_kernel_{n}t"] = row[f"own_rays_{n}t_Mrays"] / row[f"kernel_{n}t_Mrays"]
            row[f"camera_only_over_kernel_{n}t"] = best[f"kernel_{n}t_s"] / best[f"camera_only_{n}t_s"]
            row[f"lights_share_{n}t"] = 1 - best[f"no_lights_{n}t_s"] / best[f"frame_{n}t_s"]
            if "mitsuba_1t_s" in best:
                row[f"frame_over_mitsuba_time_{n}t"] = best[f"frame_{n}t_s"] / best[f"mitsuba_{n}t_s"]
        rows.append(row)
    bar.close()
    return rows


def print_frames(rows: list[dict]) -> None:
    """Print :func:`frames`'s rows, one line per scene and thread count: frame and render times against the
    closest-hit kernel on the camera rays and on the frame's own rays, and Mitsuba's frame where it ran."""
    mitsuba = "mitsuba_1t_s" in rows[0]
    print("\nwhole frames, 320×240, 1 spp: frame (camera rays, trace, pixels; scene already as arrays) and render "
          "(with the scene to arrays), against the closest-hit kernel on the frame's camera rays and the kernels on "
          "the frame's own rays" + (", and Mitsuba 3's direct-lighting frame (scalar_rgb, as many shadow rays per "
                                    "light)" if mitsuba else " (Mitsuba not installed)"))
    print(f"{'scene':<16} {'thr':>3} {'frame ms':>8} {'render ms':>9} {'rays':>7} {'frame Mr/s':>10} {'camera-ray kernel':>17} "
          f"{'ratio':>5} {'own-ray kernels':>15} {'ratio':>5} {'fps':>5}" + (f" {'Mitsuba ms':>10} {'kit/Mitsuba':>11}" if mitsuba else ""))
    for r in rows:
        for n in (1, 2):
            line = (f"{r['scene']:<16} {n:>3} {r[f'frame_{n}t_s'] * 1e3:>8.1f} {r[f'render_{n}t_s'] * 1e3:>9.1f} "
                    f"{r['rays']:>7} {r[f'frame_{n}t_Mrays']:>10.2f} {r[f'kernel_{n}t_Mrays']:>17.2f} "
                    f"{r[f'frame_over_kernel_{n}t']:>5.2f} {r[f'own_rays_{n}t_Mrays']:>15.2f} "
                    f"{r[f'frame_over_own_rays_{n}t']:>5.2f} {1 / r[f'frame_{n}t_s']:>5.1f}")
            if mitsuba:
                line += f" {r[f'mitsuba_{n}t_s'] * 1e3:>10.1f} {r[f'frame_over_mitsuba_time_{n}t']:>11.2f}"
            print(line)


def print_time_split(rows: list[dict]) -> None:
    """Print where a frame's time goes, per scene and thread count: camera rays only, then with reflection and
    refraction, then the whole frame, the rest being the lights' share."""
    print("\nwhere a frame's time goes (320×240, 1 spp): camera rays only (no lights, no recursion; against the "
          "closest-hit kernel on the same rays), then with reflection and refraction, then the whole frame: the "
          "rest is the lights (shadow rays and shading)")
    print(f"{'scene':<16} {'thr':>3} {'camera only ms':>14} {'kernel/camera-only':>18} {'+ recursion ms':>14} "
          f"{'whole frame ms':>14} {'lights share':>12}")
    for r in rows:
        for n in (1, 2):
            print(f"{r['scene']:<16} {n:>3} {r[f'camera_only_{n}t_s'] * 1e3:>14.1f} "
                  f"{r[f'camera_only_over_kernel_{n}t']:>18.2f} {r[f'no_lights_{n}t_s'] * 1e3:>14.1f} "
                  f"{r[f'frame_{n}t_s'] * 1e3:>14.1f} {r[f'lights_share_{n}t']:>12.0%}")
