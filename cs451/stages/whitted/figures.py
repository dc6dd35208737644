"""The Whitted deck's figures: ray trees, the kinds of rays, the cut-off, the hierarchy, and the bench measured small.
"""
from __future__ import annotations

import copy
from typing import Any, Callable

import numpy as np

from ...bench import bench_module
from ...progress import Progress
from ...scene import parse_scene
from .. import get_stage
from ...slides.registry import Drawn, slide_figure
from ...slides.canvas import (Panel, axes_plot, encoded, panel_grid, project, reference_impl, scene_data,
                              stacked, visible_segment)
from .accel import forced
from .figure_rays import ray_tree
from .ray_tree import Pinhole


WHITTED_KIT = ("cs451.stages.whitted", "cs451.stages.base", "cs451.tracescene", "cs451.scene", "cs451.viewing",
               "cs451.imageio", "cs451.stages.whitted.figure_rays", "cs451.stages.whitted.ray_tree")
#: how each kind of ray is drawn (colour, line style); shadow rays by what reaches the point
RAY_STYLE = {"camera": ("white", "-"), "reflection": ("#33d6ff", "-"), "refraction": ("#ff5ce1", "-"),
             "lit": ("#ffd21f", "--"), "dimmed": ("#ff9a1f", "--"), "blocked": ("#8a8a8a", ":")}


def camera_matrix(camera: Any, size: tuple[int, int]) -> np.ndarray:
    """Projection · view of a scene camera (clip space, as :func:`cs451.slides.canvas.project` reads it), fitted to the
    reference's own camera rays (W1) as the demo fits its pinhole: no other stage's view function needed."""
    rays = get_stage("whitted").call(reference_impl("whitted"), "W1", camera, *size)
    return Pinhole(*rays, size[0], size[1], 1).clip_matrix()


def _whitted(data: dict[str, Any], size: tuple[int, int], **options: Any) -> tuple[np.ndarray, dict[str, int]]:
    """A scene traced by the reference through stage 2's render probe: the image (uint8) and the tracer's counters."""
    stage, impl = get_stage("whitted"), reference_impl("whitted")
    with forced("numpy"):
        out = stage.probes["render"](impl, data, list(size), **options)
    counters = {k: int(v) for k, v in out.items() if k != "image"}
    return encoded(out["image"], parse_scene(data)), counters


def _shadow_style(ray: dict[str, Any]) -> str:
    through = float(np.max(ray["through"]))
    return "lit" if through >= 0.999 else "blocked" if through <= 1e-6 else "dimmed"


def _draw_rays(rays: list[dict[str, Any]], matrix: np.ndarray, size: tuple[int, int], kinds: set[str] | None = None,
               width: float = 1.6) -> Callable[[Any], None]:
    """An overlay that draws ``rays`` (those of ``kinds``) projected by ``matrix``, with a dot at every hit."""
    def overlay(ax: Any) -> None:
        for ray in rays:
            if kinds is not None and ray["kind"] not in kinds:
                continue
            style = _shadow_style(ray) if ray["kind"] == "shadow" else ray["kind"]
            line = visible_segment(matrix, ray["origin"], ray["end"], size)
            if line is None:
                continue
            colour, dashes = RAY_STYLE[style]
            ax.plot(line[:, 0], line[:, 1], color=colour, ls=dashes, lw=width, solid_capstyle="round")
            if ray["hit"]:
                ax.plot(*line[1], "o", ms=4, color="white", mec="black", mew=0.6)
    return overlay


def _legend(ax: Any, styles: list[str], labels: dict[str, str] | None = None) -> None:
    from matplotlib.lines import Line2D
    labels = labels or {}
    handles = [Line2D([], [], color=RAY_STYLE[s][0], ls=RAY_STYLE[s][1], lw=2, label=labels.get(s, s)) for s in styles]
    legend = ax.legend(handles=handles, loc="lower right", fontsize=7, framealpha=0.75, facecolor="#202020",
                       edgecolor="none", labelcolor="white")
    legend.set_zorder(10)


SHADOW_LABELS = {"lit": "shadow ray: the light reaches", "dimmed": "shadow ray: through glass",
                 "blocked": "shadow ray: blocked"}


