"""The Whitted deck's figures: ray trees, the kinds of rays, the cut-off, the hierarchy, and the bench measured small.
"""
from __future__ import annotations

import copy
from typing import Any, Callable

import numpy as np

from ...progress import Progress
from ...scene import parse_scene
from .. import get_stage
from ...slides.registry import Drawn, slide_figure
from ...slides.canvas import (Panel, axes_plot, encoded, footer, heading, label_points, panel_grid, plain_log_ticks,
                              project, reference_impl, scene_data, side_by_side, stacked, visible_segment)
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


def legend_entries(styles: list[str], labels: dict[str, str] | None = None) -> list[tuple[str, dict[str, Any]]]:
    """Legend entries (for the figure's footer, on white) of these ray styles; the camera ray in black."""
    labels = labels or {}
    return [(labels.get(st, st), {"color": "black" if st == "camera" else RAY_STYLE[st][0], "ls": RAY_STYLE[st][1],
                                  "lw": 2.5}) for st in styles]


#: the camera ray in a legend: drawn black in the tree, white over the images
CAMERA_LABEL = "camera ray (white over an image)"


SHADOW_LABELS = {"lit": "shadow ray: the light reaches", "dimmed": "shadow ray: through glass",
                 "blocked": "shadow ray: blocked", "reflection": "reflected ray", "refraction": "refracted ray",
                 "camera": "camera ray"}


def _side_view(data: dict[str, Any], camera: dict[str, Any]) -> dict[str, Any]:
    """The same scene seen by another camera."""
    other = copy.deepcopy(data)
    other["camera"] = {**other["camera"], **camera}
    return other


