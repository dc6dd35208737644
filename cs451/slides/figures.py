"""The decks' figures: what the kit's reference draws and measures, made through the stage interfaces, cached.

``render_figure(name, cache)`` returns a PNG; :data:`FIGURES` names them, each with one line that says what
it shows. Every figure is drawn by the reference through its stage's interface (``get_stage(...)``: the
stage's ``render``, its probes, ``Stage.call`` and ``functions_replaced``, its diagrams), the hemicube
engine's pictures (:mod:`cs451.formfactors.pictures`), the engine's drawing (:mod:`cs451.drawing`) and the
benchmarks' own functions (``bench/``, measured small), so a change to the reference changes the slides.

The cache key of a figure is a hash of what made it: its name and parameters, the bundled scene files it
reads, and the source text of the reference packages and kit modules that draw it (this module included).
Change one function of ``reference/hemicube`` and every figure drawn with it is made again; change a
handout and none is. The PNG carries its key and the numbers it shows (a row sum, counters, timings) as
text chunks: :func:`figure_facts` reads them back.

Ray tracing figures run the reference's plain numpy path (``_numpy_path``): it gives the same colours as
the compiled kernels (tests/test_whitted_frame.py), takes well under a second at slide sizes, and never
waits for numba's first compile (~2 minutes on two cores). Not thread-safe: build figures in one thread, or in
processes.
"""
from __future__ import annotations

import contextlib
import copy
import hashlib
import importlib.util
import io
import json
import math
import os
import re
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace
from typing import Any, Callable, Iterator

import numpy as np

from .. import KIT_ROOT
from ..bench import bench_module
from ..errors import KitError
from ..impl import earlier_stage_impl, load_impl
from ..imageio import to_uint8
from ..patches import patch_centers, patch_normals, scene_polygons
from ..progress import Progress
from ..scene import BUNDLED_DIR, parse_scene
from ..solvers import energy
from ..stages import get_stage
from ..stages.base import functions_replaced

#: Where the figures load the reference from (tests point it at an edited copy). The stages' own code loads
#: what it builds on from the kit's reference (:func:`cs451.impl.earlier_stage_impl`): see ``Spec.engine``.
REFERENCE = KIT_ROOT / "reference"
#: Bump to make every figure again (a change of this module alone already does: its source is hashed).
FORMAT = 1
#: Pixels per inch of every matplotlib canvas: figure sizes below are in pixels.
DPI = 100


# --- the registry -------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Drawn:
    """A figure as drawn: the picture (uint8 RGB) and the numbers it shows, kept in the PNG beside it."""
    image: np.ndarray
    facts: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Spec:
    """One figure: what it shows, how it is drawn, at which sizes, and everything whose change makes it again."""
    name: str
    description: str
    draw: Callable[..., Drawn]       # draw(bar, **params) -> Drawn
    full: dict[str, Any]
    quick: dict[str, Any]
    stages: tuple[str, ...] = ()     # reference packages this module loads (from REFERENCE)
    engine: tuple[str, ...] = ()     # reference packages the stages' own code loads (the kit's reference)
    kit: tuple[str, ...] = ()        # kit modules that draw it (dotted names)
    bench: tuple[str, ...] = ()      # benchmark modules it measures with (bench/<name>.py)
    scenes: tuple[str, ...] = ()     # bundled scene files it reads (cs451/scenes/<file>)
    steps: int = 1                   # progress steps, for the bar


_SPECS: dict[str, Spec] = {}


def _figure(name: str, description: str, *, full: dict[str, Any] | None = None, quick: dict[str, Any] | None = None,
            **sources: Any) -> Callable[[Callable[..., Drawn]], Callable[..., Drawn]]:
    """Register a figure's draw function; ``quick`` overrides parameters of ``full`` for the tests' small version."""
    def register(draw: Callable[..., Drawn]) -> Callable[..., Drawn]:
        params = dict(full or {})
        _SPECS[name] = Spec(name, description, draw, params, {**params, **(quick or {})}, **sources)
        return draw
    return register


def _spec(name: str) -> Spec:
    if name not in _SPECS:
        raise KitError(f"unknown figure {name!r} (the figures: {', '.join(_SPECS)})")
    return _SPECS[name]


# --- the cache ------------------------------------------------------------------------------------------

def _module_file(name: str) -> Path:
    spec = importlib.util.find_spec(name)
    if spec is None or spec.origin is None:
        raise KitError(f"figure sources: no module {name!r}")
    return Path(spec.origin)


def _package_files(folder: Path, label: str) -> list[tuple[str, Path]]:
    if not (folder / "__init__.py").is_file():
        raise KitError(f"{folder}: no reference package here (the figures draw with the kit's reference)")
    return [(f"{label}/{p.relative_to(folder).as_posix()}", p) for p in sorted(folder.rglob("*.py"))
            if "__pycache__" not in p.parts]


def figure_sources(name: str) -> list[tuple[str, Path]]:
    """Every file whose text enters figure ``name``'s cache key, labelled: reference packages, kit and bench
    modules, scene files, and this module."""
    spec = _spec(name)
    files = [item for stage in spec.stages for item in _package_files(REFERENCE / stage, f"reference/{stage}")]
    files += [item for stage in spec.engine
              for item in _package_files(earlier_stage_impl(stage), f"kit reference/{stage}")]
    files += [(module, _module_file(module)) for module in (*spec.kit, __name__)]
    files += [(f"bench/{module}.py", KIT_ROOT / "bench" / f"{module}.py") for module in spec.bench]
    files += [(f"scenes/{scene}", BUNDLED_DIR / scene) for scene in spec.scenes]
    return files


def figure_key(name: str, quick: bool = False) -> str:
    """The hash of what makes figure ``name``: its parameters and the text of :func:`figure_sources`."""
    spec = _spec(name)
    digest = hashlib.sha256()
    head = {"format": FORMAT, "figure": name, "quick": bool(quick), "params": spec.quick if quick else spec.full}
    digest.update(json.dumps(head, sort_keys=True, default=str).encode())
    for label, path in figure_sources(name):
        try:
            data = path.read_bytes()
        except OSError as err:
            raise KitError(f"figure {name!r}: cannot read {path} ({err.strerror or err})") from None
        digest.update(f"\n{label}\n{len(data)}\n".encode())
        digest.update(data)
    return digest.hexdigest()


def render_figure(name: str, cache: Path, quick: bool = False) -> Path:
    """The PNG of figure ``name`` in ``cache``: drawn when no PNG there has the key of what makes it now.

    ``quick``: the tests' small version (its own file). A figure drawn again replaces its older PNGs.
    """
    spec = _spec(name)
    key = figure_key(name, quick)
    stem = f"{name}-quick" if quick else name
    cache = Path(cache)
    path = cache / f"{stem}-{key[:16]}.png"
    if path.is_file():
        return path
    bar = Progress(f"figure {name}", spec.steps)
    try:
        drawn = spec.draw(bar, **(spec.quick if quick else spec.full))
    finally:
        bar.close()
    _write_png(path, drawn, spec, key)
    for old in cache.glob(f"{stem}-*.png"):
        if old != path and re.fullmatch(rf"{re.escape(stem)}-[0-9a-f]{{16}}", old.stem):
            old.unlink(missing_ok=True)
    return path