def _side_view(data: dict[str, Any], camera: dict[str, Any]) -> dict[str, Any]:
    """The same scene seen by another camera."""
    other = copy.deepcopy(data)
    other["camera"] = {**other["camera"], **camera}
    return other


@slide_figure("whitted-ray-tree",
         "The ray tree of one pixel on Whitted's glass sphere, recorded from the reference's W11 (its W5 and W7 "
         "calls): camera, reflected, refracted and shadow rays and every hit, drawn over the image, over the "
         "scene seen from the side, and as a tree",
         full={"size": [400, 300], "side_size": [400, 300], "pixel": [0.345, 0.6],
               "side_camera": {"eye": [6.5, 3.0, 3.3], "center": [-0.3, 1.0, 3.0], "fovy": 48}},
         quick={"size": [80, 60], "side_size": [80, 60]},
         stages=("whitted", "hemicube"), kit=WHITTED_KIT, scenes=("whitted.json",), steps=3)
def _ray_tree_figure(bar: Progress, size: list[int], side_size: list[int], pixel: list[float],
                     side_camera: dict[str, Any]) -> Drawn:
    data = scene_data("whitted.json")
    w, h = size
    px = (min(int(pixel[0] * w), w - 1), min(int(pixel[1] * h), h - 1))
    rays = ray_tree(data, [px], (w, h))
    bar.advance(note="ray tree")
    image, _ = _whitted(data, (w, h))
    side = _side_view(data, side_camera)
    side_image, _ = _whitted(side, tuple(side_size))
    bar.advance(note="images")
    scene, side_scene = parse_scene(data), parse_scene(side)
    front = camera_matrix(scene.camera, (w, h))
    back = camera_matrix(side_scene.camera, tuple(side_size))
    counts = {kind: sum(r["kind"] == kind for r in rays) for kind in ("camera", "reflection", "refraction", "shadow")}
    first_hit = project(front, rays[0]["end"], (w, h))[0]

    def at_pixel(ax: Any) -> None:
        _draw_rays(rays, front, (w, h), kinds={"reflection", "refraction", "shadow"})(ax)
        ax.plot(*px, "s", ms=9, mfc="none", mec="white", mew=1.5)
        _legend(ax, ["reflection", "refraction", "lit", "dimmed", "blocked"], SHADOW_LABELS)

    def from_side(ax: Any) -> None:
        _draw_rays(rays, back, tuple(side_size))(ax)
        eye = project(back, np.asarray(scene.camera.eye), tuple(side_size))[0]
        ax.plot(*eye, "^", ms=8, color="white", mec="black")
        for light in scene.lights:
            ax.plot(*project(back, np.asarray(light.position), tuple(side_size))[0], "*", ms=12, color="#ffd21f",
                    mec="black")

    panels = [Panel(image, f"pixel ({px[0]}, {px[1]}) of the camera's image: its secondary rays"
                           f"\n(its camera ray is the square: it points into the image)", at_pixel),
              Panel(side_image, "the same rays seen from the side\n(triangle: the eye; dashed: toward the lights)",
                    from_side)]
    grid = panel_grid([panels], f"One pixel's ray tree: {counts['camera']} camera, {counts['reflection']} reflected, "
                           f"{counts['refraction']} refracted and {counts['shadow']} shadow rays")
    tree = _tree_diagram(rays, grid.shape[1])
    bar.advance(note="tree")
    facts = {"pixel": list(px), "rays": counts, "first_hit_pixel": first_hit.tolist(),
             "materials": [r["material"] for r in rays if r["hit"]]}
    return Drawn(stacked([grid, tree]), facts)


