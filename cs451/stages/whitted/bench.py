"""``cs451 bench whitted``: run time against error, closest-hit rays per second and hierarchy builds against
Embree, and whole frames against their kernels and against Mitsuba 3.

Part 1, for each bundled Whitted scene: frame time and error over image size, samples per
pixel and the β cut-off, against a converged render of the same scene (16 samples per pixel,
cut-off 1e-4, 12 bounces, 64 shadow rays per area light). Error is the RMS difference in
linear colour clipped to [0, 1] (what a display shows), after box-filtering the converged image
to the size rendered.

Part 2: closest-hit queries on the 55,296-triangle rippled torus (the mesh alone), the
reference's compiled kernels against Embree 4 through embreex, in the same run, on the same
rays (primary rays and random rays from inside the torus's bounding box). Embree's ``run``
is one thread; two threads each take half the rays. Skipped with a note when embreex is absent.
Each kind is timed again on only the rays that hit a triangle: a ray that misses the torus's box costs the
kit a few nanoseconds and Embree's Python wrapper more, so the mix of the two moves the whole-batch ratio.
The hierarchy: the reference's binned-SAH build and eight-wide layout (warm, without the cache) against
Embree's scene build, and what the cache hands back for the same boxes.

Part 3 (``whitted_frames``): whole frames at 320×240 against the kernels their rays go through and
against Mitsuba 3's frame of the same scene. Part 4 (``whitted_demo``): how long the demo takes to refine
the same frames. A summary table prints every ratio measured in this run.
"""
from __future__ import annotations

import json
import os
import platform
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from cs451.impl import load_impl, resolve_impl
from cs451.progress import Progress
from cs451.tracescene import BVH_KEYS
from cs451.scene import BUNDLED_DIR, load_scene, parse_scene
from cs451.stages import whitted as stage

from .bench_demo import demo_speed, print_demo_speed
from .bench_frames import frames, print_frames, print_time_split
from .bench_kernels import best_of, closest_queries, reference_parts
from .bench_kernels import threads as threads_of

#: The top-level keys of whitted.json that the docs and decks read (tests/test_benches.py checks a quick run writes them).
KEYS = ("time_against_error", "closest_hit", "frames", "demo", "converged", "summary")

SCENES = ("whitted", "cornell-spheres", "rippled-torus")
CONVERGED = {"spp": 16, "min_weight": 1e-4, "max_depth": 12, "light_samples": 64}
DEFAULT = {"spp": 1, "min_weight": 0.01}


def _render(impl, scene, size, **opts):
    start = time.perf_counter()
    image, counters = stage.render_traced(scene, impl, size, **opts)
    return image, counters, time.perf_counter() - start