def _write_png(path: Path, drawn: Drawn, spec: Spec, key: str) -> None:
    """Write through a temporary file of our own, so that a reader never sees half a PNG."""
    from PIL import Image, PngImagePlugin

    info = PngImagePlugin.PngInfo()
    info.add_text("Title", spec.name)
    info.add_text("Description", spec.description)
    info.add_text("cs451:key", key)
    info.add_text("cs451:facts", json.dumps(drawn.facts, sort_keys=True, default=float))
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}-", suffix=".png", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as out:
            Image.fromarray(np.ascontiguousarray(drawn.image[..., :3], dtype=np.uint8)).save(out, "PNG", pnginfo=info)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def figure_facts(path: Path) -> dict[str, Any]:
    """The numbers a figure's PNG shows (row sums, counters, timings), and its key, as written with it."""
    from PIL import Image

    with Image.open(path) as image:
        text = dict(getattr(image, "text", {}))
    return {**json.loads(text.get("cs451:facts", "{}")), "key": text.get("cs451:key")}


# --- shared pieces ---------------------------------------------------------------------------------

def _impl(stage: str) -> Any:
    """The reference of ``stage`` (from :data:`REFERENCE`), imported under a private name."""
    folder = REFERENCE / stage
    if not (folder / "__init__.py").is_file():
        raise KitError(f"{folder}: no reference package here (the figures draw with the kit's reference)")
    return load_impl(folder, stage)


def _scene_data(file: str) -> dict[str, Any]:
    """A bundled scene as its JSON dict (to change a field before parsing it)."""
    return json.loads((BUNDLED_DIR / file).read_text())


def _encoded(image: np.ndarray, scene: Any) -> np.ndarray:
    return to_uint8(image, scene.image.exposure, scene.image.srgb)


@contextlib.contextmanager
def _numpy_path(impl: Any) -> Iterator[None]:
    """Within the block the reference tracer keeps to its numpy path whatever the batch size (the switches
    tests/test_whitted_frame.py sets); another implementation runs as it is."""
    bvh = sys.modules.get(f"{impl.__name__}.bvh")
    if bvh is None or not hasattr(bvh, "COMPILED_RAYS") or not hasattr(bvh, "_compiled"):
        yield
        return
    saved = bvh.COMPILED_RAYS, bvh._compiled[0]
    bvh.COMPILED_RAYS, bvh._compiled[0] = 10 ** 12, False
    try:
        yield
    finally:
        bvh.COMPILED_RAYS, bvh._compiled[0] = saved


def _views_of(impl: Any) -> Any:
    """A stage-3 implementation's H2 as the engine's camera code asks for it (``calls.views``)."""
    hemicube = get_stage("hemicube")
    return SimpleNamespace(views=lambda center, normal, up: hemicube.call(impl, "H2", center, normal, up))


def _camera_matrix(camera: Any, size: tuple[int, int]) -> np.ndarray:
    """Projection · view of a scene camera, as the engine's own pictures place it (:mod:`cs451.viewing`)."""
    from ..viewing import camera_projection, camera_view
    return camera_projection(camera, *size) @ camera_view(camera, _views_of(_impl("hemicube")).views)