def _tree_diagram(rays: list[dict[str, Any]], width: int) -> np.ndarray:
    """The rays as a tree: a node per hit (its material), an edge per ray, leaves laid out left to right."""
    children: dict[int | None, list[int]] = {}
    for i, ray in enumerate(rays):
        children.setdefault(ray["parent"], []).append(i)
    x: dict[int, float] = {}
    next_leaf = [0.0]

    def place(i: int) -> float:
        kids = children.get(i, [])
        x[i] = float(np.mean([place(k) for k in kids])) if kids else next_leaf[0]
        if not kids:
            next_leaf[0] += 1.0
        return x[i]
    for root in children.get(None, []):
        place(root)
    depth = max(r["depth"] for r in rays) + 1

    def draw(ax: Any) -> None:
        for i, ray in enumerate(rays):
            y = -ray["depth"] - 1
            x0, y0 = (x[ray["parent"]], -ray["depth"]) if ray["parent"] is not None else (x[i], 0.0)
            style = _shadow_style(ray) if ray["kind"] == "shadow" else ray["kind"]
            colour, dashes = RAY_STYLE[style]
            ax.plot([x0, x[i]], [y0, y], color="black" if style == "camera" else colour, ls=dashes, lw=2)
            if ray["kind"] == "shadow":
                ax.plot(x[i], y, "*", ms=9, color=colour, mec="black", mew=0.5)
            elif ray["hit"]:
                ax.plot(x[i], y, "o", ms=7, color="white", mec="black")
                ax.annotate(ray["material"], (x[i], y), xytext=(5, 3), textcoords="offset points", fontsize=7)
            else:
                ax.annotate("sky", (x[i], y), xytext=(0, -10), textcoords="offset points", fontsize=7, ha="center")
        ax.plot(x[0], 0, "^", ms=9, color="white", mec="black")
        ax.annotate("eye", (x[0], 0), xytext=(6, 0), textcoords="offset points", fontsize=7, va="center")
        ax.set_xlim(-0.7, max(next_leaf[0] - 0.3, 0.7))
        ax.set_ylim(-depth - 0.6, 0.5)
        ax.set_yticks([-k for k in range(depth + 1)], [str(k) for k in range(depth + 1)], fontsize=7)
        ax.set_ylabel("depth", fontsize=8)
        ax.set_xticks([])
        ax.set_title("the same rays as a tree (nodes: hits, with their material; stars: lights)", fontsize=9)
        for spine in ("top", "right", "bottom"):
            ax.spines[spine].set_visible(False)
    return axes_plot(width, 60 * depth + 90, draw)


def _pixels_and_rays(rays: list[dict[str, Any]], kinds: set[str], pixels: list[tuple[int, int]], styles: list[str],
                     matrix: np.ndarray, size: tuple[int, int]) -> Callable[[Any], None]:
    """An overlay: the rays of ``kinds``, a square on each pixel they come from, and a legend of ``styles``."""
    def overlay(ax: Any) -> None:
        _draw_rays(rays, matrix, size, kinds=kinds)(ax)
        for p in pixels:
            ax.plot(*p, "s", ms=8, mfc="none", mec="white", mew=1.4)
        _legend(ax, styles, SHADOW_LABELS)
    return overlay


@slide_figure("whitted-ray-kinds",
         "The three kinds of secondary ray from the hits of a few pixels of Whitted's scene, recorded from the "
         "reference's W11: shadow rays (reaching the light, dimmed by glass, blocked), reflected rays off the mirror "
         "and refracted rays through the glass, with the whole image's ray counters",
         full={"size": [400, 300],
               "pixels": {"shadow": [[0.473, 0.721], [0.712, 0.609], [0.841, 0.801]],
                          "reflection": [[0.638, 0.529], [0.545, 0.384], [0.69, 0.45]],
                          "refraction": [[0.386, 0.528], [0.408, 0.405], [0.33, 0.6]]}},
         quick={"size": [80, 60]},
         stages=("whitted", "hemicube"), kit=WHITTED_KIT, scenes=("whitted.json",), steps=4)
