"""The hemicube deck's figures: the five views, the item buffer, the delta form factors, a row, and the bench measured small.
"""
from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np

from ... import import_from_kit
from ...errors import KitError
from ...imageio import to_uint8
from ...patches import patch_centers, patch_normals, scene_polygons
from ...progress import Progress
from ...scene import parse_scene
from .. import get_stage
from ...slides.records import declare_record
from ...slides.registry import Drawn, slide_figure
from ...slides.canvas import (MIN_FONT_PT, SCALE, Panel, canvas_pixels, encoded, new_canvas, panel_grid, project,
                              reference_impl, scene_data, text_size)


def views_of(impl: Any) -> Any:
    """A stage-3 implementation's H2 as the engine's camera code asks for it (``calls.views``)."""
    hemicube = get_stage("hemicube")
    return SimpleNamespace(views=lambda center, normal, up: hemicube.call(impl, "H2", center, normal, up))


def camera_matrix(camera: Any, size: tuple[int, int]) -> np.ndarray:
    """Projection · view of a scene camera, as the engine's own pictures place it (:mod:`cs451.viewing`)."""
    from ...viewing import camera_projection, camera_view
    return camera_projection(camera, *size) @ camera_view(camera, views_of(reference_impl("hemicube")).views)



HEMICUBE_KIT = ("cs451.stages.hemicube", "cs451.stages.base", "cs451.formfactors.rows", "cs451.formfactors.atlas",
                "cs451.formfactors.geometry", "cs451.formfactors.pictures", "cs451.formfactors.proximity",
                "cs451.patches", "cs451.viewing", "cs451.gl", "cs451.scene")
#: the item buffer's faces in H2's order
FACES = ("top", "side 1", "side 2", "side 3", "side 4")
#: the patch whose hemicube the figures show: on the red wall (polygon 4), above the blocks, seen by the camera
SHOOTER = {"polygon": 4, "near": [554.0, 420.0, 300.0]}


def _cornell(split: int, closed: bool = False) -> SimpleNamespace:
    """The Cornell box's polygons cut into split × split patches (bench/meshes.py), each with its colour.

    ``closed`` adds the missing front wall (which the camera looks through) as the last polygon, so that every
    hemicube sees something in every direction. Emitters are drawn in the light's colour."""
    scene = parse_scene(scene_data("cornell-box.json"), "cornell-box")
    polygons, names, emission = scene_polygons(scene)
    colours = np.array([scene.material(name).diffuse for name in names], dtype=np.float64)
    lit = emission.max(axis=1) > 0
    colours[lit] = emission[lit] / emission[lit].max()
    if closed:
        polygons = np.concatenate([polygons, _front_wall(polygons)[None]])
        colours = np.concatenate([colours, [[0.6, 0.6, 0.6]]])
    quads, parent = import_from_kit("bench.meshes").subdivide_uniform(polygons, split)
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


def _patch_image(scene: Any, quads: np.ndarray, values: np.ndarray, size: tuple[int, int], views: Any) -> np.ndarray:
    """The patches from the scene camera, each flat in its colour ``values`` (linear), as stage 3's pictures paint
    them (:func:`cs451.formfactors.pictures.paint_patches`)."""
    from ...formfactors.pictures import paint_patches
    from ...viewing import camera_view
    return paint_patches(scene, quads, values, camera_view(scene.camera, views.views), size, scene.image.background)


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
    stage, impl = get_stage("hemicube"), reference_impl("hemicube")
    parts = stage.probes["hemicube_buffers"](impl, box.quads, [patch], resolution=resolution)
    parts.update(stage.probes["item_buffer_parts"](impl, box.quads, patch, resolution))
    return parts


def _patches_seen(parts: dict[str, np.ndarray]) -> int:
    """How many patches a hemicube's item buffers show."""
    ids = np.unique(np.concatenate([parts["top_items"][0].ravel(), parts["side_items"][0].ravel()]))
    return int((ids > 0).sum())