def _downsample(image: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    h, w = image.shape[:2]
    fy, fx = h // size[1], w // size[0]
    return image.reshape(size[1], fy, size[0], fx, 3).mean(axis=(1, 3))


def time_against_error(impl, quick: bool) -> list[dict]:
    """Part 1: each bundled scene rendered over image size, samples per pixel, the cut-off (and shadow rays for
    an area light), each frame's seconds, rays and RMS error against the converged render."""
    rows = []
    top = (160, 120) if quick else (320, 240)
    sizes = [(top[0] // 4, top[1] // 4), (top[0] // 2, top[1] // 2), top]
    bar = Progress("time against error", len(SCENES))
    for name in SCENES:
        bar.advance(0, note=name)
        scene = load_scene(name)
        area = any(getattr(l, "type_name", "") == "area" for l in scene.lights)
        _render(impl, scene, (16, 12))  # compile and warm up
        converged, _, conv_s = _render(impl, scene, top, **CONVERGED)
        variants = [("size", f"{w}×{h}", (w, h), DEFAULT) for w, h in sizes]
        variants += [("spp", str(s), top, {**DEFAULT, "spp": s}) for s in ((1, 4) if quick else (1, 4, 9))]
        variants += [("cut-off", f"{c:g}", top, {**DEFAULT, "min_weight": c}) for c in (0.5, 0.1, 0.01, 0.001)]
        if area:
            variants += [("shadow rays", str(k), top, {**DEFAULT, "light_samples": k}) for k in (1, 4, 16)]
        for sweep, value, size, opts in variants:
            image, counters, seconds = _render(impl, scene, size, **opts)
            # on displayable values (clipped to [0, 1]): a visible emitter must not swamp the error
            err = np.sqrt(np.mean((np.clip(image, 0, 1) - np.clip(_downsample(converged, size), 0, 1)) ** 2))
            rays = sum(counters[k] for k in ("camera", "shadow", "reflection", "transmission"))
            rows.append({"scene": name, "sweep": sweep, "value": value, "width": size[0], "height": size[1],
                         "seconds": seconds, "rms_error": float(err), "rays": rays, **counters,
                         "converged_seconds": conv_s})
        bar.advance(note=name)
    bar.close()
    return rows


def _torus_only():
    data = json.loads((BUNDLED_DIR / "rippled-torus.json").read_text())    # the bundled scene, wherever the kit is
    data["objects"] = [o for o in data["objects"] if o["type"] == "mesh"]
    return parse_scene(data, "rippled-torus (mesh only)")


def _query_rays(scene, n_side: int, seed: int = 7) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    from cs451 import tracescene
    ts = tracescene.build(scene)
    lo, hi = ts.bounds()
    box_lo, box_hi = lo.min(axis=0), hi.max(axis=0)
    cam = scene.camera
    primary = stage._camera_rays(load_impl(resolve_impl("reference", "whitted"), "whitted"), cam, n_side * 4 // 3, n_side)
    rng = np.random.default_rng(seed)
    n = len(primary[0])
    o = rng.uniform(box_lo, box_hi, (n, 3))
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return {"primary": primary, "random": (o, d)}


def _embree(ts):
    """An Embree scene of the triangles (None without embreex) and its build time (scene, geometry, commit)."""
    try:
        from embreex import rtcore_scene as rtcs
        from embreex.mesh_construction import TriangleMesh
    except ImportError:
        return None, None
    tri = np.stack([ts.tri_v0, ts.tri_v1, ts.tri_v2], axis=1).astype(np.float32)

    def make():
        escene = rtcs.EmbreeScene()
        TriangleMesh(escene, tri)
        escene.run(np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32))  # commit (builds the BVH)
        return escene
    start = time.perf_counter()
    escene = make()
    return escene, min(time.perf_counter() - start, best_of(make, 2))


def hierarchy_build(impl, ts, escene_build_s: float | None, quick: bool) -> dict:
    """The reference's build (binned SAH, numba) and eight-wide layout, warm and uncached, beside Embree's."""
    ref = reference_parts(impl)
    lo, hi = ts.bounds()
    leaf = ref.queries.LEAF_SIZE
    tri = np.ascontiguousarray(np.concatenate([ts.tri_v0, ts.tri_v1, ts.tri_v2], axis=1))
    start = time.perf_counter()
    bvh = dict(zip(BVH_KEYS, ref.hierarchy.build(lo, hi, leaf)))
    first = time.perf_counter() - start                    # includes loading (or compiling) the kernel
    ref.hierarchy.eight_wide(bvh, ts.n_spheres, tri)
    repeats = 2 if quick else 5
    build_s = best_of(lambda: ref.hierarchy.build(lo, hi, leaf), repeats)
    layout_s = best_of(lambda: ref.hierarchy.eight_wide(bvh, ts.n_spheres, tri), repeats)
    build = lambda: stage.STAGE.call(impl, "W4", lo, hi)   # through the reference's hook: the cached build
    build()
    cached_s = best_of(build, repeats)
    out = {"build_s": build_s, "layout_s": layout_s, "first_build_s": first, "cached_s": cached_s,
           "nodes": int(len(bvh["child"])), "cache": ref.hierarchy.cache_counts()}
    if escene_build_s is not None:
        out["embree_build_s"] = escene_build_s
        out["ratio"] = (build_s + layout_s) / escene_build_s
    return out


def rays_per_second(impl, quick: bool) -> dict:
    """Closest-hit queries on the torus alone: the reference's kernel against Embree, same rays, same run."""
    scene = _torus_only()
    ref = reference_parts(impl)
    ts = stage.prepare(scene, impl, hierarchy=True)
    escene, embree_build_s = _embree(ts)
    rays = _query_rays(scene, 480 if quick else 960)
    repeats = 2 if quick else 5
    closest = closest_queries(ref, ts)
    out: dict = {"triangles": int(ts.n_triangles), "cpus": os.cpu_count(),
                 "machine": platform.processor() or platform.machine(), "kinds": {},
                 "build": hierarchy_build(impl, ts, embree_build_s, quick)}
    if escene is None:
        out["embree"] = "embreex is not installed (pip install -e '.[peers]'): Embree columns skipped"
    bar = Progress("closest-hit queries against Embree", len(rays))
    for kind, (o, d) in rays.items():
        bar.advance(0, note=kind)
        o = np.ascontiguousarray(o)
        d = np.ascontiguousarray(d)
        n = len(o)
        t, prim, stats = closest(o, d)
        row: dict = {"rays": n, "nodes_per_ray": float(stats[:, 0].mean()), "tests_per_ray": float(stats[:, 1].mean())}
        hit = prim >= 0     # the rays that reach a triangle: traversal's real work (a miss of the root box is cheap)
        oh, dh = np.ascontiguousarray(o[hit]), np.ascontiguousarray(d[hit])
        row["hit_fraction"] = float(hit.mean())
        if escene is not None:
            o32, d32 = o.astype(np.float32), d.astype(np.float32)
            oh32, dh32 = oh.astype(np.float32), dh.astype(np.float32)
            res = escene.run(o32, d32, output=1)
            ehit = res["geomID"] >= 0
            row["agree_prim"] = float(np.mean(np.where(ehit, res["primID"], -1) == np.where(prim >= 0, prim, -1)))
            both = ehit & (prim >= 0)
            row["agree_t_rel"] = float(np.median(np.abs(res["tfar"][both] - t[both]) / t[both])) if both.any() else 0.0
            half = n // 2
            pool = ThreadPoolExecutor(2)

            def two():
                list(pool.map(lambda s: escene.run(o32[s], d32[s], output=1), (slice(0, half), slice(half, n))))
        best: dict[str, float] = {}
        for _ in range(repeats):   # interleaved, so that the machine's load weighs on both alike
            for threads in (1, 2):
                with threads_of(ref, threads):
                    seconds = best_of(lambda: closest(o, d), 1)
                best[f"reference_{threads}t_Mrays"] = max(best.get(f"reference_{threads}t_Mrays", 0), n / seconds / 1e6)
            if len(oh):
                with threads_of(ref, 1):
                    seconds = best_of(lambda: closest(oh, dh), 1)
                best["reference_1t_hit_Mrays"] = max(best.get("reference_1t_hit_Mrays", 0), len(oh) / seconds / 1e6)
            ts.reset_counters()
            seconds = best_of(lambda: impl.closest_hit(ts, o, d), 1)
            best["reference_W5_Mrays"] = max(best.get("reference_W5_Mrays", 0), n / seconds / 1e6)
            if escene is not None:
                for label, output in (("full", 1), ("prim", None)):
                    seconds = best_of(lambda: escene.run(o32, d32, output=output), 1)
                    best[f"embree_1t_{label}_Mrays"] = max(best.get(f"embree_1t_{label}_Mrays", 0), n / seconds / 1e6)
                best["embree_2t_full_Mrays"] = max(best.get("embree_2t_full_Mrays", 0), n / best_of(two, 1) / 1e6)
                if len(oh):
                    seconds = best_of(lambda: escene.run(oh32, dh32, output=1), 1)
                    best["embree_1t_hit_Mrays"] = max(best.get("embree_1t_hit_Mrays", 0), len(oh) / seconds / 1e6)
        row.update(best)
        if escene is not None:
            pool.shutdown()
            row["ratio_2t"] = row["reference_2t_Mrays"] / row["embree_2t_full_Mrays"]
            row["ratio_1t"] = row["reference_1t_Mrays"] / row["embree_1t_full_Mrays"]
            if "embree_1t_hit_Mrays" in row:
                row["ratio_1t_hit"] = row["reference_1t_hit_Mrays"] / row["embree_1t_hit_Mrays"]
        out["kinds"][kind] = row
        bar.advance(note=kind)
    bar.close()
    return out


def _plot(rows: list[dict], speed: dict, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
    ax = axes[0]
    markers = {"size": "o", "spp": "s", "cut-off": "^", "shadow rays": "D"}
    colours = dict(zip(SCENES, ("tab:blue", "tab:orange", "tab:green")))
    for r in rows:
        ax.scatter(r["seconds"], r["rms_error"], marker=markers[r["sweep"]], color=colours[r["scene"]], s=30)
        ax.annotate(r["value"], (r["seconds"], r["rms_error"]), fontsize=6, xytext=(3, 2), textcoords="offset points")
    for scene, c in colours.items():
        ax.scatter([], [], color=c, label=scene)
    for sweep, m in markers.items():
        ax.scatter([], [], marker=m, color="gray", label=sweep)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("frame time (s)")
    ax.set_ylabel("RMS error against converged (linear)")
    ax.set_title("Whitted reference: time against error")
    ax.legend(fontsize=7)
    ax = axes[1]
    kinds = list(speed["kinds"])
    labels = [k for k in ("reference_1t_Mrays", "reference_2t_Mrays", "embree_1t_full_Mrays", "embree_2t_full_Mrays")
              if k in speed["kinds"][kinds[0]]]
    x = np.arange(len(kinds))
    for i, label in enumerate(labels):
        ax.bar(x + i * 0.2, [speed["kinds"][k][label] for k in kinds], 0.2, label=label.replace("_Mrays", ""))
    ax.set_xticks(x + 0.3, kinds)
    ax.set_ylabel("million closest-hit rays per second")
    ax.set_title(f"{speed['triangles']:,} triangles")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def summary(speed: dict, frame_rows: list[dict], demo_rows: list[dict]) -> list[str]:
    """The issue's table: each ratio measured side by side in this run (Markdown)."""
    lines = ["| measure | kit | peer, same run | ratio |", "|---|---|---|---|"]
    kinds, build = speed["kinds"], speed["build"]
    for kind, label in (("primary", "primary rays"), ("random", "random rays from inside")):
        r = kinds[kind]
        peer = f"Embree {r['embree_1t_full_Mrays']:.2f}" if "embree_1t_full_Mrays" in r else "-"
        ratio = f"{r['ratio_1t']:.2f}" if "ratio_1t" in r else "-"
        lines.append(f"| closest-hit, {label}, {speed['triangles']:,}-triangle torus, 1 thread (M rays/s) | "
                     f"{r['reference_1t_Mrays']:.2f} | {peer} | {ratio} |")
        if "reference_1t_hit_Mrays" in r:
            peer = f"Embree {r['embree_1t_hit_Mrays']:.2f}" if "embree_1t_hit_Mrays" in r else "-"
            ratio = f"{r['ratio_1t_hit']:.2f}" if "ratio_1t_hit" in r else "-"
            lines.append(f"| the same, only the {r['hit_fraction']:.0%} of them that hit a triangle | "
                         f"{r['reference_1t_hit_Mrays']:.2f} | {peer} | {ratio} |")
    peer = f"Embree {build['embree_build_s']:.3f} s" if "embree_build_s" in build else "-"
    ratio = f"{build['ratio']:.2f}×" if "ratio" in build else "-"
    lines.append(f"| hierarchy build + eight-wide layout, {speed['triangles']:,} triangles (again from the cache: "
                 f"{build['cached_s'] * 1e3:.1f} ms) | {build['build_s'] + build['layout_s']:.3f} s | {peer} | {ratio} |")
    names = " · ".join(r["scene"] for r in frame_rows)

    def each(key: str, fmt: str = ".2f") -> str:
        return " · ".join(format(r[key], fmt) for r in frame_rows)
    for t in (1, 2):
        on = f"{t} thread{'s' * (t > 1)}"
        seconds = " · ".join(f"{r[f'frame_{t}t_Mrays']:.2f} ({r[f'frame_{t}t_s']:.3f})" for r in frame_rows)
        lines.append(f"| whole frame 320×240, 1 spp, {on}: {names}; M rays/s (s), against the closest-hit kernel on "
                     f"its camera rays | {seconds} | kernel {each(f'kernel_{t}t_Mrays')} | "
                     f"{each(f'frame_over_kernel_{t}t')} |")
        lines.append(f"| the same frames against the kernels on the frame's own rays (closest hit and shadow), {on} | "
                     f"{each(f'frame_{t}t_Mrays')} | kernels {each(f'own_rays_{t}t_Mrays')} | "
                     f"{each(f'frame_over_own_rays_{t}t')} |")
        lines.append(f"| the frame's own rays through the kernels alone, against the closest-hit kernel on its camera rays "
                     f"(the frame's ratio if shading cost nothing), {on} | kernels {each(f'own_rays_{t}t_Mrays')} | "
                     f"kernel {each(f'kernel_{t}t_Mrays')} | {each(f'own_rays_over_kernel_{t}t')} |")
        lines.append(f"| the same frames with camera rays only (no lights, no recursion), {on} (s); its share spent on "
                     f"the lights | {each(f'camera_only_{t}t_s', '.4f')}; lights {each(f'lights_share_{t}t', '.0%')} | "
                     f"kernel on the same rays | {each(f'camera_only_over_kernel_{t}t')} |")
        lines.append(f"| `render_traced` (with the scene to arrays), {on} (s) | {each(f'render_{t}t_s', '.3f')} | - | - |")
        if f"mitsuba_{t}t_s" in frame_rows[0]:
            lines.append(f"| the same frames beside Mitsuba 3 direct lighting, {on} (s) | {each(f'frame_{t}t_s', '.3f')} "
                         f"| Mitsuba {each(f'mitsuba_{t}t_s', '.3f')} | kit/Mitsuba time "
                         f"{each(f'frame_over_mitsuba_time_{t}t')} |")
    names = " · ".join(r["scene"] for r in demo_rows)
    lines.append(f"| `cs451 demo whitted` 320×240, fresh demo to finished picture: {names}; s (frames shown, fps), "
                 f"against one render of the same frame | "
                 + " · ".join(f"{r['refine_s']:.2f} ({r['frames']}, {r['fps']:.0f} fps)" for r in demo_rows)
                 + " | render " + " · ".join(f"{r['frame_s']:.3f} s" for r in demo_rows)
                 + " | " + " · ".join(f"{r['refine_over_frame']:.1f}×" for r in demo_rows) + " |")
    return lines


def main(output: Path, quick: bool = False) -> dict:
    """Every part (closest hits against Embree, whole frames, the demo, time against error): prints the tables and
    the summary, writes ``whitted.json`` and ``whitted.png`` in ``output``, and returns the data."""
    impl = load_impl(resolve_impl("reference", "whitted"), "whitted")
    speed = rays_per_second(impl, quick)
    frame_rows = frames(impl, quick)
    demo_rows = demo_speed(impl, quick, {r["scene"]: r["render_2t_s"] for r in frame_rows})
    rows = time_against_error(impl, quick)
    print("stage 2 whitted: time against error (RMS, linear, clipped to [0, 1]) against a converged render "
          f"(spp {CONVERGED['spp']}, cut-off {CONVERGED['min_weight']:g}, depth {CONVERGED['max_depth']}, "
          f"{CONVERGED['light_samples']} shadow rays per area light)")
    print(f"{'scene':<16} {'sweep':<12} {'value':>8} {'size':>8} {'seconds':>8} {'rays':>9} {'Mrays/s':>8} {'RMS error':>10}")
    for r in rows:
        print(f"{r['scene']:<16} {r['sweep']:<12} {r['value']:>8} {r['width']}×{r['height']:<4} {r['seconds']:>8.3f} "
              f"{r['rays']:>9} {r['rays'] / r['seconds'] / 1e6:>8.2f} {r['rms_error']:>10.5f}")
    b = speed["build"]
    print(f"\nclosest-hit queries, {speed['triangles']:,} triangles (rippled torus alone), {speed['cpus']} CPUs; "
          f"hierarchy: build {b['build_s']:.3f} s + eight-wide layout {b['layout_s']:.3f} s ({b['nodes']} nodes; "
          f"first build in this process {b['first_build_s']:.2f} s, from the cache {b['cached_s'] * 1e3:.1f} ms)"
          + (f", Embree {b['embree_build_s']:.3f} s" if "embree_build_s" in b else ""))
    if "embree" in speed:
        print(speed["embree"])
    cols = ["reference_1t_Mrays", "reference_2t_Mrays", "reference_W5_Mrays", "embree_1t_full_Mrays",
            "embree_1t_prim_Mrays", "embree_2t_full_Mrays", "ratio_1t", "ratio_2t", "agree_prim", "hit_fraction",
            "reference_1t_hit_Mrays", "embree_1t_hit_Mrays", "ratio_1t_hit"]
    print(f"{'rays':<8} {'n':>8} " + " ".join(f"{c.replace('_Mrays', ''):>16}" for c in cols))
    for kind, r in speed["kinds"].items():
        print(f"{kind:<8} {r['rays']:>8} " + " ".join(f"{r[c]:>16.3f}" if c in r else f"{'-':>16}" for c in cols))
    print_frames(frame_rows)
    print_time_split(frame_rows)
    print_demo_speed(demo_rows)
    table = summary(speed, frame_rows, demo_rows)
    print("\nsummary (each ratio measured side by side in this run)\n" + "\n".join(table))
    output.mkdir(parents=True, exist_ok=True)
    result = {"time_against_error": rows, "closest_hit": speed, "frames": frame_rows, "demo": demo_rows,
              "converged": CONVERGED,
              "summary": table}
    (output / "whitted.json").write_text(json.dumps(result, indent=2))
    _plot(rows, speed, output / "whitted.png")
    print(f"wrote {output / 'whitted.json'} and {output / 'whitted.png'}")
    return result


# --- the slides' record: `cs451 slides record whitted` -------------------------------------------------------

#: what `cs451 slides record whitted` measures (full; --quick: the tests' small run)
SLIDE = {False: {"top": (320, 240), "spps": (1, 4, 9), "cutoffs": (0.5, 0.1, 0.01, 0.001)},
         True: {"top": (64, 48), "spps": (1, 4), "cutoffs": (0.5, 0.01)}}
SLIDE_COLUMNS = {
    "sweep": "what varies: size, spp (samples per pixel) or cut-off; the others at the default (1 spp, cut-off 0.01, "
             "the largest size)",
    "value": "its value, as the figure labels it",
    "width": "image width (pixels)", "height": "image height (pixels)", "spp": "samples per pixel",
    "cutoff": "the β cut-off: a ray is cast while its weight is at least this",
    "seconds": "median wall-clock seconds of a whole frame (render_traced, the reference on its numpy path)",
    "seconds_min": "fastest repeat (wall clock)", "seconds_max": "slowest repeat (wall clock)",
    "cpu_seconds": "median CPU seconds this process spent on the frame: what the figure plots, since other work on "
                   "the machine delays the wall clock but not this (single-threaded numpy: the two agree on a quiet "
                   "machine)",
    "cpu_seconds_min": "fastest repeat (CPU)", "cpu_seconds_max": "slowest repeat (CPU)",
    "rms_error": "RMS difference from the converged render (linear colour clipped to [0, 1], the converged image "
                 "box-filtered to the size rendered)",
    "rays": "rays cast: camera, shadow, reflected and refracted (the tracer's counters)",
}


def slide_record(quick: bool = False, repeats: int = 3) -> dict:
    """The Whitted deck's time-against-error record (``cs451 slides record whitted``): Whitted's scene on the
    reference's numpy path (its compiled kernels held off, as the other slides draw it) over image size, samples per
    pixel and the cut-off, each frame's error against a converged render. Every configuration is rendered
    ``repeats`` times, round-robin over the configurations, so that a busy moment of the machine weighs on all of
    them alike; a configuration shared by two sweeps (the default) is measured once."""
    from cs451.stages.whitted.accel import forced

    plan = SLIDE[quick]
    impl = load_impl(resolve_impl("reference", "whitted"), "whitted")
    scene = load_scene("whitted")
    top = tuple(plan["top"])
    configs: dict[tuple, tuple[tuple[int, int], dict]] = {}
    sweeps = []
    for w, h in ((top[0] // 4, top[1] // 4), (top[0] // 2, top[1] // 2), top):
        sweeps.append(("size", f"{w}×{h}", (w, h), DEFAULT))
    sweeps += [("spp", str(s), top, {**DEFAULT, "spp": s}) for s in plan["spps"]]
    sweeps += [("cut-off", f"{c:g}", top, {**DEFAULT, "min_weight": c}) for c in plan["cutoffs"]]
    for _, _, size, opts in sweeps:
        configs.setdefault((size, tuple(sorted(opts.items()))), (size, opts))
    measured: dict[tuple, dict] = {key: {"seconds": [], "cpu": []} for key in configs}
    bar = Progress("whitted: time against error", 1 + repeats * len(configs), unit="frame")
    try:
        with forced("numpy"):
            _render(impl, scene, (16, 12))                              # imports and first calls, untimed
            bar.advance(0, note="converged")
            converged, _, converged_seconds = _render(impl, scene, top, **CONVERGED)
            bar.advance(note="converged")
            for _ in range(repeats):
                for key, (size, opts) in configs.items():
                    cpu = time.process_time()
                    image, counters, seconds = _render(impl, scene, size, **opts)
                    measured[key]["cpu"].append(time.process_time() - cpu)
                    measured[key]["seconds"].append(seconds)
                    truth = _downsample(converged, size)
                    measured[key]["error"] = float(np.sqrt(np.mean((np.clip(image, 0, 1) - np.clip(truth, 0, 1)) ** 2)))
                    measured[key]["rays"] = int(sum(counters[k] for k in ("camera", "shadow", "reflection",
                                                                          "transmission")))
                    bar.advance(note=f"{size[0]}×{size[1]} {opts}")
    finally:
        bar.close()
    rows = []
    for sweep, value, size, opts in sweeps:
        m = measured[(size, tuple(sorted(opts.items())))]
        rows.append({"sweep": sweep, "value": value, "width": size[0], "height": size[1], "spp": opts["spp"],
                     "cutoff": opts["min_weight"], "seconds": float(np.median(m["seconds"])),
                     "seconds_min": min(m["seconds"]), "seconds_max": max(m["seconds"]),
                     "cpu_seconds": float(np.median(m["cpu"])), "cpu_seconds_min": min(m["cpu"]),
                     "cpu_seconds_max": max(m["cpu"]), "rms_error": m["error"], "rays": m["rays"]})
    return {"rows": rows, "columns": SLIDE_COLUMNS,
            "params": {"scene": "whitted", "path": "numpy (the reference's compiled kernels held off)",
                       "converged": CONVERGED, "converged_seconds": converged_seconds, "default": DEFAULT,
                       "top": list(top), "options": {k: v for k, v in vars(stage.STAGE.options(scene)).items()
                                                     if isinstance(v, (int, float, str, bool))}}}
