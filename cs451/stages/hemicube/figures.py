"""The hemicube deck's figures: the five views, the item buffer, the delta form factors, a row, and the bench measured small.
"""
from __future__ import annotations

import math
import tempfile
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

from ...bench import bench_module
from ...errors import KitError
from ...imageio import to_uint8
from ...patches import patch_centers, patch_normals, scene_polygons
from ...progress import Progress
from ...scene import parse_scene
from .. import get_stage
from ...slides.registry import Drawn, slide_figure
from ...slides.canvas import (Panel, canvas_pixels, encoded, new_canvas, panel_grid, png_pixels, project, quietly,
                              reference_impl, scene_data)


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
                "cs451.patches", "cs451.drawing", "cs451.viewing", "cs451.gl", "cs451.scene")
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


def flat_corners(quads: np.ndarray, parent: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, ...]:
    """Vertex colours as R5 returns them, but each patch's own corners in its own value: flat patches."""
    return quads.reshape(-1, 3), np.repeat(values, quads.shape[1], axis=0), np.arange(quads.size // 3).reshape(-1, 4)


def _patch_image(scene: Any, quads: np.ndarray, values: np.ndarray, size: tuple[int, int], views: Any) -> np.ndarray:
    """The patches from the scene camera, each flat in its colour ``values`` (linear), drawn by the engine's drawer
    (:func:`cs451.drawing.draw_solution`, which shows B/π: hence the exposure π)."""
    from ...drawing import draw_solution
    from ...viewing import camera_view
    patches = SimpleNamespace(quads=quads, parent=np.arange(len(quads)))
    return draw_solution(scene, flat_corners, patches, values, size, camera_view(scene.camera, views.views), math.pi)


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
    where = to_uint8(_patch_image(box.scene, box.quads, colours, tuple(size), views_of(reference_impl("hemicube"))))
    directions = [_face_direction(v) for v in parts["views"]]
    rows = [[Panel(where, f"the patch (yellow) on the red wall\nof the Cornell box, {len(box.quads)} patches"),
             Panel(top, f"top face: looks along the normal ({directions[0]})\n{resolution} × {resolution} cells")],
            [Panel(side, f"{FACES[k + 1]}: looks toward {directions[k + 1]}\n{resolution} × {resolution // 2} cells")
             for k, side in enumerate(sides)]]
    grid = panel_grid(rows, f"Five views from one patch: together they see the whole hemisphere above it "
                       f"({_patches_seen(parts)} patches)")
    bar.advance(note="panels")
    return Drawn(grid, {"patch": patch, "patches_seen": _patches_seen(parts), "directions": directions,
                        "row_sum": float(parts["hemicube_rows"][0].sum())})


@slide_figure("hemicube-item-buffer",
         "The unfolded item buffer of a patch on the Cornell box's red wall (cs451.formfactors.pictures, from "
         "stage 3's item-buffer probe): every cell holds the id of the patch it sees, drawn in that patch's colour, "
         "beside the scene with every patch in its id's colour",
         full={"split": 4, "resolution": 64, "size": [360, 360], "shooter": SHOOTER},
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
            ax.text(x, y, f"{FACES[face]} ({directions[face]})", color="white", fontsize=7, ha="center",
                    va="center", rotation=90 if face in (3, 4) else 0,
                    bbox={"facecolor": "black", "alpha": 0.55, "pad": 1.5, "edgecolor": "none"})
    panels = [Panel(painted, f"{len(box.quads)} patches, each in its id's colour\n(white: the patch whose hemicube "
                           f"this is)"),
              Panel(unfolded, f"its item buffer unfolded: top in the middle,\neach side against its edge "
                              f"({_patches_seen(parts)} patches seen)", labels)]
    grid = panel_grid([panels], "The item buffer: each cell holds the id of the patch it sees (H4)")
    bar.advance(note="panels")
    return Drawn(grid, {"patch": patch, "patches_seen": _patches_seen(parts), "directions": directions})


@slide_figure("hemicube-delta-weights",
         "The delta form factors of notes eq. 7–9 from the reference's H1 (stage 3's tables probe) as heat maps on "
         "one colour scale: the top face (eq. 7) and a side face (eq. 8–9, one table for all four), with their sum",
         full={"resolution": 32, "size": 300}, quick={"resolution": 16, "size": 128},
         stages=("hemicube",), kit=("cs451.stages.hemicube", "cs451.stages.base"))
def _delta_weights(bar: Progress, resolution: int, size: int) -> Drawn:
    tables = get_stage("hemicube").probes["tables"](reference_impl("hemicube"), resolution)
    top, side = tables["top"], tables["side"]
    vmax = float(max(top.max(), side.max()))
    total = float(top.sum() + 4 * side.sum())
    margin, gap, bar_w, head = 72, 80, 16, 104
    width = margin + size + gap + size + 60 + bar_w + 50
    height = head + size + 50
    fig = new_canvas(width, height)
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
    return Drawn(canvas_pixels(fig), {"resolution": resolution, "sum": total, "vmin": 0.0, "vmax": vmax, "cmap": "viridis",
                                "regions": regions, "top_max": float(top.max()), "side_max": float(side.max())})


@slide_figure("hemicube-row",
         "A row of the form-factor matrix from a patch on the Cornell box's red wall (stage 3's rows probe: H1–H5 "
         "on the engine, no proximity fix), painted on the scene (cs451.formfactors.pictures), with the row sum "
         "over the box closed by its front wall (1 up to the tables' error) and over the open box",
         full={"split": 6, "resolution": 128, "size": [360, 360], "shooter": SHOOTER},
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
    grid = panel_grid([[Panel(image, caption, mark)]], title, min_width=420)
    return Drawn(grid, {"patch": patch, "patches": len(row), "row_sum": sum_closed, "front_wall": front,
                        "open_row_sum": sum_open, "max": float(row.max()), "caption": caption})



@slide_figure("bench-hemicube",
         "cs451 bench hemicube's plot, measured small with its own functions: the closed-form configurations "
         "(bench.hemicube.closed_forms) at resolutions 16 to 128, and the Cornell box's full matrix on its 16 "
         "polygons (bench.hemicube.cornell, no subdivision, no ray casting) against resolution 256",
         full={"resolutions": [16, 32, 64, 128], "reference_resolution": 256, "split": 1},
         quick={"resolutions": [16, 32], "reference_resolution": 64},
         stages=("hemicube",), kit=HEMICUBE_KIT, bench=("hemicube", "meshes"), scenes=("cornell-box.json",), steps=3)
def _bench_hemicube(bar: Progress, resolutions: list[int], reference_resolution: int, split: int) -> Drawn:
    from ...gl import create_context
    bench, impl, ctx = bench_module("hemicube"), reference_impl("hemicube"), create_context()
    forms = quietly(lambda: bench.closed_forms(impl, resolutions, ctx))
    bar.advance(note="closed forms")
    box = quietly(lambda: bench.cornell(impl, resolutions, reference_resolution, split, [], ctx))
    bar.advance(note="Cornell box")
    with tempfile.TemporaryDirectory(prefix="cs451-figure-") as folder:
        bench._plot(Path(folder) / "hemicube.png", forms, box, resolutions)
        image = png_pixels(Path(folder) / "hemicube.png")
    bar.advance(note="plot")
    facts = {"closed_forms": [{k: f[k] for k in ("config", "resolution", "error", "seconds_per_row")} for f in forms],
             "cornell": [{k: h[k] for k in ("resolution", "error", "seconds_matrix")} for h in box["hemicube"]],
             "patches": box["patches"]}
    return Drawn(image, facts)