@slide_figure("hemicube-views",
         "The five views of a hemicube (H2, H3, drawn with H4 into the engine's item buffers) standing on a patch "
         "of the Cornell box's red wall: the top face and the four half-height side faces, each cell in the colour "
         "of the patch it sees, beside where the patch is",
         full={"split": 4, "resolution": 64, "scale": 6, "size": [384, 384], "shooter": SHOOTER},
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
    where = to_uint8(_patch_image(box.scene, box.quads, colours, tuple(size), views_of(reference_impl("hemicube"))))
    directions = [_face_direction(v) for v in parts["views"]]
    rows = [[Panel(where, f"the patch (yellow), red wall\n{len(box.quads)} patches"),
             Panel(top, f"top: along the normal ({directions[0]})\n{resolution} × {resolution} cells")],
            [Panel(side, f"{FACES[k + 1]}: toward {directions[k + 1]}\n{resolution} × {resolution // 2} cells")
             for k, side in enumerate(sides)]]
    grid = panel_grid(rows, f"Five views from one patch see the whole hemisphere above it "
                            f"({_patches_seen(parts)} patches)", pad=8)
    bar.advance(note="panels")
    return Drawn(grid, {"patch": patch, "patches_seen": _patches_seen(parts), "directions": directions,
                        "row_sum": float(parts["hemicube_rows"][0].sum())})


@slide_figure("hemicube-item-buffer",
         "The unfolded item buffer of a patch on the Cornell box's red wall (cs451.formfactors.pictures, from "
         "stage 3's item-buffer probe): every cell holds the id of the patch it sees, drawn in that patch's colour, "
         "beside the scene with every patch in its id's colour",
         full={"split": 4, "resolution": 64, "size": [512, 512], "shooter": SHOOTER},
         quick={"resolution": 16, "size": [96, 96]},
         stages=("hemicube",), kit=HEMICUBE_KIT, bench=("meshes",), scenes=("cornell-box.json",), steps=2)
def _item_buffer(bar: Progress, split: int, resolution: int, size: list[int], shooter: dict[str, Any]) -> Drawn:
    from ...formfactors import palette
    stage, impl = get_stage("hemicube"), reference_impl("hemicube")
    box = _cornell(split)
    patch = _shooter(box, shooter)
    cross = stage.probes["item_buffer"](impl, box.quads, patch, resolution)["image"]
    parts = _hemicube_parts(box, patch, resolution)
    bar.advance(note="item buffer")
    scale = max(1, size[0] // cross.shape[1])
    unfolded = np.repeat(np.repeat(to_uint8(cross), scale, axis=0), scale, axis=1)
    colours = palette(np.arange(1, len(box.quads) + 1))
    colours[patch] = 1.0
    painted = to_uint8(_patch_image(box.scene, box.quads, colours, tuple(size), views_of(impl)))
    directions = [_face_direction(v) for v in parts["views"]]
    r = unfolded.shape[0]

    def labels(ax: Any) -> None:
        spots = {0: (r / 2, r / 2), 1: (r / 2, r * 0.06), 2: (r / 2, r * 0.94), 3: (r * 0.94, r / 2),
                 4: (r * 0.06, r / 2)}      # where unfold() puts each face: top in the middle, side k on its edge
        for face, (x, y) in spots.items():
            ax.text(x, y, f"{FACES[face]} ({directions[face]})", color="white", ha="center",
                    va="center", rotation=90 if face in (3, 4) else 0,
                    bbox={"facecolor": "black", "alpha": 0.55, "pad": 1.5, "edgecolor": "none"})
    panels = [Panel(painted, f"{len(box.quads)} patches, each in its id's colour\n(white: this hemicube's patch)"),
              Panel(unfolded, f"its item buffer unfolded: top in the\nmiddle, sides at the edges "
                              f"({_patches_seen(parts)} seen)", labels)]
    grid = panel_grid([panels], "The item buffer: each cell holds the id of the patch it sees (H4)", pad=8)
    bar.advance(note="panels")
    return Drawn(grid, {"patch": patch, "patches_seen": _patches_seen(parts), "directions": directions})


@slide_figure("hemicube-delta-weights",
         "The delta form factors of notes eq. 7–9 from the reference's H1 (stage 3's tables probe) as heat maps on "
         "one colour scale: the top face (eq. 7) and a side face (eq. 8–9, one table for all four), with their sum",
         full={"resolution": 32, "size": 280}, quick={"resolution": 16, "size": 128},
         stages=("hemicube",), kit=("cs451.stages.hemicube", "cs451.stages.base"))
def _delta_weights(bar: Progress, resolution: int, size: int) -> Drawn:
    tables = get_stage("hemicube").probes["tables"](reference_impl("hemicube"), resolution)
    top, side = tables["top"], tables["side"]
    vmax = float(max(top.max(), side.max()))
    total = float(top.sum() + 4 * side.sum())
    margin, gap, bar_w, head = 56, 70, 18, 96
    heading = (f"Delta form factors at resolution {resolution} (ΔA = (2/{resolution})²): top + 4 sides = "
               f"{total:.5f}")
    width = max(margin + size + gap + size + 40 + bar_w + 90, text_size(heading, MIN_FONT_PT + 2, "bold")[0] + 30)
    height = head + size + 50
    fig = new_canvas(width, height)
    regions = {}
    panels = (("top", top, (-1, 1, -1, 1), size, "x", "y", "top face, eq. 7:\nΔF = ΔA / (π (x² + y² + 1)²)",
               [-1, 0, 1]),
              ("side", side, (-1, 1, 0, 1), size // 2, "y", "z", "side face, eq. 8–9:\nΔF = z ΔA / (π (y² + z² + 1)²)",
               [0, 0.5, 1]))
    x = margin
    for key, table, extent, h, xlabel, ylabel, title, yticks in panels:
        y = head + (size - h)          # the side face stands on the same base line as the top face
        ax = fig.add_axes((x / width, 1 - (y + h) / height, size / width, h / height))
        shown = ax.imshow(table, origin="lower", extent=extent, cmap="viridis", vmin=0.0, vmax=vmax,
                          interpolation="nearest", aspect="auto")
        ax.set_xticks([-1, 0, 1])
        ax.set_yticks(yticks)
        ax.set_xlabel(xlabel, labelpad=1)
        ax.set_ylabel(ylabel, labelpad=1)
        ax.set_title(title, linespacing=1.3)
        regions[key] = [v * SCALE for v in (x, y, x + size, y + h)]     # in the PNG's pixels
        x += size + gap
    colourbar = fig.add_axes(((x - gap + 40) / width, 1 - (head + size) / height, bar_w / width, size / height))
    fig.colorbar(shown, cax=colourbar, format="{x:.4f}")
    colourbar.set_title("ΔF")
    fig.text(0.5, 1 - 8 / height, heading, ha="center", va="top", fontsize=MIN_FONT_PT + 2, weight="bold")
    return Drawn(canvas_pixels(fig), {"resolution": resolution, "sum": total, "vmin": 0.0, "vmax": vmax, "cmap": "viridis",
                                "regions": regions, "top_max": float(top.max()), "side_max": float(side.max())})


@slide_figure("hemicube-row",
         "A row of the form-factor matrix from a patch on the Cornell box's red wall (stage 3's rows probe: H1–H5 "
         "on the engine, no proximity fix), painted on the scene (cs451.formfactors.pictures), with the row sum "
         "over the box closed by its front wall (1 up to the tables' error) and over the open box",
         full={"split": 6, "resolution": 128, "size": [600, 600], "shooter": SHOOTER},
         quick={"split": 2, "resolution": 32, "size": [96, 96]},
         stages=("hemicube",), kit=HEMICUBE_KIT, bench=("meshes",), scenes=("cornell-box.json",), steps=3)
def _row(bar: Progress, split: int, resolution: int, size: list[int], shooter: dict[str, Any]) -> Drawn:
    from ...formfactors import formfactor_image
    stage, impl = get_stage("hemicube"), reference_impl("hemicube")
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
    image = encoded(formfactor_image(closed.scene, closed.quads[drawn], row[drawn], views_of(impl), tuple(size)),
                     closed.scene)
    bar.advance(note="painted")
    brightest = int(np.argmax(row))
    matrix = camera_matrix(closed.scene.camera, tuple(size))
    centre = project(matrix, patch_centers(closed.quads[patch:patch + 1]), tuple(size))[0]

    def mark(ax: Any) -> None:
        ax.plot(*centre, "o", ms=9, mfc="none", mec="white", mew=1.5)

    sum_closed, sum_open = float(row.sum()), float(rows["open"].sum())
    caption = (f"Σ_j F_ij = {sum_closed:.4f} over the closed box\n(front wall, not drawn: {front:.4f}); "
               f"open box: {sum_open:.4f}")
    title = (f"One hemicube, one row: F from patch {patch} (circled)\nto each of {len(row)} patches, "
             f"resolution {resolution}\nbrightest: F = {row[brightest]:.4f}; dark blue: F = 0 (not seen)")
    grid = panel_grid([[Panel(image, caption, mark)]], title, pad=8)
    return Drawn(grid, {"patch": patch, "patches": len(row), "row_sum": sum_closed, "front_wall": front,
                        "open_row_sum": sum_open, "max": float(row.max()), "caption": caption})



#: how each method of the hemicube record is drawn: (marker, colour, what its labels count)
METHOD_STYLE = {"hemicube": ("o", "tab:blue", ""), "proximity fix": ("s", "tab:orange", ""),
                "shooter split 4×4": ("^", "tab:green", ""), "ray casting": ("D", "tab:purple", " rays")}


def _rays_label(n: int) -> str:
    return f"{n // 1000}k" if n >= 1000 and n % 1000 == 0 else str(n)


declare_record("hemicube", "Form factors where patches hide each other (the Cornell box, whole and cut 4 × 4): the hemicube "
                           "at resolutions, the proximity fix and the split shooter, and ray casting, time against error "
                           "from the area average", f"{__package__}.bench_occluded")


@slide_figure("bench-hemicube",
         "Form factors where patches hide each other, from the record (slides/records/hemicube.json, made by cs451 "
         "slides record hemicube, never timed while the deck is built): the Cornell box as 16 polygons and cut 4 × 4, "
         "the plain hemicube at resolutions 16 to 512, the proximity fix, the shooter split 4 × 4 and ray casting, "
         "each method's time for the same rows against its error from the area average",
         kit=("cs451.slides.records",), records=("hemicube",))
def _bench_hemicube(bar: Progress) -> Drawn:
    from ...slides.canvas import label_points, plain_log_ticks, plot_row
    from ...slides.records import facts as record_facts, load_record, provenance
    record = load_record("hemicube")
    rows, params = record["rows"], record["params"]
    cases = sorted({r["patches"] for r in rows})
    truth = params["truth"]

    def panel(patches: int) -> Any:
        def draw(ax: Any) -> None:
            for method, (marker, colour, unit) in METHOD_STYLE.items():
                points = sorted((r for r in rows if r["patches"] == patches and r["method"] == method),
                                key=lambda r: r["setting"])
                if not points:
                    continue
                xs, ys = [r["seconds"] for r in points], [r["error"] for r in points]
                ax.plot(xs, ys, marker=marker, color=colour, ms=6, lw=1.4)
                label_points(ax, xs, ys, [_rays_label(r["setting"]) if method == "ray casting" else str(r["setting"])
                                          for r in points], colour)
            noise = truth[str(patches)]["noise"]
            ax.axhline(noise, color="grey", ls="--", lw=1.2)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel(f"seconds for {points[0]['rows']} rows of F" if points else "seconds")
            ax.set_title(f"{patches} patches" + (" (its 16 polygons)" if patches == 16 else
                                                 f" (each polygon cut {rows_of(patches)[0]['subdivision']} × "
                                                 f"{rows_of(patches)[0]['subdivision']})"))
            ax.grid(True, which="both", alpha=0.25)
            ax.margins(x=0.15, y=0.15)
            plain_log_ticks(ax)
        return draw

    def rows_of(patches: int) -> list[dict[str, Any]]:
        return [r for r in rows if r["patches"] == patches]

    draws = [panel(p) for p in cases]
    first = draws[0]

    def with_label(ax: Any) -> None:
        first(ax)
        ax.set_ylabel("mean relative row error")
    draws[0] = with_label
    caster = params["ray_caster"]
    by = "Embree" if params.get("embree") else "the kit's CPU caster"
    legend = [("hemicube, no fix (resolution)", {"color": "tab:blue", "marker": "o"}),
              ("proximity fix (resolution)", {"color": "tab:orange", "marker": "s"}),
              ("shooter split 4×4 (resolution)", {"color": "tab:green", "marker": "^"}),
              (f"ray casting, {by} (rays per patch)", {"color": "tab:purple", "marker": "D"}),
              ("the truth's own noise", {"color": "grey", "ls": "--"})]
    rays = truth[str(cases[0])]["rays_per_patch"]
    note = (f"Error: mean over rows of Σ|F − F*| / ΣF*, F* the area average by ray casting from random points of "
            f"the shooter ({_rays_label(rays)} rays a patch, {by}"
            f"{'' if params.get('embree') else ': Embree is not installed'}). {provenance(record)}.")
    image = plot_row(1160, 240, draws, "Form factors where patches hide each other: time against error", legend,
                     note)
    bar.advance(note="plot")
    table = {str(p): [{k: r[k] for k in ("method", "setting", "seconds", "error")} for r in rows_of(p)]
             for p in cases}
    return Drawn(image, {"table": table, "truth": truth, "ray_caster": caster, **record_facts(record)})