def _ray_kinds(bar: Progress, size: list[int], pixels: dict[str, list[list[float]]]) -> Drawn:
    data = scene_data("whitted.json")
    w, h = size
    image, counters = _whitted(data, (w, h))
    bar.advance(note="image")
    matrix = camera_matrix(parse_scene(data).camera, (w, h))
    kinds = {"shadow": ({"shadow"}, ["lit", "dimmed", "blocked"], "shadow rays: toward each light"),
             "reflection": ({"reflection"}, ["reflection"], "reflected rays: r = d − 2(d·n)n"),
             "refraction": ({"refraction"}, ["refraction"], "refracted rays: Snell's law")}
    panels, facts = [], {"image_counters": counters}
    for kind, (drawn, styles, caption) in kinds.items():
        picked = [(min(int(fx * w), w - 1), min(int(fy * h), h - 1)) for fx, fy in pixels[kind]]
        # the shadow panel looks at the camera rays' own hits only (depth 0): the rays of the hits it is about
        rays = ray_tree(data, picked, (w, h), **({"max_depth": 0} if kind == "shadow" else {}))
        shown = [r for r in rays if r["kind"] in drawn]
        facts[kind] = {"pixels": [list(p) for p in picked], "rays": len(shown),
                       "styles": sorted({_shadow_style(r) for r in shown}) if kind == "shadow" else [kind]}
        panels.append(Panel(image, f"{caption}\n{len(shown)} from the {len(picked)} marked pixels",
                            _pixels_and_rays(rays, drawn, picked, styles, matrix, (w, h))))
        bar.advance(note=kind)
    title = (f"The whole image casts {counters['camera']:,} camera, {counters['shadow']:,} shadow, "
             f"{counters['reflection']:,} reflected and {counters['transmission']:,} refracted rays")
    grid = panel_grid([panels], title)
    return Drawn(grid, facts)


def _rms(image: np.ndarray, truth: np.ndarray) -> float:
    """RMS difference of two uint8 images in [0, 1], what a display shows."""
    return float(np.sqrt(np.mean((image.astype(np.float64) - truth.astype(np.float64)) ** 2)) / 255.0)


def _secondary(counters: dict[str, int]) -> int:
    return counters["reflection"] + counters["transmission"]


def _rays(counters: dict[str, int]) -> int:
    return counters["camera"] + counters["shadow"] + _secondary(counters)


@slide_figure("whitted-cutoff",
         "The β cut-off (Whitted's adaptive depth) on Whitted's scene: images at three cut-offs with their error "
         "against a converged render (cut-off 1e-5, depth 12), and the secondary rays each cut-off and each fixed "
         "depth costs for its error, from the tracer's counters",
         full={"size": [200, 150], "shown": [0.5, 0.05, 0.001], "cutoffs": [0.5, 0.2, 0.1, 0.05, 0.01, 0.001],
               "depths": [0, 1, 2, 3, 4, 6], "converged": {"min_weight": 1e-5, "max_depth": 12}},
         quick={"size": [64, 48], "cutoffs": [0.5, 0.05, 0.001], "depths": [0, 2]},
         stages=("whitted",), kit=WHITTED_KIT, scenes=("whitted.json",), steps=12)
def _cutoff(bar: Progress, size: list[int], shown: list[float], cutoffs: list[float], depths: list[int],
            converged: dict[str, Any]) -> Drawn:
    data, size_ = scene_data("whitted.json"), (size[0], size[1])
    truth, truth_counters = _whitted(data, size_, **converged)
    bar.advance(note="converged")
    runs: dict[str, list[dict[str, Any]]] = {"cut-off": [], "depth": []}
    images = {}
    for beta in sorted(set(cutoffs) | set(shown), reverse=True):
        image, counters = _whitted(data, size_, min_weight=beta, max_depth=converged["max_depth"])
        runs["cut-off"].append({"value": beta, "error": _rms(image, truth), **counters})
        images[beta] = image
        bar.advance(note=f"β {beta:g}")
    for depth in depths:
        image, counters = _whitted(data, size_, min_weight=0.0, max_depth=depth)
        runs["depth"].append({"value": depth, "error": _rms(image, truth), **counters})
        bar.advance(note=f"depth {depth}")
    by_beta = {r["value"]: r for r in runs["cut-off"]}
    panels = [Panel(images[beta], f"cut-off β ≥ {beta:g}\n{_rays(by_beta[beta]):,} rays, "
                                  f"{_secondary(by_beta[beta]):,} secondary\nRMS error {by_beta[beta]['error']:.4f}")
              for beta in shown]
    grid = panel_grid([panels], "The cut-off: a ray is cast only while its weight β is at least the cut-off")

    def draw(ax: Any) -> None:
        for label, marker, colour in (("cut-off", "o", "tab:red"), ("depth", "s", "tab:blue")):
            points = sorted(runs[label], key=_rays)
            xs = [_rays(p) for p in points]
            ax.plot(xs, [max(p["error"], 1e-5) for p in points], marker=marker, color=colour,
                    label=("β cut-off, depth ≤ %d" % converged["max_depth"]) if label == "cut-off"
                    else "fixed depth, no cut-off")
            for x, p in zip(xs, points):
                text = f"β {p['value']:g}" if label == "cut-off" else f"depth {p['value']}"
                ax.annotate(text, (x, max(p["error"], 1e-5)), xytext=(4, 3), textcoords="offset points", fontsize=7)
        ax.set_yscale("log")
        ax.set_xlabel("rays cast: camera, shadow, reflected and refracted (the tracer's counters)")
        ax.set_ylabel("RMS error against converged")
        ax.set_title(f"{size[0]}×{size[1]}, one ray per pixel; converged: {_rays(truth_counters):,} rays",
                     fontsize=9)
        ax.grid(True, which="both", alpha=0.25)
        ax.legend(fontsize=8)
    plot = axes_plot(grid.shape[1], 330, draw)
    bar.advance(note="plot")
    return Drawn(stacked([grid, plot]), {"converged": truth_counters, **runs})


