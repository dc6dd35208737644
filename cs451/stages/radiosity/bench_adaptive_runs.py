"""The adaptive mesh against a uniform one at equal element count (:mod:`.bench_adaptive`), each against
Mitsuba's converged render wall by wall, and the handout's figure of the two meshes: part of ``cs451 bench
radiosity``.
"""
from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np

from cs451 import KIT_ROOT, import_from_kit
from cs451.patches import patch_areas

from .bench_adaptive import solve_adaptive, uniform_solution
from .bench_adaptive_display import draw

subdivide_uniform = import_from_kit("bench.meshes").subdivide_uniform    # the kit's fine meshes (bench/)

#: the full and the quick run: patch size, hemicube resolution, image size, Mitsuba's samples per pixel (two halves),
#: uniform elements per patch side (each compared with adaptive at the same element count)
RUNS = {False: {"patch_size": 100.0, "resolution": 128, "size": (256, 256), "spp": 512, "ks": (2, 3, 4)},
        True: {"patch_size": 140.0, "resolution": 64, "size": (128, 128), "spp": 64, "ks": (2,)}}
#: the relative contrast between neighbours above which elements are split
THRESHOLD = 0.1
#: the finest element the refinement may make: 1/8 of a patch's side
FINEST = 8
#: the light's patches split again, k × k, so that it shoots from more points than the walls' patch size gives it
#: (a patch shoots from its centre: four points make four hard shadows where the real light makes penumbrae)
LIGHT_SPLIT = 2
#: the mesh figure's panels, pixels
FIGURE_SIZE = (320, 320)
#: the figure's second row: the floor seen from high above the box, the near plane past the ceiling and the light
#: (951 away) so that they are cut away, the back wall at the top; Mitsuba renders it with half the table's samples
PLAN = (("eye", (278.0, 1500.0, 279.6)), ("center", (278.0, 0.0, 279.6)), ("up", (0.0, 0.0, 1.0)), ("fovy", 23.0),
        ("near", 960.0), ("far", 3000.0))
#: the handout's copy of the mesh figure (kit only: a student's release has no bench), written by the full bench run
HANDOUT_FIGURE = KIT_ROOT / "assignments" / "04-radiosity" / "kit" / "adaptive-mesh.png"


def split_emitters(patches: Any, k: int) -> Any:
    """The patches with every emitting patch split k × k again (a :class:`cs451.patching.Patches`)."""
    from cs451.patching import Patches

    emits = np.asarray(patches.emission).max(axis=1) > 0
    light, rest = np.flatnonzero(emits), np.flatnonzero(~emits)
    finer, parent = subdivide_uniform(patches.quads[light], k)
    source = np.concatenate([rest, light[parent]])
    quads = np.concatenate([patches.quads[rest], finer])
    return Patches(quads, patches.parent[source], patch_areas(quads), patches.reflectance[source],
                   patches.emission[source], patches.polygons, patches.labels)


def image_errors(ours: np.ndarray, theirs: np.ndarray, masks: dict[str, np.ndarray]) -> dict[str, float]:
    """Relative L1 error Σ|ours − theirs| / Σ|theirs| over each wall's pixels (all channels), and over all of them ("image")."""
    out, num, den = {}, 0.0, 0.0
    for wall, mask in masks.items():
        d, t = float(np.abs(ours[mask] - theirs[mask]).sum()), float(np.abs(theirs[mask]).sum())
        out[wall] = d / max(t, 1e-300)
        num, den = num + d, den + t
    out["image"] = num / max(den, 1e-300)
    return out


def mesh_overlay(screen: np.ndarray, ids: np.ndarray, color: Sequence[int] = (40, 150, 255), alpha: float = 0.75
                 ) -> np.ndarray:
    """A displayed (uint8) image with the element edges drawn: pixels whose element differs from the next pixel's."""
    edge = np.zeros(ids.shape, dtype=bool)
    edge[:, :-1] |= ids[:, :-1] != ids[:, 1:]
    edge[:-1, :] |= ids[:-1, :] != ids[1:, :]
    out = screen.astype(np.float64)
    out[edge] = (1 - alpha) * out[edge] + alpha * np.asarray(color, dtype=np.float64)
    return np.round(out).astype(np.uint8)