@slide_figure("whitted-ray-tree",
         "The ray tree of one pixel on Whitted's glass sphere, recorded from the reference's W11 (its W5 and W7 "
         "calls): camera, reflected, refracted and shadow rays and every hit, drawn over the image, over the "
         "scene seen from the side, and as a tree",
         full={"size": [640, 480], "side_size": [640, 480], "pixel": [0.345, 0.6],
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
        _draw_rays(rays, front, (w, h), kinds={"reflection", "refraction", "shadow"}, width=2.4)(ax)
        ax.plot(*px, "s", ms=10, mfc="none", mec="white", mew=2)

    def from_side(ax: Any) -> None:
        _draw_rays(rays, back, tuple(side_size), width=2.4)(ax)
        eye = project(back, np.asarray(scene.camera.eye), tuple(side_size))[0]
        ax.plot(*eye, "^", ms=11, color="white", mec="black")
        for light in scene.lights:
            ax.plot(*project(back, np.asarray(light.position), tuple(side_size))[0], "*", ms=16, color="#ffd21f",
                    mec="black")

    panels = [Panel(image, f"pixel ({px[0]}, {px[1]}), the square:\nthe rays from its hits", at_pixel),
              Panel(side_image, "the same rays from the side\n(triangle: the eye; star: a light)", from_side)]
    grid = panel_grid([panels], pad=8)
    tree = _tree_diagram(rays, 430, grid.shape[0] / 2)
    body = side_by_side([grid, tree])
    title = (f"One pixel's ray tree: {counts['camera']} camera, {counts['reflection']} reflected, "
             f"{counts['refraction']} refracted and {counts['shadow']} shadow rays")
    styles = ["camera", "reflection", "refraction", "lit", "dimmed", "blocked"]
    figure = stacked([heading(body.shape[1] / 2, title), body,
                      footer(body.shape[1] / 2, legend_entries(styles, {**SHADOW_LABELS, "camera": CAMERA_LABEL}))],
                     gap=0)
    bar.advance(note="tree")
    facts = {"pixel": list(px), "rays": counts, "first_hit_pixel": first_hit.tolist(),
             "materials": [r["material"] for r in rays if r["hit"]]}
    return Drawn(figure, facts)


def _tree_diagram(rays: list[dict[str, Any]], width: float, height: float) -> np.ndarray:
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
            ax.plot([x0, x[i]], [y0, y], color="black" if style == "camera" else colour, ls=dashes, lw=2.2)
            if ray["kind"] == "shadow":
                ax.plot(x[i], y, "*", ms=12, color=colour, mec="black", mew=0.6)
            elif ray["hit"]:
                ax.plot(x[i], y, "o", ms=8, color="white", mec="black")
                ax.annotate(ray["material"], (x[i], y), xytext=(0, 7), textcoords="offset points", ha="center",
                            va="bottom", bbox={"facecolor": "white", "edgecolor": "none", "pad": 0.5, "alpha": 0.8})
            else:
                ax.annotate("sky", (x[i], y), xytext=(0, -7), textcoords="offset points", ha="center", va="top")
        ax.plot(x[0], 0, "^", ms=11, color="white", mec="black")
        ax.annotate("eye", (x[0], 0), xytext=(9, 0), textcoords="offset points", va="center")
        ax.set_xlim(-0.6, max(next_leaf[0] - 0.4, 0.6))
        ax.set_ylim(-depth - 0.7, 0.6)
        ax.set_yticks([-k for k in range(depth + 1)], [str(k) for k in range(depth + 1)])
        ax.set_ylabel("depth")
        ax.set_xticks([])
        ax.set_title("the same rays as a tree\n(nodes: hits; stars: toward a light)")
        for spine in ("top", "right", "bottom"):
            ax.spines[spine].set_visible(False)
    return axes_plot(width, height, draw)


def _pixels_and_rays(rays: list[dict[str, Any]], kinds: set[str], pixels: list[tuple[int, int]],
                     matrix: np.ndarray, size: tuple[int, int]) -> Callable[[Any], None]:
    """An overlay: the rays of ``kinds`` and a square on each pixel they come from."""
    def overlay(ax: Any) -> None:
        _draw_rays(rays, matrix, size, kinds=kinds, width=2.2)(ax)
        for p in pixels:
            ax.plot(*p, "s", ms=9, mfc="none", mec="white", mew=1.8)
    return overlay


@slide_figure("whitted-ray-kinds",
         "The three kinds of secondary ray from the hits of a few pixels of Whitted's scene, recorded from the "
         "reference's W11: shadow rays (reaching the light, dimmed by glass, blocked), reflected rays off the mirror "
         "and refracted rays through the glass, with the whole image's ray counters",
         full={"size": [600, 450],
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
             "reflection": ({"reflection"}, ["reflection"], "reflected: r = d − 2(d·n)n"),
             "refraction": ({"refraction"}, ["refraction"], "refracted: Snell's law")}
    panels, facts = [], {"image_counters": counters}
    for kind, (drawn, styles, caption) in kinds.items():
        picked = [(min(int(fx * w), w - 1), min(int(fy * h), h - 1)) for fx, fy in pixels[kind]]
        # the shadow panel looks at the camera rays' own hits only (depth 0): the rays of the hits it is about
        rays = ray_tree(data, picked, (w, h), **({"max_depth": 0} if kind == "shadow" else {}))
        shown = [r for r in rays if r["kind"] in drawn]
        facts[kind] = {"pixels": [list(p) for p in picked], "rays": len(shown),
                       "styles": sorted({_shadow_style(r) for r in shown}) if kind == "shadow" else [kind]}
        panels.append(Panel(image, f"{caption}\n{len(shown)} from the {len(picked)} marked pixels",
                            _pixels_and_rays(rays, drawn, picked, matrix, (w, h))))
        bar.advance(note=kind)
    title = (f"The whole image: {counters['camera']:,} camera, {counters['shadow']:,} shadow, "
             f"{counters['reflection']:,} reflected, {counters['transmission']:,} refracted rays")
    grid = panel_grid([panels], title, pad=8,
                      legend=legend_entries(["reflection", "refraction", "lit", "dimmed", "blocked"], SHADOW_LABELS))
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
         "against a converged render (cut-off 1e-5, depth 12), and the rays each cut-off and each fixed "
         "depth costs for its error, from the tracer's counters",
         full={"size": [400, 300], "shown": [0.5, 0.05, 0.001], "cutoffs": [0.5, 0.2, 0.1, 0.05, 0.01, 0.001],
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
    panels = [Panel(images[beta], f"β ≥ {beta:g}: {_rays(by_beta[beta]):,} rays\nRMS error {by_beta[beta]['error']:.4f}")
              for beta in shown]
    grid = panel_grid([panels], pad=8)
    styles = {"cut-off": ("o", "tab:red"), "depth": ("s", "tab:blue")}

    def draw(ax: Any) -> None:
        for label, (marker, colour) in styles.items():
            points = sorted(runs[label], key=_rays)
            xs = [_rays(p) / 1e3 for p in points]
            ys = [max(p["error"], 1e-5) for p in points]
            ax.plot(xs, ys, marker=marker, color=colour, ms=6)
            label_points(ax, xs, ys, [f"{p['value']:g}" if label == "cut-off" else f"depth {p['value']}"
                                      for p in points], colour)
        ax.set_yscale("log")
        ax.set_xlabel("thousand rays cast (the tracer's counters)")
        ax.set_ylabel("RMS error against converged")
        ax.grid(True, which="both", alpha=0.25)
        ax.margins(x=0.1, y=0.15)
        plain_log_ticks(ax, "y")
    plot = axes_plot(480, 300, draw)
    body = side_by_side([grid, plot])
    title = "The cut-off: a ray is cast while its weight β is at least the cut-off"
    legend = [("β cut-off (labelled β), depth ≤ 12", {"color": "tab:red", "marker": "o"}),
              ("fixed depth, no cut-off", {"color": "tab:blue", "marker": "s"})]
    legend[0] = (f"β cut-off (labelled β), depth ≤ {converged['max_depth']}", legend[0][1])
    note = (f"{size[0]}×{size[1]}, one ray per pixel; error against a converged render "
            f"(cut-off {converged['min_weight']:g}, depth {converged['max_depth']}: {_rays(truth_counters):,} rays)")
    figure = stacked([heading(body.shape[1] / 2, title), body, footer(body.shape[1] / 2, legend, note)], gap=0)
    bar.advance(note="plot")
    return Drawn(figure, {"converged": truth_counters, **runs})


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
         full={"size": [640, 480], "depths": [1, 4, 8]}, quick={"size": [64, 48], "depths": [1, 3]},
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
    title = (f"{primitives:,} primitives in {len(depth):,} nodes ({int(leaves.sum()):,} leaves, "
             f"{int(depth.max())} deep)\nper camera ray (W5): {per_ray['nodes_visited']:.0f} nodes visited, "
             f"{per_ray['tests']:.0f} primitive tests; {primitives + 1:,} tests without it")
    grid = panel_grid([panels], title, pad=8)
    bar.advance(note="boxes")
    facts = {"primitives": primitives, "nodes": int(len(depth)), "leaves": int(leaves.sum()), "depth": int(depth.max()),
             "per_camera_ray": per_ray, "counters": counters}
    return Drawn(grid, facts)


from . import figure_bench  # noqa: E402,F401  (the timing figure, drawn from its record, declares itself)