#: the twelve edges of a box, as pairs of its corners numbered by bits (x: 1, y: 2, z: 4)
BOX_EDGES = [(a, a | bit) for a in range(8) for bit in (1, 2, 4) if not a & bit]


def _node_depths(child: np.ndarray) -> np.ndarray:
    """The depth of every node of a hierarchy (the root's is 0), from its ``child`` array."""
    depth = np.zeros(len(child), dtype=np.int64)
    level = [0]
    while level:
        inner = [n for n in level if child[n] >= 0]
        for n in inner:
            depth[child[n]] = depth[child[n] + 1] = depth[n] + 1
        level = [c for n in inner for c in (child[n], child[n] + 1)]
    return depth


def _draw_boxes(lo: np.ndarray, hi: np.ndarray, matrix: np.ndarray, size: tuple[int, int]) -> Callable[[Any], None]:
    """An overlay that draws boxes (lo, hi) as wireframes, a colour each."""
    from matplotlib import colormaps
    from matplotlib.collections import LineCollection

    def overlay(ax: Any) -> None:
        colours = colormaps["hsv"](np.linspace(0, 1, len(lo), endpoint=False))
        lines, line_colours = [], []
        for k, (a, b) in enumerate(zip(lo, hi)):
            corners = np.array([[(b if i & 1 else a)[0], (b if i & 2 else a)[1], (b if i & 4 else a)[2]]
                                for i in range(8)])
            for i, j in BOX_EDGES:
                line = visible_segment(matrix, corners[i], corners[j], size)
                if line is not None:
                    lines.append(line)
                    line_colours.append(colours[k])
        ax.add_collection(LineCollection(lines, colors=line_colours, linewidths=0.9))
    return overlay


@slide_figure("whitted-hierarchy",
         "The reference's bounding volume hierarchy (W4, binned surface area heuristic) over the rippled torus's "
         "55,296 triangles and the mirror sphere: its boxes three depths deep drawn over the render, with W5's "
         "node visits and primitive tests per camera ray from the tracer's counters",
         full={"size": [320, 240], "depths": [1, 4, 8]}, quick={"size": [64, 48], "depths": [1, 3]},
         stages=("whitted", "hemicube"), kit=WHITTED_KIT, scenes=("rippled-torus.json", "rippled-torus.obj"), steps=3)
def _hierarchy(bar: Progress, size: list[int], depths: list[int]) -> Drawn:
    data, size_ = scene_data("rippled-torus.json"), (size[0], size[1])
    stage, impl = get_stage("whitted"), reference_impl("whitted")
    tree = stage.probes["build_bvh"](impl, scene=data)
    bar.advance(note="W4")
    image, counters = _whitted(data, size_)
    bar.advance(note="render")
    matrix = camera_matrix(parse_scene(data).camera, size_)
    depth = _node_depths(tree["child"])
    leaves = tree["child"] < 0
    panels = []
    for d in depths:
        nodes = np.nonzero(depth == d)[0]
        panels.append(Panel(image, f"depth {d}: {len(nodes)} boxes", _draw_boxes(tree["lo"][nodes], tree["hi"][nodes],
                                                                               matrix, size_)))
    primitives = len(tree["box_lo"])
    per_ray = {k: counters[k] / counters["camera"] for k in ("nodes_visited", "tests")}
    title = (f"{primitives:,} bounded primitives in {len(depth):,} nodes ({int(leaves.sum()):,} leaves, "
             f"{int(depth.max())} deep)\nW5 per camera ray: {per_ray['nodes_visited']:.0f} nodes visited and "
             f"{per_ray['tests']:.0f} primitive tests, against {primitives + 1:,} tests without the hierarchy")
    grid = panel_grid([panels], title)
    bar.advance(note="boxes")
    facts = {"primitives": primitives, "nodes": int(len(depth)), "leaves": int(leaves.sum()), "depth": int(depth.max()),
             "per_camera_ray": per_ray, "counters": counters}
    return Drawn(grid, facts)