def _project(matrix: np.ndarray, points: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """Pixel coordinates (x right, y down, pixel centres at integers) of points in front of the camera."""
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    clip = np.c_[points, np.ones(len(points))] @ matrix.T
    ndc = clip[:, :2] / clip[:, 3:4]
    return np.c_[(ndc[:, 0] + 1) / 2 * size[0] - 0.5, (1 - ndc[:, 1]) / 2 * size[1] - 0.5]


def _segment(matrix: np.ndarray, a: np.ndarray, b: np.ndarray, size: tuple[int, int]) -> np.ndarray | None:
    """The part of segment a–b in front of the camera, in pixel coordinates (2, 2), or None if it is all behind."""
    wa, wb = (float(np.r_[p, 1.0] @ matrix[3]) for p in (a, b))
    eps = 1e-6
    if wa <= eps and wb <= eps:
        return None
    if wa <= eps:
        a = a + (b - a) * (eps - wa) / (wb - wa)
    elif wb <= eps:
        b = a + (b - a) * (eps - wa) / (wb - wa)
    return _project(matrix, np.stack([a, b]), size)


def _canvas(width: int, height: int) -> Any:
    """A matplotlib figure of this many pixels, drawn by Agg (no pyplot, no global backend)."""
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    except ImportError:
        raise KitError("the slides' figures draw with matplotlib: pip install -e '.[bench]'") from None
    fig = Figure(figsize=(width / DPI, height / DPI), dpi=DPI, facecolor="white")
    FigureCanvasAgg(fig)
    return fig


def _pixels(fig: Any) -> np.ndarray:
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()


def _png_pixels(path: Path) -> np.ndarray:
    from PIL import Image
    with Image.open(path) as image:
        return np.asarray(image.convert("RGB")).copy()


@dataclass
class Panel:
    """One picture of a grid, its caption, and what to draw over it (``overlay(ax)``, in pixel coordinates)."""
    image: np.ndarray
    caption: str = ""
    overlay: Callable[[Any], None] | None = None


def _grid(rows: list[list[Panel]], title: str = "", pad: int = 10, min_width: int = 150,
          font: float = 9.0) -> np.ndarray:
    """Panels at their own pixel size (no resampling) in rows, each caption above its panel, a title on top."""
    band = 8 + 15 * max(p.caption.count("\n") + 1 for row in rows for p in row)
    cell_w = max(min_width, max(p.image.shape[1] for row in rows for p in row))
    heights = [max(p.image.shape[0] for p in row) for row in rows]
    columns = max(len(row) for row in rows)
    top = 10 + 18 * (title.count("\n") + 1) if title else 0
    width = columns * cell_w + (columns + 1) * pad
    height = top + sum(heights) + len(rows) * band + (len(rows) + 1) * pad
    fig = _canvas(width, height)
    for r, row in enumerate(rows):
        row_x = (columns - len(row)) * (cell_w + pad) // 2           # a shorter row is centred
        for c, panel in enumerate(row):
            h, w = panel.image.shape[:2]
            x = row_x + pad + c * (cell_w + pad) + (cell_w - w) // 2
            y = top + pad + sum(heights[:r]) + r * (band + pad) + band
            ax = fig.add_axes((x / width, 1 - (y + h) / height, w / width, h / height))
            ax.imshow(panel.image, interpolation="nearest")
            ax.set_axis_off()
            if panel.overlay is not None:
                panel.overlay(ax)
            ax.set_xlim(-0.5, w - 0.5)
            ax.set_ylim(h - 0.5, -0.5)
            if panel.caption:
                fig.text((x + w / 2) / width, 1 - (y - 4) / height, panel.caption, ha="center", va="bottom",
                         fontsize=font, linespacing=1.2)
    if title:
        fig.text(0.5, 1 - 6 / height, title, ha="center", va="top", fontsize=font + 2, weight="bold")
    return _pixels(fig)


def _stacked(images: list[np.ndarray], gap: int = 6) -> np.ndarray:
    """Images one above the other, centred on a white page."""
    width = max(i.shape[1] for i in images)
    out = []
    for image in images:
        left = (width - image.shape[1]) // 2
        out.append(np.pad(image, ((0, gap), (left, width - image.shape[1] - left), (0, 0)), constant_values=255))
    return np.vstack(out)[:-gap]


def _plot(width: int, height: int, draw: Callable[[Any], None]) -> np.ndarray:
    """A plot of this many pixels: ``draw(ax)`` on one axes."""
    fig = _canvas(width, height)
    ax = fig.add_subplot(1, 1, 1)
    draw(ax)
    fig.tight_layout()
    return _pixels(fig)


# --- stage 1: the lit sphere ---------------------------------------------------------------------------

SPHERE_KIT = ("cs451.stages.sphere", "cs451.stages.base", "cs451.scene", "cs451.gl", "cs451.imageio")
SPHERE_DIAGRAMS = (*SPHERE_KIT, "cs451.stages._sphere_diagrams", "cs451.demos.frames")


@_figure("sphere-gouraud-vs-phong",
         "The notes' lit sphere shaded per vertex (Gouraud, S5) and per fragment (Phong, S6) at its 32 × 32 "
         "tessellation and at a coarse 12 × 8 one, with their difference",
         full={"size": 260, "tessellations": [[32, 32], [12, 8]]}, quick={"size": 64},
         stages=("sphere",), kit=SPHERE_KIT, scenes=("sphere.json",), steps=4)
def _gouraud_vs_phong(bar: Progress, size: int, tessellations: list[list[int]]) -> Drawn:
    stage, impl = get_stage("sphere"), _impl("sphere")
    rows, facts = [], {}
    for slices, stacks in tessellations:
        data = _scene_data("sphere.json")
        data["objects"][0].update(slices=slices, stacks=stacks)
        scene = parse_scene(data, f"sphere {slices} x {stacks}")
        shaded = {}
        for shading in ("gouraud", "phong"):
            shaded[shading] = _encoded(stage.render(scene, impl, (size, size), shading=shading), scene)
            bar.advance(note=f"{shading} {slices}x{stacks}")
        difference = np.abs(shaded["gouraud"].astype(int) - shaded["phong"].astype(int))
        facts[f"{slices}x{stacks}"] = {"max_difference": int(difference.max()),
                                       "mean_difference": float(difference.mean())}
        rows.append([Panel(shaded["gouraud"], f"Gouraud: lit per vertex (S5)\n{slices} × {stacks} sphere"),
                     Panel(shaded["phong"], f"Phong: lit per fragment (S6)\n{slices} × {stacks} sphere"),
                     Panel(np.clip(difference * 8, 0, 255).astype(np.uint8),
                           f"difference × 8\n(at most {int(difference.max())}/255)")])
    image = _grid(rows, "One sphere, one light: where the lighting equation is evaluated")
    return Drawn(image, facts)


def _sphere_diagram(file: str) -> Drawn:
    return Drawn(get_stage("sphere").diagrams()[file]())


@_figure("sphere-light-spaces",
         "The notes' sphere with its light set after gluLookAt (fixed in the world, as the notes do) and before "
         "it (fixed to the camera), and their difference: the stage's handout diagram",
         engine=("sphere",), kit=SPHERE_DIAGRAMS, scenes=("sphere.json",))
def _light_spaces(bar: Progress) -> Drawn:
    return _sphere_diagram("light-spaces.png")


@_figure("sphere-modelview",
         "The modelview composition: translate, rotate and scale called in three orders on one sphere (the call "
         "made last acts first): the stage's handout diagram",
         engine=("sphere",), kit=SPHERE_DIAGRAMS)
def _modelview(bar: Progress) -> Drawn:
    return _sphere_diagram("modelview-order.png")


# --- stage 2: Whitted ray tracing --------------------------------------------------------------------------

WHITTED_KIT = ("cs451.stages.whitted", "cs451.stages.base", "cs451.tracescene", "cs451.scene", "cs451.viewing",
               "cs451.imageio")
#: how each kind of ray is drawn (colour, line style); shadow rays by what reaches the point
RAY_STYLE = {"camera": ("white", "-"), "reflection": ("#33d6ff", "-"), "refraction": ("#ff5ce1", "-"),
             "lit": ("#ffd21f", "--"), "dimmed": ("#ff9a1f", "--"), "blocked": ("#8a8a8a", ":")}
#: how far a ray that leaves the scene is drawn
MISS_LENGTH = 2.5


def _whitted(data: dict[str, Any], size: tuple[int, int], **options: Any) -> tuple[np.ndarray, dict[str, int]]:
    """A scene traced by the reference through stage 2's render probe: the image (uint8) and the tracer's counters."""
    stage, impl = get_stage("whitted"), _impl("whitted")
    with _numpy_path(impl):
        out = stage.probes["render"](impl, data, list(size), **options)
    counters = {k: int(v) for k, v in out.items() if k != "image"}
    return _encoded(out["image"], parse_scene(data)), counters


def ray_tree(data: dict[str, Any], pixels: list[tuple[int, int]], size: tuple[int, int],
             **options: Any) -> list[dict[str, Any]]:
    """Every ray Whitted's recursion casts for these pixels of an image of ``size``, with its hit.

    W11 (the reference's) traces the pixels' camera rays (W1) while its calls of W5 (closest hit) and W7 (shadow
    rays) are recorded, as the grader records the reference (``functions_replaced``). A ray is a dict: ``kind``
    (camera, reflection, refraction or shadow), ``origin``, ``end`` (its hit, the light, or MISS_LENGTH along a
    miss), ``hit`` (bool), ``parent`` (the index of the ray whose hit cast it), ``depth``, ``material`` at the
    hit, and for a shadow ray ``through`` (the RGB factor of light that gets through).
    """
    from ..tracescene import build
    stage, impl = get_stage("whitted"), _impl("whitted")
    scene = parse_scene(data, "<ray tree>")
    origins, directions = stage.call(impl, "W1", scene.camera, *size)
    picked = [y * size[0] + x for x, y in pixels]
    calls: dict[str, list] = {"W5": [], "W7": []}

    def recording(task: str) -> Callable[[Any], Any]:
        def wrap(own: Any) -> Any:
            def recorded(*args: Any) -> Any:
                out = own(*args)
                calls[task].append((args[1:], out))
                return out
            return recorded
        return wrap

    with _numpy_path(impl), functions_replaced(stage, impl, {task: recording(task) for task in calls}):
        stage.probes["render"](impl, data, [len(picked), 1], origins=origins[picked], directions=directions[picked],
                               **options)
    arrays = build(scene)
    rays: list[dict[str, Any]] = []
    for depth, ((o, d), (t, prim, normals)) in enumerate(calls["W5"]):
        for k in range(len(o)):
            parent, kind = None, "camera"
            if depth:
                parent = _nearest_hit(rays, o[k], depth - 1)
                p = rays[parent]
                facing = p["normal"] if p["direction"] @ p["normal"] < 0 else -p["normal"]
                kind = "reflection" if d[k] @ facing > 0 else "refraction"
            hit = bool(prim[k] >= 0)
            end = o[k] + (t[k] if hit else MISS_LENGTH) * d[k]
            material = arrays.material_names[int(arrays.material_at(prim[k:k + 1], end[None])[0])] if hit else None
            rays.append({"kind": kind, "origin": o[k], "direction": d[k], "end": end, "hit": hit, "normal": normals[k],
                         "parent": parent, "depth": depth, "material": material})
    for (o, targets), through in calls["W7"]:
        for k in range(len(o)):
            parent = _nearest_hit(rays, o[k])
            rays.append({"kind": "shadow", "origin": o[k], "end": np.asarray(targets[k], dtype=np.float64),
                         "hit": False, "parent": parent, "depth": rays[parent]["depth"] + 1, "material": None,
                         "through": np.asarray(through[k], dtype=np.float64)})
    return rays


def _nearest_hit(rays: list[dict[str, Any]], point: np.ndarray, depth: int | None = None) -> int:
    """The ray (of ``depth``) whose hit a spawned ray starts from: the nearest hit point (spawn moves it by 1e-9)."""
    found = [(float(np.linalg.norm(r["end"] - point)), i) for i, r in enumerate(rays)
             if r["hit"] and r["kind"] != "shadow" and (depth is None or r["depth"] == depth)]
    if not found:
        raise KitError("ray tree: a spawned ray starts from no recorded hit")
    return min(found)[1]


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
            line = _segment(matrix, ray["origin"], ray["end"], size)
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


@_figure("whitted-ray-tree",
         "The ray tree of one pixel on Whitted's glass sphere, recorded from the reference's W11 (its W5 and W7 "
         "calls): camera, reflected, refracted and shadow rays and every hit, drawn over the image, over the "
         "scene seen from the side, and as a tree",
         full={"size": [400, 300], "side_size": [400, 300], "pixel": [0.345, 0.6],
               "side_camera": {"eye": [6.5, 3.0, 3.3], "center": [-0.3, 1.0, 3.0], "fovy": 48}},
         quick={"size": [80, 60], "side_size": [80, 60]},
         stages=("whitted", "hemicube"), kit=WHITTED_KIT, scenes=("whitted.json",), steps=3)
def _ray_tree_figure(bar: Progress, size: list[int], side_size: list[int], pixel: list[float],
                     side_camera: dict[str, Any]) -> Drawn:
    data = _scene_data("whitted.json")
    w, h = size
    px = (min(int(pixel[0] * w), w - 1), min(int(pixel[1] * h), h - 1))
    rays = ray_tree(data, [px], (w, h))
    bar.advance(note="ray tree")
    image, _ = _whitted(data, (w, h))
    side = _side_view(data, side_camera)
    side_image, _ = _whitted(side, tuple(side_size))
    bar.advance(note="images")
    scene, side_scene = parse_scene(data), parse_scene(side)
    front = _camera_matrix(scene.camera, (w, h))
    back = _camera_matrix(side_scene.camera, tuple(side_size))
    counts = {kind: sum(r["kind"] == kind for r in rays) for kind in ("camera", "reflection", "refraction", "shadow")}
    first_hit = _project(front, rays[0]["end"], (w, h))[0]

    def at_pixel(ax: Any) -> None:
        _draw_rays(rays, front, (w, h), kinds={"reflection", "refraction", "shadow"})(ax)
        ax.plot(*px, "s", ms=9, mfc="none", mec="white", mew=1.5)
        _legend(ax, ["reflection", "refraction", "lit", "dimmed", "blocked"], SHADOW_LABELS)

    def from_side(ax: Any) -> None:
        _draw_rays(rays, back, tuple(side_size))(ax)
        eye = _project(back, np.asarray(scene.camera.eye), tuple(side_size))[0]
        ax.plot(*eye, "^", ms=8, color="white", mec="black")
        for light in scene.lights:
            ax.plot(*_project(back, np.asarray(light.position), tuple(side_size))[0], "*", ms=12, color="#ffd21f",
                    mec="black")

    panels = [Panel(image, f"pixel ({px[0]}, {px[1]}) of the camera's image: its secondary rays"
                           f"\n(its camera ray is the square: it points into the image)", at_pixel),
              Panel(side_image, "the same rays seen from the side\n(triangle: the eye; dashed: toward the lights)",
                    from_side)]
    grid = _grid([panels], f"One pixel's ray tree: {counts['camera']} camera, {counts['reflection']} reflected, "
                           f"{counts['refraction']} refracted and {counts['shadow']} shadow rays")
    tree = _tree_diagram(rays, grid.shape[1])
    bar.advance(note="tree")
    facts = {"pixel": list(px), "rays": counts, "first_hit_pixel": first_hit.tolist(),
             "materials": [r["material"] for r in rays if r["hit"]]}
    return Drawn(_stacked([grid, tree]), facts)


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
    return _plot(width, 60 * depth + 90, draw)


def _pixels_and_rays(rays: list[dict[str, Any]], kinds: set[str], pixels: list[tuple[int, int]], styles: list[str],
                     matrix: np.ndarray, size: tuple[int, int]) -> Callable[[Any], None]:
    """An overlay: the rays of ``kinds``, a square on each pixel they come from, and a legend of ``styles``."""
    def overlay(ax: Any) -> None:
        _draw_rays(rays, matrix, size, kinds=kinds)(ax)
        for p in pixels:
            ax.plot(*p, "s", ms=8, mfc="none", mec="white", mew=1.4)
        _legend(ax, styles, SHADOW_LABELS)
    return overlay


@_figure("whitted-ray-kinds",
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
    data = _scene_data("whitted.json")
    w, h = size
    image, counters = _whitted(data, (w, h))
    bar.advance(note="image")
    matrix = _camera_matrix(parse_scene(data).camera, (w, h))
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
    grid = _grid([panels], title)
    return Drawn(grid, facts)


def _rms(image: np.ndarray, truth: np.ndarray) -> float:
    """RMS difference of two uint8 images in [0, 1], what a display shows."""
    return float(np.sqrt(np.mean((image.astype(np.float64) - truth.astype(np.float64)) ** 2)) / 255.0)


def _secondary(counters: dict[str, int]) -> int:
    return counters["reflection"] + counters["transmission"]


def _rays(counters: dict[str, int]) -> int:
    return counters["camera"] + counters["shadow"] + _secondary(counters)


@_figure("whitted-cutoff",
         "The β cut-off (Whitted's adaptive depth) on Whitted's scene: images at three cut-offs with their error "
         "against a converged render (cut-off 1e-5, depth 12), and the secondary rays each cut-off and each fixed "
         "depth costs for its error, from the tracer's counters",
         full={"size": [200, 150], "shown": [0.5, 0.05, 0.001], "cutoffs": [0.5, 0.2, 0.1, 0.05, 0.01, 0.001],
               "depths": [0, 1, 2, 3, 4, 6], "converged": {"min_weight": 1e-5, "max_depth": 12}},
         quick={"size": [64, 48], "cutoffs": [0.5, 0.05, 0.001], "depths": [0, 2]},
         stages=("whitted",), kit=WHITTED_KIT, scenes=("whitted.json",), steps=12)
def _cutoff(bar: Progress, size: list[int], shown: list[float], cutoffs: list[float], depths: list[int],
            converged: dict[str, Any]) -> Drawn:
    data, size_ = _scene_data("whitted.json"), (size[0], size[1])
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
    grid = _grid([panels], "The cut-off: a ray is cast only while its weight β is at least the cut-off")

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
    plot = _plot(grid.shape[1], 330, draw)
    bar.advance(note="plot")
    return Drawn(_stacked([grid, plot]), {"converged": truth_counters, **runs})


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
                line = _segment(matrix, corners[i], corners[j], size)
                if line is not None:
                    lines.append(line)
                    line_colours.append(colours[k])
        ax.add_collection(LineCollection(lines, colors=line_colours, linewidths=0.9))
    return overlay


@_figure("whitted-hierarchy",
         "The reference's bounding volume hierarchy (W4, binned surface area heuristic) over the rippled torus's "
         "55,296 triangles and the mirror sphere: its boxes three depths deep drawn over the render, with W5's "
         "node visits and primitive tests per camera ray from the tracer's counters",
         full={"size": [320, 240], "depths": [1, 4, 8]}, quick={"size": [64, 48], "depths": [1, 3]},
         stages=("whitted", "hemicube"), kit=WHITTED_KIT, scenes=("rippled-torus.json", "rippled-torus.obj"), steps=3)
def _hierarchy(bar: Progress, size: list[int], depths: list[int]) -> Drawn:
    data, size_ = _scene_data("rippled-torus.json"), (size[0], size[1])
    stage, impl = get_stage("whitted"), _impl("whitted")
    tree = stage.probes["build_bvh"](impl, scene=data)
    bar.advance(note="W4")
    image, counters = _whitted(data, size_)
    bar.advance(note="render")
    matrix = _camera_matrix(parse_scene(data).camera, size_)
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
    grid = _grid([panels], title)
    bar.advance(note="boxes")
    facts = {"primitives": primitives, "nodes": int(len(depth)), "leaves": int(leaves.sum()), "depth": int(depth.max()),
             "per_camera_ray": per_ray, "counters": counters}
    return Drawn(grid, facts)


# --- stage 3: hemi-cube form factors --------------------------------------------------------------------

HEMICUBE_KIT = ("cs451.stages.hemicube", "cs451.stages.base", "cs451.formfactors.rows", "cs451.formfactors.atlas",
                "cs451.formfactors.geometry", "cs451.formfactors.pictures", "cs451.formfactors.proximity",
                "cs451.patches", "cs451.drawing", "cs451.viewing", "cs451.gl", "cs451.scene")
#: the item buffer's faces in H2's order
FACES = ("top", "side 1", "side 2", "side 3", "side 4")
#: the patch whose hemicube the figures show: on the red wall (polygon 4), above the blocks, seen by the camera
SHOOTER = {"polygon": 4, "near": [554.0, 420.0, 300.0]}


def _cornell(split: int, closed: bool = False) -> SimpleNamespace:
    """The Cornell box's polygons cut into split × split patches (bench/meshes.py), each with its colour.

    ``closed`` adds the missing front wall (which the camera looks through) as the last polygon, so that every
    hemicube sees something in every direction. Emitters are drawn in the light's colour."""
    scene = parse_scene(_scene_data("cornell-box.json"), "cornell-box")
    polygons, names, emission = scene_polygons(scene)
    colours = np.array([scene.material(name).diffuse for name in names], dtype=np.float64)
    lit = emission.max(axis=1) > 0
    colours[lit] = emission[lit] / emission[lit].max()
    if closed:
        polygons = np.concatenate([polygons, _front_wall(polygons)[None]])
        colours = np.concatenate([colours, [[0.6, 0.6, 0.6]]])
    quads, parent = bench_module("meshes").subdivide_uniform(polygons, split)
    return SimpleNamespace(scene=scene, quads=quads, parent=parent, colours=colours[parent],
                           front=len(polygons) - 1 if closed else None)


def _told_apart(box: SimpleNamespace, split: int) -> np.ndarray:
    """The patches' colours, darker on faces turned from the camera's light and in a checkerboard of the patches
    of each polygon, so that flat drawings show faces of one colour and their patches apart."""
    facing = np.abs(patch_normals(box.quads) @ np.array([0.3, 0.8, -0.5]) / np.linalg.norm([0.3, 0.8, -0.5]))
    k = np.arange(len(box.quads)) % (split * split)
    checker = np.where((k // split + k % split) % 2 == 0, 1.0, 0.88)
    return box.colours * ((0.55 + 0.45 * facing) * checker)[:, None]


def _front_wall(polygons: np.ndarray) -> np.ndarray:
    """The quad closing the box where the camera looks in: the polygons' corners in the plane of least z, in order
    around their centre, facing into the box."""
    corners = polygons.reshape(-1, 3)
    front = np.unique(corners[np.isclose(corners[:, 2], corners[:, 2].min())], axis=0)
    if len(front) != 4:
        raise KitError(f"cornell-box: expected 4 corners on its open side, found {len(front)}")
    middle = front.mean(axis=0)
    quad = front[np.argsort(np.arctan2(front[:, 1] - middle[1], front[:, 0] - middle[0]))]
    inward = corners.mean(axis=0) - middle
    return quad if patch_normals(quad[None])[0] @ inward > 0 else quad[::-1]


def _shooter(box: SimpleNamespace, shooter: dict[str, Any]) -> int:
    """The patch of polygon ``shooter["polygon"]`` whose centre is nearest the point ``shooter["near"]``."""
    candidates = np.nonzero(box.parent == shooter["polygon"])[0]
    distance = np.linalg.norm(patch_centers(box.quads[candidates]) - np.asarray(shooter["near"]), axis=1)
    return int(candidates[np.argmin(distance)])


def _flat_corners(quads: np.ndarray, parent: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, ...]:
    """Vertex colours as R5 returns them, but each patch's own corners in its own value: flat patches."""
    return quads.reshape(-1, 3), np.repeat(values, quads.shape[1], axis=0), np.arange(quads.size // 3).reshape(-1, 4)


def _patch_image(scene: Any, quads: np.ndarray, values: np.ndarray, size: tuple[int, int], views: Any) -> np.ndarray:
    """The patches from the scene camera, each flat in its colour ``values`` (linear), drawn by the engine's drawer
    (:func:`cs451.drawing.draw_solution`, which shows B/π: hence the exposure π)."""
    from ..drawing import draw_solution
    from ..viewing import camera_view
    patches = SimpleNamespace(quads=quads, parent=np.arange(len(quads)))
    return draw_solution(scene, _flat_corners, patches, values, size, camera_view(scene.camera, views.views), math.pi)


def _face_direction(view: np.ndarray) -> str:
    """Where a view looks, as the world axis nearest its forward direction ("+y", "−z")."""
    forward = -np.asarray(view)[2, :3]
    axis = int(np.argmax(np.abs(forward)))
    return f"{'+' if forward[axis] > 0 else '−'}{'xyz'[axis]}"


def _ids_in_colours(ids: np.ndarray, colours: np.ndarray, scale: int) -> np.ndarray:
    """An item buffer (rows bottom to top, 0: nothing, j + 1: patch j) shown in the patches' colours, each patch
    outlined, enlarged ``scale`` times, rows top to bottom."""
    ids = np.flipud(np.asarray(ids, dtype=np.int64))
    image = np.vstack([[0.0, 0.0, 0.0], colours])[ids]
    edge = np.zeros(ids.shape, dtype=bool)
    edge[1:] |= ids[1:] != ids[:-1]
    edge[:, 1:] |= ids[:, 1:] != ids[:, :-1]
    image[edge] *= 0.55
    return np.repeat(np.repeat(to_uint8(image), scale, axis=0), scale, axis=1)


def _hemicube_parts(box: SimpleNamespace, patch: int, resolution: int) -> dict[str, np.ndarray]:
    """Patch ``patch``'s hemicube from stage 3's probes (as the grader asks the reference): its five views (H2), its
    item buffers (H1–H4 on the engine's atlas), the tables and its row (H5)."""
    stage, impl = get_stage("hemicube"), _impl("hemicube")
    parts = stage.probes["hemicube_buffers"](impl, box.quads, [patch], resolution=resolution)
    parts.update(stage.probes["item_buffer_parts"](impl, box.quads, patch, resolution))
    return parts


def _patches_seen(parts: dict[str, np.ndarray]) -> int:
    """How many patches a hemicube's item buffers show."""
    ids = np.unique(np.concatenate([parts["top_items"][0].ravel(), parts["side_items"][0].ravel()]))
    return int((ids > 0).sum())


@_figure("hemicube-views",
         "The five views of a hemicube (H2, H3, drawn with H4 into the engine's item buffers) standing on a patch "
         "of the Cornell box's red wall: the top face and the four half-height side faces, each cell in the colour "
         "of the patch it sees, beside where the patch is",
         full={"split": 4, "resolution": 64, "scale": 4, "size": [300, 300], "shooter": SHOOTER},
         quick={"resolution": 16, "scale": 2, "size": [96, 96]},
         stages=("hemicube",), kit=HEMICUBE_KIT, bench=("meshes",), scenes=("cornell-box.json",), steps=2)
def _five_views(bar: Progress, split: int, resolution: int, scale: int, size: list[int],
                shooter: dict[str, Any]) -> Drawn:
    box = _cornell(split)
    patch = _shooter(box, shooter)
    parts = _hemicube_parts(box, patch, resolution)
    bar.advance(note="hemicube")
    colours = _told_apart(box, split)
    top = _ids_in_colours(parts["top_items"][0], colours, scale)
    sides = [_ids_in_colours(side, colours, scale) for side in parts["side_items"][0]]
    colours[patch] = (1.0, 0.9, 0.0)
    where = to_uint8(_patch_image(box.scene, box.quads, colours, tuple(size), _views_of(_impl("hemicube"))))
    directions = [_face_direction(v) for v in parts["views"]]
    rows = [[Panel(where, f"the patch (yellow) on the red wall\nof the Cornell box, {len(box.quads)} patches"),
             Panel(top, f"top face: looks along the normal ({directions[0]})\n{resolution} × {resolution} cells")],
            [Panel(side, f"{FACES[k + 1]}: looks toward {directions[k + 1]}\n{resolution} × {resolution // 2} cells")
             for k, side in enumerate(sides)]]
    grid = _grid(rows, f"Five views from one patch: together they see the whole hemisphere above it "
                       f"({_patches_seen(parts)} patches)")
    bar.advance(note="panels")
    return Drawn(grid, {"patch": patch, "patches_seen": _patches_seen(parts), "directions": directions,
                        "row_sum": float(parts["hemicube_rows"][0].sum())})


@_figure("hemicube-item-buffer",
         "The unfolded item buffer of a patch on the Cornell box's red wall (cs451.formfactors.pictures, from "
         "stage 3's item-buffer probe): every cell holds the id of the patch it sees, drawn in that patch's colour, "
         "beside the scene with every patch in its id's colour",
         full={"split": 4, "resolution": 64, "size": [360, 360], "shooter": SHOOTER},
         quick={"resolution": 16, "size": [96, 96]},
         stages=("hemicube",), kit=HEMICUBE_KIT, bench=("meshes",), scenes=("cornell-box.json",), steps=2)
def _item_buffer(bar: Progress, split: int, resolution: int, size: list[int], shooter: dict[str, Any]) -> Drawn:
    from ..formfactors import palette
    stage, impl = get_stage("hemicube"), _impl("hemicube")
    box = _cornell(split)
    patch = _shooter(box, shooter)
    cross = stage.probes["item_buffer"](impl, box.quads, patch, resolution)["image"]
    parts = _hemicube_parts(box, patch, resolution)
    bar.advance(note="item buffer")
    scale = max(1, size[0] // cross.shape[1])
    unfolded = np.repeat(np.repeat(to_uint8(cross), scale, axis=0), scale, axis=1)
    colours = palette(np.arange(1, len(box.quads) + 1))
    colours[patch] = 1.0
    painted = to_uint8(_patch_image(box.scene, box.quads, colours, tuple(size), _views_of(impl)))
    directions = [_face_direction(v) for v in parts["views"]]
    r = unfolded.shape[0]

    def labels(ax: Any) -> None:
        spots = {0: (r / 2, r / 2), 1: (r / 2, r * 0.06), 2: (r / 2, r * 0.94), 3: (r * 0.94, r / 2),
                 4: (r * 0.06, r / 2)}      # where unfold() puts each face: top in the middle, side k on its edge
        for face, (x, y) in spots.items():
            ax.text(x, y, f"{FACES[face]} ({directions[face]})", color="white", fontsize=7, ha="center",
                    va="center", rotation=90 if face in (3, 4) else 0,
                    bbox={"facecolor": "black", "alpha": 0.55, "pad": 1.5, "edgecolor": "none"})
    panels = [Panel(painted, f"{len(box.quads)} patches, each in its id's colour\n(white: the patch whose hemicube "
                           f"this is)"),
              Panel(unfolded, f"its item buffer unfolded: top in the middle,\neach side against its edge "
                              f"({_patches_seen(parts)} patches seen)", labels)]
    grid = _grid([panels], "The item buffer: each cell holds the id of the patch it sees (H4)")
    bar.advance(note="panels")
    return Drawn(grid, {"patch": patch, "patches_seen": _patches_seen(parts), "directions": directions})


@_figure("hemicube-delta-weights",
         "The delta form factors of notes eq. 7–9 from the reference's H1 (stage 3's tables probe) as heat maps on "
         "one colour scale: the top face (eq. 7) and a side face (eq. 8–9, one table for all four), with their sum",
         full={"resolution": 32, "size": 300}, quick={"resolution": 16, "size": 128},
         stages=("hemicube",), kit=("cs451.stages.hemicube", "cs451.stages.base"))
def _delta_weights(bar: Progress, resolution: int, size: int) -> Drawn:
    tables = get_stage("hemicube").probes["tables"](_impl("hemicube"), resolution)
    top, side = tables["top"], tables["side"]
    vmax = float(max(top.max(), side.max()))
    total = float(top.sum() + 4 * side.sum())
    margin, gap, bar_w, head = 72, 80, 16, 104
    width = margin + size + gap + size + 60 + bar_w + 50
    height = head + size + 50
    fig = _canvas(width, height)
    regions = {}
    panels = (("top", top, (-1, 1, -1, 1), size, "x", "y", "top face, eq. 7:\n"
               r"$\Delta F = \dfrac{\Delta A}{\pi\,(x^2 + y^2 + 1)^2}$"),
              ("side", side, (-1, 1, 0, 1), size // 2, "y", "z", "side face, eq. 8–9:\n"
               r"$\Delta F = \dfrac{z\,\Delta A}{\pi\,(y^2 + z^2 + 1)^2}$"))
    x = margin
    for key, table, extent, h, xlabel, ylabel, title in panels:
        y = head + (size - h)          # the side face stands on the same base line as the top face
        ax = fig.add_axes((x / width, 1 - (y + h) / height, size / width, h / height))
        shown = ax.imshow(table, origin="lower", extent=extent, cmap="viridis", vmin=0.0, vmax=vmax,
                          interpolation="nearest", aspect="auto")
        ax.set_xlabel(xlabel, fontsize=9)
        ax.set_ylabel(ylabel, fontsize=9)
        ax.tick_params(labelsize=8)
        ax.set_title(title, fontsize=9)
        regions[key] = [x, y, x + size, y + h]
        x += size + gap
    colourbar = fig.add_axes(((x - gap + 60) / width, 1 - (head + size) / height, bar_w / width, size / height))
    fig.colorbar(shown, cax=colourbar).ax.tick_params(labelsize=7)
    colourbar.set_title("ΔF", fontsize=8)
    fig.text(0.5, 1 - 8 / height, f"Delta form factors at resolution {resolution} (ΔA = (2/{resolution})²): "
                                  f"top + 4 sides = {total:.5f}", ha="center", va="top", fontsize=10, weight="bold")
    return Drawn(_pixels(fig), {"resolution": resolution, "sum": total, "vmin": 0.0, "vmax": vmax, "cmap": "viridis",
                                "regions": regions, "top_max": float(top.max()), "side_max": float(side.max())})


@_figure("hemicube-row",
         "A row of the form-factor matrix from a patch on the Cornell box's red wall (stage 3's rows probe: H1–H5 "
         "on the engine, no proximity fix), painted on the scene (cs451.formfactors.pictures), with the row sum "
         "over the box closed by its front wall (1 up to the tables' error) and over the open box",
         full={"split": 6, "resolution": 128, "size": [360, 360], "shooter": SHOOTER},
         quick={"split": 2, "resolution": 32, "size": [96, 96]},
         stages=("hemicube",), kit=HEMICUBE_KIT, bench=("meshes",), scenes=("cornell-box.json",), steps=3)
def _row(bar: Progress, split: int, resolution: int, size: list[int], shooter: dict[str, Any]) -> Drawn:
    from ..formfactors import formfactor_image
    stage, impl = get_stage("hemicube"), _impl("hemicube")
    closed, open_ = _cornell(split, closed=True), _cornell(split)
    patch = _shooter(closed, shooter)
    rows = {}
    for label, box in (("closed", closed), ("open", open_)):
        rows[label] = stage.probes["rows"](impl, box.quads, [patch], resolution=resolution, rotate=False,
                                           proximity="none")["rows"][0]
        bar.advance(note=f"{label} box")
    row = rows["closed"]
    drawn = closed.parent != closed.front            # the camera looks in through the front wall: not drawn
    front = float(row[~drawn].sum())
    image = _encoded(formfactor_image(closed.scene, closed.quads[drawn], row[drawn], _views_of(impl), tuple(size)),
                     closed.scene)
    bar.advance(note="painted")
    brightest = int(np.argmax(row))
    matrix = _camera_matrix(closed.scene.camera, tuple(size))
    centre = _project(matrix, patch_centers(closed.quads[patch:patch + 1]), tuple(size))[0]

    def mark(ax: Any) -> None:
        ax.plot(*centre, "o", ms=9, mfc="none", mec="white", mew=1.5)

    sum_closed, sum_open = float(row.sum()), float(rows["open"].sum())
    caption = (f"Σ_j F_ij = {sum_closed:.4f} over the closed box\n(front wall, not drawn: {front:.4f}); "
               f"open box: {sum_open:.4f}")
    title = (f"One hemicube, one row: F from patch {patch} (circled)\nto each of {len(row)} patches, "
             f"resolution {resolution}\nbrightest: F = {row[brightest]:.4f}; dark blue: F = 0 (not seen)")
    grid = _grid([[Panel(image, caption, mark)]], title, min_width=420)
    return Drawn(grid, {"patch": patch, "patches": len(row), "row_sum": sum_closed, "front_wall": front,
                        "open_row_sum": sum_open, "max": float(row.max()), "caption": caption})


# --- stage 4: progressive refinement radiosity ----------------------------------------------------------------

RADIOSITY_KIT = ("cs451.stages.radiosity", "cs451.stages.base", "cs451.solvers", "cs451.patching", "cs451.patches",
                 "cs451.drawing", "cs451.viewing", "cs451.formfactors.rows", "cs451.formfactors.atlas",
                 "cs451.formfactors.geometry", "cs451.formfactors.proximity", "cs451.gl", "cs451.scene",
                 "cs451.imageio")


def _radiosity_system(scene_file: str, patch_size: float, resolution: int) -> tuple[Any, dict[str, np.ndarray]]:
    """A scene's patches (R1) and full form-factor matrix (stage 3's hemicube), as stage 4's system probe gives the
    grader them."""
    data = _scene_data(scene_file)
    system = get_stage("radiosity").probes["system"](_impl("radiosity"), data, patch_size=patch_size,
                                                     resolution=resolution)
    return parse_scene(data, scene_file), system


def _shoot(system: dict[str, np.ndarray], tolerance: float, shots: int = 0,
           on_shot: Callable[..., None] | None = None) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """(B, ΔB, the shooters in order) from the reference's shooting loop (R3, a checked call) on the system's rows,
    stopped at ``tolerance`` or after ``shots`` shots (0: 1000 a patch, as the stage does); ``on_shot`` sees each."""
    F = system["F"]
    return get_stage("radiosity").call(_impl("radiosity"), "R3", lambda i: F[int(i)].copy(), system["areas"].copy(),
                                       system["reflectance"].copy(), system["emission"].copy(), float(tolerance),
                                       int(shots or 1000 * len(F)), 1.0, on_shot)


def _radiosity_image(scene: Any, system: dict[str, np.ndarray], display: np.ndarray, size: tuple[int, int],
                     flat: bool = False) -> np.ndarray:
    """Per-patch radiosities drawn as the stage draws them (radiance B/π, the scene's exposure and encoding), with
    R5's vertex colours (Gouraud) or each patch in its own value (``flat``)."""
    from ..drawing import draw_solution
    stage, impl = get_stage("radiosity"), _impl("radiosity")
    corners = _flat_corners if flat else (lambda quads, parent, values: stage.call(impl, "R5", quads, parent, values))
    patches = SimpleNamespace(quads=system["quads"], parent=system["parent"])
    image = draw_solution(scene, corners, patches, display, size, system["view"], stage.options(scene).exposure)
    return _encoded(image, scene)


@_figure("radiosity-progress",
         "Progressive refinement (the reference's R3 through stage 4's probe) on the Cornell box after 1, 10 and 100 "
         "shots, drawn as B alone and as B + ρ·ambient (R4, the 1988 paper's preview term), with the unshot energy",
         full={"patch_size": 50.0, "resolution": 64, "shots": [1, 10, 100], "size": [220, 220]},
         quick={"patch_size": 140.0, "resolution": 32, "shots": [1, 10], "size": [64, 64]},
         stages=("radiosity",), engine=("hemicube",), kit=RADIOSITY_KIT, scenes=("cornell-box.json",), steps=5)
def _progress(bar: Progress, patch_size: float, resolution: int, shots: list[int], size: list[int]) -> Drawn:
    stage, impl = get_stage("radiosity"), _impl("radiosity")
    scene, system = _radiosity_system("cornell-box.json", patch_size, resolution)
    bar.advance(note="form factors")
    a, rho, emitted = system["areas"], system["reflectance"], energy(system["emission"], system["areas"])
    states: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def on_shot(count: int, i: int, radiosity: np.ndarray, unshot: np.ndarray) -> None:
        if count in shots:
            states[count] = (np.array(radiosity, dtype=np.float64), np.array(unshot, dtype=np.float64))
    _shoot(system, stage.options(scene).tolerance, max(shots), on_shot)
    bar.advance(note="shooting")
    plain, ambient, facts = [], [], {"patches": len(a), "shots": {}}
    for k in shots:
        B, dB = states[k]
        term = stage.probes["ambient"](impl, a, rho, dB)["ambient"]
        left = energy(dB, a) / emitted
        facts["shots"][str(k)] = {"unshot": left, "ambient": term.tolist()}
        plain.append(Panel(_radiosity_image(scene, system, B, tuple(size)),
                           f"after {k} shot{'s' * (k > 1)}: B alone\n{left:.0%} of the light not shot yet"))
        ambient.append(Panel(_radiosity_image(scene, system, B + rho * term, tuple(size)),
                             f"after {k} shot{'s' * (k > 1)}: B + ρ·ambient\nambient {term.mean():.3g}"))
        bar.advance(note=f"{k} shots")
    grid = _grid([plain, ambient], f"Progressive refinement on the Cornell box ({len(a)} patches):\n"
                                         f"the ambient term stands in for the light not shot yet")
    return Drawn(grid, facts)


@_figure("radiosity-gouraud",
         "The converged radiosity of the Cornell box drawn flat (each patch its own B) and Gouraud-shaded from the "
         "vertex colours the reference's R5 averages from the adjoining patches",
         full={"patch_size": 100.0, "resolution": 64, "size": [300, 300]},
         quick={"patch_size": 140.0, "resolution": 32, "size": [64, 64]},
         stages=("radiosity",), engine=("hemicube",), kit=RADIOSITY_KIT, scenes=("cornell-box.json",), steps=2)
def _gouraud(bar: Progress, patch_size: float, resolution: int, size: list[int]) -> Drawn:
    scene, system = _radiosity_system("cornell-box.json", patch_size, resolution)
    B, _, order = _shoot(system, get_stage("radiosity").options(scene).tolerance)
    bar.advance(note="solve")
    panels = [Panel(_radiosity_image(scene, system, B, tuple(size), flat=True),
                    f"flat: each of the {len(B)} patches in its own B"),
              Panel(_radiosity_image(scene, system, B, tuple(size)),
                    "Gouraud: R5's vertex colours (the mean of\nthe adjoining patches), interpolated")]
    grid = _grid([panels], "Displaying a radiosity solution (notes §2.3)")
    bar.advance(note="drawn")
    return Drawn(grid, {"patches": len(B), "shots": len(order)})


# --- the benchmarks, measured small -------------------------------------------------------------------

def _quietly(work: Callable[[], Any]) -> Any:
    """Run a bench function without its printed tables (the figure shows them)."""
    with contextlib.redirect_stdout(io.StringIO()):
        return work()


@_figure("bench-whitted",
         "cs451 bench whitted's time against error, measured small: Whitted's scene at three sizes, two sample counts "
         "and four cut-offs through the bench's own _render, against its converged render (bench.whitted.CONVERGED) "
         "at the largest size; the reference on its numpy path",
         full={"top": [128, 96], "spps": [1, 4], "cutoffs": [0.5, 0.1, 0.01, 0.001]},
         quick={"top": [48, 36], "spps": [1], "cutoffs": [0.5, 0.01]},
         stages=("whitted",), kit=WHITTED_KIT, bench=("whitted",), scenes=("whitted.json",), steps=10)
def _bench_whitted(bar: Progress, top: list[int], spps: list[int], cutoffs: list[float]) -> Drawn:
    bench, impl = bench_module("whitted"), _impl("whitted")
    scene = parse_scene(_scene_data("whitted.json"), "whitted")
    largest = (top[0], top[1])
    with _numpy_path(impl):
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
    return Drawn(_plot(720, 420, draw), {"rows": rows, "converged_seconds": converged_seconds,
                                         "converged": bench.CONVERGED, "top": list(largest)})


@_figure("bench-hemicube",
         "cs451 bench hemicube's plot, measured small with its own functions: the closed-form configurations "
         "(bench.hemicube.closed_forms) at resolutions 16 to 128, and the Cornell box's full matrix on its 16 "
         "polygons (bench.hemicube.cornell, no subdivision, no ray casting) against resolution 256",
         full={"resolutions": [16, 32, 64, 128], "reference_resolution": 256, "split": 1},
         quick={"resolutions": [16, 32], "reference_resolution": 64},
         stages=("hemicube",), kit=HEMICUBE_KIT, bench=("hemicube", "meshes"), scenes=("cornell-box.json",), steps=3)
def _bench_hemicube(bar: Progress, resolutions: list[int], reference_resolution: int, split: int) -> Drawn:
    from ..gl import create_context
    bench, impl, ctx = bench_module("hemicube"), _impl("hemicube"), create_context()
    forms = _quietly(lambda: bench.closed_forms(impl, resolutions, ctx))
    bar.advance(note="closed forms")
    box = _quietly(lambda: bench.cornell(impl, resolutions, reference_resolution, split, [], ctx))
    bar.advance(note="Cornell box")
    with tempfile.TemporaryDirectory(prefix="cs451-figure-") as folder:
        bench._plot(Path(folder) / "hemicube.png", forms, box, resolutions)
        image = _png_pixels(Path(folder) / "hemicube.png")
    bar.advance(note="plot")
    facts = {"closed_forms": [{k: f[k] for k in ("config", "resolution", "error", "seconds_per_row")} for f in forms],
             "cornell": [{k: h[k] for k in ("resolution", "error", "seconds_matrix")} for h in box["hemicube"]],
             "patches": box["patches"]}
    return Drawn(image, facts)


@_figure("bench-radiosity",
         "cs451 bench radiosity's plot, measured small with its own functions: every solver and shooting variant on "
         "the Cornell box at one patch size (bench.radiosity.run_case), error of B against the direct solve over "
         "time with the form factors charged",
         full={"patch_size": 100.0, "resolution": 64}, quick={"patch_size": 140.0, "resolution": 32},
         stages=("radiosity",), engine=("hemicube",), kit=RADIOSITY_KIT, bench=("radiosity", "shooting_orders"),
         scenes=("cornell-box.json",), steps=2)
def _bench_radiosity(bar: Progress, patch_size: float, resolution: int) -> Drawn:
    bench = bench_module("radiosity")
    case = _quietly(lambda: bench.run_case(_impl("radiosity"), "cornell-box", patch_size, resolution))
    bar.advance(note="solvers")
    with tempfile.TemporaryDirectory(prefix="cs451-figure-") as folder:
        bench.plot([case], Path(folder) / "radiosity.png")
        image = _png_pixels(Path(folder) / "radiosity.png")
    bar.advance(note="plot")
    methods = {label: {k: m[k] for k in m if k.startswith(("seconds_to", "rows_to")) or k in ("rows", "shots")}
               for label, m in case["methods"].items()}
    return Drawn(image, {"patches": case["patches"], "methods": methods,
                         "formfactor_seconds_per_row": case["formfactor_seconds_per_row"]})


#: Every figure by name, with one line that says what it shows and how it is made.
FIGURES: dict[str, str] = {name: spec.description for name, spec in _SPECS.items()}