def compare_adaptive(ref: Any, quick: bool) -> dict | None:
    """The Cornell box, uniform against adaptive elements at equal counts: error against Mitsuba per wall and on the image.

    The image error is the relative L1 over the walls' pixels (:func:`image_errors`), and ꟻLIP over the
    whole frame as a screen shows it (sRGB). Mitsuba's own noise: half the L1 difference of its two halves (the
    noise of their mean), and ꟻLIP between the halves (each noisier than the mean). Adaptive elements start from
    half the uniform side (one element a patch below 4 × 4) and may be cut down to 1/:data:`FINEST` of a patch.
    """
    try:
        import mitsuba  # noqa: F401
    except ImportError:
        print("Mitsuba 3 is not installed (pip install -e '.[peers]'): skipping the adaptive subdivision comparison")
        return None
    from cs451.stages.radiosity import display as D
    from cs451.compare import flip_error
    from cs451.gl import create_context
    from cs451.imageio import to_uint8
    from cs451.scene import load_scene
    from cs451.stages import radiosity as R
    from .bench_peer import mitsuba_reference, polygon_ids, wall_masks

    import dataclasses

    run = RUNS[quick]
    scene = load_scene("cornell-box")
    plan = dataclasses.replace(scene, camera=dataclasses.replace(scene.camera, **dict(PLAN)))
    size = run["size"]
    peer = mitsuba_reference("cornell-box", size, run["spp"], 64)
    theirs = peer["image"]
    ctx = create_context()
    drawer = D.GouraudDrawer(ctx)
    masks = wall_masks(polygon_ids(scene, size, drawer=drawer))
    screen = lambda image: to_uint8(image, scene.image.exposure, scene.image.srgb)
    patches = split_emitters(R.make_patches(scene, ref, run["patch_size"]), LIGHT_SPLIT)
    engine = lambda quads: R.hemicube_formfactors(quads, run["resolution"], "none", ctx=ctx)
    noise = image_errors(peer["halves"][0], peer["halves"][1], masks)
    rows: list[dict] = [{"method": "Mitsuba's own noise", "k": None, "elements": None, "hemicubes": None, "seconds": None,
                         "errors": {w: 0.5 * e for w, e in noise.items()},
                         "flip": flip_error(screen(peer["halves"][0]), screen(peer["halves"][1]))[0]}]
    figure: dict[str, Any] = {}
    for k in run["ks"]:
        start_k = max(1, k // 2)                    # room to place three quarters of the budget, or more
        depth = int(round(math.log2(FINEST / start_k)))
        for method in ("uniform", "adaptive"):
            if method == "uniform":
                sol = uniform_solution(patches, engine, k)
            else:
                sol = solve_adaptive(patches, engine, k=start_k, threshold=THRESHOLD, max_depth=depth,
                                     budget=len(patches) * k * k)
            ours = draw(scene, ref, sol, len(patches), size, drawer=drawer)
            rows.append({"method": method, "k": k, "elements": len(sol.mesh), "hemicubes": sol.hemicubes,
                         "seconds": sol.seconds, "errors": image_errors(ours, theirs, masks),
                         "flip": flip_error(screen(theirs), screen(ours))[0], "passes": sol.passes,
                         "start": None if method == "uniform" else {"k": start_k, "max_depth": depth}})
            if k == run["ks"][0]:                     # the figure shows the coarsest pair, where the mesh can be seen
                views = []
                for seen in (scene, plan):            # the scene's camera, and the floor from above
                    big = draw(seen, ref, sol, len(patches), FIGURE_SIZE, drawer=drawer)
                    views.append(mesh_overlay(screen(big), polygon_ids(seen, FIGURE_SIZE, quads=sol.mesh.quads,
                                                                      drawer=drawer)))
                figure[method] = {"image": views[0], "plan": views[1], "elements": len(sol.mesh),
                                  "error": rows[-1]["errors"]["image"], "floor": rows[-1]["errors"]["floor"]}
            print(f"  adaptive subdivision: {method} at {len(sol.mesh)} elements done", flush=True)
    above = mitsuba_reference("cornell-box", FIGURE_SIZE, max(run["spp"] // 2, 2), 64, PLAN)
    figure["mitsuba"] = {"image": screen(theirs), "plan": screen(above["image"]), "spp": peer["spp"],
                         "plan_spp": above["spp"]}
    return {"scene": "cornell-box", "patches": len(patches), "patch_size": run["patch_size"], "light_split": LIGHT_SPLIT,
            "resolution": run["resolution"], "size": list(size), "threshold": THRESHOLD, "finest": FINEST,
            "mitsuba_spp": peer["spp"], "mitsuba_seconds": peer["seconds"], "rows": rows, "figure": figure}


def print_adaptive(result: dict) -> list[str]:
    """The table: per wall and on the image, relative L1 error against Mitsuba, uniform against adaptive."""
    walls = [w for w in result["rows"][0]["errors"] if w != "image"]
    short = {w: w.split(" ")[0] for w in walls}
    head = "".join(f"{short[w]:>8}" for w in walls)
    lines = ["", f"adaptive subdivision: the Cornell box, {result['patches']} patches (the light's split "
             f"{result['light_split']} × {result['light_split']}), hemicube {result['resolution']}; relative L1 error "
             f"against Mitsuba 3 ({result['mitsuba_spp']} spp, {result['mitsuba_seconds']:.0f} s) per wall and over all "
             f"walls ('image'), ꟻLIP over the frame; adaptive: threshold {result['threshold']:g}, finest 1/{result['finest']} "
             f"of a patch",
             f"{'method':<20} {'elements':>8} {'hemicubes':>9} {'seconds':>7}{head} {'image':>7} {'ꟻLIP':>6}", "-" * 120]
    for row in result["rows"]:
        e = row["errors"]
        cells = "".join(f"{100 * e[w]:>7.2f}%" for w in walls)
        cost = (f"{row['elements']:>8} {row['hemicubes']:>9} {row['seconds']:>7.1f}" if row["elements"] is not None
                else f"{'':>8} {'':>9} {'':>7}")
        lines.append(f"{row['method']:<20} {cost}{cells} {100 * e['image']:>6.2f}% {row['flip']:>6.3f}")
    print("\n".join(lines))
    return lines


def mesh_figure(fig_data: dict, path: Any) -> Any:
    """Uniform and adaptive meshes of the same element count over their renders, beside Mitsuba's: a PNG at ``path``.

    The top row shows the box from the scene's camera, the bottom row its floor from above (:data:`PLAN`), where
    the shadows are. ``fig_data`` is :func:`compare_adaptive`'s ``figure``. The full run of
    ``cs451 bench radiosity`` writes it to :data:`HANDOUT_FIGURE` too, the copy the handout shows.
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from pathlib import Path

    u, a, m = fig_data["uniform"], fig_data["adaptive"], fig_data["mitsuba"]
    titles = [f"uniform: {u['elements']} elements\nerror {100 * u['error']:.1f}% (floor {100 * u['floor']:.1f}%)",
              f"adaptive: {a['elements']} elements\nerror {100 * a['error']:.1f}% (floor {100 * a['floor']:.1f}%)",
              f"Mitsuba 3, {m['spp']} spp\n(the reference; from above, {m['plan_spp']} spp)"]
    fig, axes = plt.subplots(2, 3, figsize=(12, 8.4))
    for col, (panel, title) in enumerate(zip((u, a, m), titles)):
        axes[0, col].imshow(panel["image"], interpolation="nearest")
        axes[0, col].set_title(title, fontsize=10)
        axes[1, col].imshow(panel["plan"], interpolation="nearest")
        for ax in axes[:, col]:
            ax.axis("off")
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=80)
    plt.close(fig)
    return path