@slide_figure("bench-whitted",
         "cs451 bench whitted's time against error, measured small: Whitted's scene at three sizes, two sample counts "
         "and four cut-offs through the bench's own _render, against its converged render (bench.whitted.CONVERGED) "
         "at the largest size; the reference on its numpy path",
         full={"top": [128, 96], "spps": [1, 4], "cutoffs": [0.5, 0.1, 0.01, 0.001]},
         quick={"top": [48, 36], "spps": [1], "cutoffs": [0.5, 0.01]},
         stages=("whitted",), kit=WHITTED_KIT, bench=("whitted",), scenes=("whitted.json",), steps=10)
def _bench_whitted(bar: Progress, top: list[int], spps: list[int], cutoffs: list[float]) -> Drawn:
    bench, impl = bench_module("whitted"), reference_impl("whitted")
    scene = parse_scene(scene_data("whitted.json"), "whitted")
    largest = (top[0], top[1])
    with forced("numpy"):
        converged, _, converged_seconds = bench._render(impl, scene, largest, **bench.CONVERGED)
        bar.advance(note="converged")
        variants = [("size", f"{w}×{h}", (w, h), bench.DEFAULT) for w, h in
                    ((largest[0] // 4, largest[1] // 4), (largest[0] // 2, largest[1] // 2), largest)]
        variants += [("spp", str(s), largest, {**bench.DEFAULT, "spp": s}) for s in spps]
        variants += [("cut-off", f"{c:g}", largest, {**bench.DEFAULT, "min_weight": c}) for c in cutoffs]
        rows = []
        for sweep, value, size, options in variants:
            image, counters, seconds = bench._render(impl, scene, size, **options)
            truth = bench._downsample(converged, size)
            error = float(np.sqrt(np.mean((np.clip(image, 0, 1) - np.clip(truth, 0, 1)) ** 2)))
            rows.append({"sweep": sweep, "value": value, "seconds": seconds, "rms_error": error,
                         "rays": _rays(counters)})
            bar.advance(note=f"{sweep} {value}")
    markers = {"size": "o", "spp": "s", "cut-off": "^"}

    def draw(ax: Any) -> None:
        for sweep, marker in markers.items():
            points = [r for r in rows if r["sweep"] == sweep]
            ax.plot([r["seconds"] for r in points], [r["rms_error"] for r in points], marker=marker, ls=":",
                    label=f"{sweep} ({bench.DEFAULT['spp']} spp, cut-off {bench.DEFAULT['min_weight']:g} unless swept)"
                    if sweep == "size" else sweep)
            for r in points:
                ax.annotate(r["value"], (r["seconds"], r["rms_error"]), xytext=(4, 3), textcoords="offset points",
                            fontsize=7)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("frame time (s), numpy path, this machine")
        ax.set_ylabel("RMS error against converged (linear, clipped)")
        ax.set_title(f"Whitted's scene: time against error (converged: {bench.CONVERGED['spp']} spp, cut-off "
                     f"{bench.CONVERGED['min_weight']:g}, depth {bench.CONVERGED['max_depth']}; "
                     f"{converged_seconds:.2f} s)", fontsize=9)
        ax.grid(True, which="both", alpha=0.25)
        ax.legend(fontsize=7)
    return Drawn(axes_plot(720, 420, draw), {"rows": rows, "converged_seconds": converged_seconds,
                                         "converged": bench.CONVERGED, "top": list(largest)})


