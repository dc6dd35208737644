"""Stage 3, hemi-cube form factors: its interface, and the calls into a student's functions with checks.

The form-factor engine (``cs451/formfactors/``, which stage 4 also uses)
renders hemicubes with the student's tables (H1), views (H2), projections (H3)
and shaders (H4), sums rows with H5 and fixes close pairs with H6; it reaches
them only through the wrappers here, so bad student output becomes a one-line
error. Heavy imports (moderngl) stay inside functions.
"""
from __future__ import annotations

import sys
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from ... import progress, schema
from ...scene import AreaLight, Polygon, Scene
from ...schema import Context, field
from ..base import Out, Probes, Stage, Task, part

TASKS = (
    Task("H1", "delta_form_factors", "Delta form factors", ("resolution",),
         (Out("top", ("resolution", "resolution")), Out("side", ("resolution // 2", "resolution")))),
    Task("H2", "hemicube_views", "The five views", ("center", "normal", "up"), (Out("views", (5, 4, 4)),)),
    Task("H3", "hemicube_projections", "The face projections", ("near", "far"), (Out("projections", (2, 4, 4)),)),
    Task("H4", "item_buffer_shaders", "Item-buffer shaders", (),
         (Out("vertex_source", kind="text"), Out("fragment_source", kind="text"))),
    Task("H5", "form_factor_row", "The row of form factors",
         ("top_items", "side_items", "top_weights", "side_weights", "n_patches"), (Out("row", ("n_patches",)),)),
    Task("H6", "point_polygon_form_factor", "The proximity fix", ("point", "normal", "polygon"), (Out("F", ()),)),
    Task("H7", "tetrahedron_delta_form_factors", "The cubic tetrahedron", ("resolution",),
         (Out("face", ("resolution", "resolution")),), optional=True),
)


@dataclass(frozen=True)
class HemicubeOptions:
    patch: int = field("Index of the patch whose hemicube `cs451 render` shows (patches as cs451.patches.scene_polygons lists them).", 0, schema.non_negative)
    resolution: int = field("Hemicube resolution (cells across the top face; even).", 128, schema.positive)
    view: Literal["itembuffer", "formfactors"] = field(
        "'itembuffer': the hemicube of `patch` unfolded, a colour per patch id; "
        "'formfactors': the scene from the camera, each patch coloured by F from `patch` to it.", "itembuffer")
    rotate: bool = field("Rotate the hemicube about the normal by a seeded random angle.", False)

    def validate(self, ctx: Context) -> None:
        """Refuse an odd resolution, or one below 2: a side face is half as high as the top face is wide."""
        if self.resolution % 2 or self.resolution < 2:
            raise ctx.child("resolution").error(f"must be an even number >= 2, got {self.resolution}")


# --- calling the student's functions, with checks on what they return --------

def call_tables(impl: Any, resolution: int) -> tuple[np.ndarray, np.ndarray]:
    """H1, checked: the top face's delta form factors ``(r, r)`` and a side face's ``(r // 2, r)``."""
    return STAGE.call(impl, "H1", int(resolution))


def call_views(impl: Any, center: np.ndarray, normal: np.ndarray, up: np.ndarray) -> np.ndarray:
    """H2, checked: the five view matrices ``(5, 4, 4)`` of a hemicube at ``center`` facing ``normal``."""
    return STAGE.call(impl, "H2", np.array(center, float), np.array(normal, float), np.array(up, float))


def call_projections(impl: Any, near: float, far: float) -> np.ndarray:
    """H3, checked: the top face's and a side face's projection matrices, ``(2, 4, 4)``."""
    return STAGE.call(impl, "H3", float(near), float(far))


def call_shaders(impl: Any) -> tuple[str, str]:
    """H4, checked: the GLSL vertex and fragment sources that draw an item buffer of patch ids."""
    return STAGE.call(impl, "H4")


def call_row(impl: Any, top_items: np.ndarray, side_items: np.ndarray, top_w: np.ndarray, side_w: np.ndarray,
             n: int) -> np.ndarray:
    """H5, checked: one hemicube's row of form factors ``(n,)``, summed from its item buffers and the tables."""
    return STAGE.call(impl, "H5", top_items, side_items, top_w, side_w, int(n))


def call_contour(impl: Any, point: np.ndarray, normal: np.ndarray, polygon: np.ndarray) -> float:
    """H6, checked: the form factor from a point with ``normal`` to ``polygon``, a float (the proximity fix)."""
    return float(STAGE.call(impl, "H6", np.array(point, float), np.array(normal, float), np.array(polygon, float)))


class _Calls:
    """A stage-3 implementation as the form-factor engine asks for it (:class:`cs451.formfactors.StageCalls`),
    every answer checked by the wrappers above."""

    def __init__(self, impl: Any):
        self.impl = impl

    def tables(self, resolution: int) -> tuple[np.ndarray, np.ndarray]:
        return call_tables(self.impl, resolution)

    def views(self, center: np.ndarray, normal: np.ndarray, up: np.ndarray) -> np.ndarray:
        return call_views(self.impl, center, normal, up)

    def projections(self, near: float, far: float) -> np.ndarray:
        return call_projections(self.impl, near, far)

    def shaders(self) -> tuple[str, str]:
        return call_shaders(self.impl)

    def row(self, top_items: np.ndarray, side_items: np.ndarray, top_weights: np.ndarray, side_weights: np.ndarray,
            n: int) -> np.ndarray:
        return call_row(self.impl, top_items, side_items, top_weights, side_weights, n)

    def contour(self, point: np.ndarray, normal: np.ndarray, polygon: np.ndarray) -> float:
        return call_contour(self.impl, point, normal, polygon)


def calls(impl: Any) -> Any:
    """What the form-factor engine takes: ``HemicubeFormFactors(quads, calls(impl))``."""
    return _Calls(impl)


# --- what a render costs ----------------------------------------------------

#: bytes per hemicube cell (top face and four half sides: 3 r² cells): ids, depth and weights
CELL_BYTES = 16


def hemicube_bytes(resolution: int, batch: int = 1) -> float:
    """Bytes that ``batch`` hemicubes of ``resolution`` hold (3 r² cells each): stages 3 and 4 estimate with it."""
    return float(CELL_BYTES) * 3 * resolution * resolution * batch


def estimate(scene: Scene, size: tuple[int, int] | None = None) -> list:
    """The memory a render needs, from the options alone: one hemicube of ``options.hemicube.resolution``."""
    from ...limits import Cost
    r = STAGE.options(scene).resolution
    return [Cost("options.hemicube.resolution", hemicube_bytes(r), f"a hemicube of resolution {r}")]


# --- rendering --------------------------------------------------------------

def render(scene: Scene, impl: Any, size: tuple[int, int] | None = None, **_: Any) -> np.ndarray:
    """The hemicube of ``options.hemicube.patch`` unfolded (a colour per patch id), or F from it painted on the scene."""
    from ...formfactors import HemicubeFormFactors, formfactor_image, item_buffer_image
    from ...patches import scene_polygons
    opts = STAGE.options(scene)
    quads, _, _ = scene_polygons(scene)
    if opts.patch >= len(quads):
        raise Context(scene.label, "options.hemicube").child("patch").error(
            f"the scene has {len(quads)} patches (0 .. {len(quads) - 1}), got {opts.patch}")
    ff = HemicubeFormFactors(quads, calls(impl), resolution=opts.resolution, rotate=opts.rotate)
    if opts.view == "itembuffer":
        return item_buffer_image(ff, opts.patch, size)
    image = formfactor_image(scene, quads, ff.row(opts.patch), ff.calls, size)
    if not progress.quiet():   # row sums, reciprocity, closure: every run but a --quiet one
        print(f"patch {opts.patch}: {ff.summary()}", file=sys.stderr)
    return image


# --- probes: what the autograder's worker asks a submission for ------------------

PROBES = Probes()


@PROBES.register
def probe_tetrahedron(impl: Any, resolution: int) -> dict[str, np.ndarray]:
    """H7 alone: one face of the cubic tetrahedron ``(r, r)``, for the cell and three-face-sum tests."""
    return {"face": STAGE.call(impl, "H7", int(resolution))}


@PROBES.register
def probe_tables(impl: Any, resolution: int) -> dict[str, np.ndarray]:
    """H1 alone: the top and side tables, ``(r, r)`` and ``(r // 2, r)``, for the cell and sum tests."""
    top, side = call_tables(impl, resolution)
    return {"top": top, "side": side}


@PROBES.register
def probe_views(impl: Any, center: list, normal: list, up: list) -> dict[str, np.ndarray]:
    """H2 alone: the five view matrices ``(5, 4, 4)``, compared with the truth's."""
    return {"views": call_views(impl, np.array(center, float), np.array(normal, float), np.array(up, float))}


@PROBES.register
def probe_projections(impl: Any, near: float, far: float) -> dict[str, np.ndarray]:
    """H3 alone: the top and side projections ``(2, 4, 4)``, compared with the truth's."""
    return {"projections": call_projections(impl, near, far)}


@PROBES.register
def probe_row_from_items(impl: Any, top_items: list, side_items: list, top_weights: list, side_weights: list,
                         n_patches: int) -> dict[str, np.ndarray]:
    """H5 on given random item buffers and the true tables: the row ``(n_patches,)``, a known sum."""
    args = [np.asarray(top_items, dtype=np.uint32), np.asarray(side_items, dtype=np.uint32),
            np.asarray(top_weights, dtype=np.float64), np.asarray(side_weights, dtype=np.float64)]
    return {"row": call_row(impl, *args, int(n_patches))}


@PROBES.register
def probe_contour(impl: Any, point: list, normal: list, polygon: list) -> dict[str, np.ndarray]:
    """H6 alone: the point-to-polygon form factor as a 0-d array ``F``, compared with Lambert's formula."""
    return {"F": np.array(call_contour(impl, np.array(point, float), np.array(normal, float), np.array(polygon, float)))}


def _quads(quads: list) -> np.ndarray:
    from ...patches import as_quads
    return as_quads(quads)


@PROBES.register
def probe_rows(impl: Any, quads: list, rows: list[int], resolution: int = 128, rotate: bool = False,
               proximity: str = "none", seed: int = 0) -> dict[str, np.ndarray]:
    """Rows of the form-factor matrix of ``quads``, everything from the submission (H1-H5, and H6 if asked)."""
    from ...formfactors import HemicubeFormFactors
    ff = HemicubeFormFactors(_quads(quads), calls(impl), resolution=resolution, rotate=rotate, proximity=proximity, seed=seed)
    return {"rows": ff.rows(list(rows))}


@PROBES.register
def probe_hemicube_buffers(impl: Any, quads: list, rows: list[int], resolution: int = 128, rotate: bool = False,
                           seed: int = 0) -> dict[str, np.ndarray]:
    """Trusted inputs of the row tests (run on the reference only): the item buffers of the rows' hemicubes,
    the tables, and the rows before any proximity fix, so that H5's and H6's tests judge H5 or H6 alone."""
    from ...formfactors import HemicubeFormFactors
    ff = HemicubeFormFactors(_quads(quads), calls(impl), resolution=resolution, rotate=rotate, proximity="none", seed=seed)
    tops, sides = ff.item_buffers(rows)
    top_w, side_w = ff.tables
    return {"top_items": tops, "side_items": sides, "top_weights": top_w, "side_weights": side_w,
            "hemicube_rows": ff.rows(list(rows))}


@PROBES.register
def probe_rows_from_buffers(impl: Any, quads: list, rows: list[int], top_items: np.ndarray, side_items: np.ndarray,
                            top_weights: np.ndarray, side_weights: np.ndarray, **_: Any) -> dict[str, np.ndarray]:
    """H5 alone: the rows the submission sums from trusted item buffers and tables (the reference's H1 to H4)."""
    n = len(quads)
    return {"rows": np.stack([call_row(impl, top.copy(), side.copy(), top_weights, side_weights, n)
                              for top, side in zip(top_items, side_items)])}


@PROBES.register
def probe_proximity_rows(impl: Any, quads: list, rows: list[int], hemicube_rows: np.ndarray, resolution: int = 128,
                         rotate: bool = False, seed: int = 0, **_: Any) -> dict[str, np.ndarray]:
    """H6 alone: trusted hemicube rows (the reference's H1 to H5), fixed for close patches with the submission's H6."""
    from ...formfactors import HemicubeFormFactors
    ff = HemicubeFormFactors(_quads(quads), calls(impl), resolution=resolution, rotate=rotate, proximity="contour", seed=seed)
    return {"rows": np.stack([ff.proximity_fixed(i, row) for i, row in zip(rows, hemicube_rows)])}


@PROBES.register
def probe_item_buffer_parts(impl: Any, quads: list, patch: int, resolution: int) -> dict[str, np.ndarray]:
    """The trusted inputs of an item-buffer image test: the views and projections (from the reference)."""
    from ...formfactors import hemicube_inputs
    views, projections, near, far = hemicube_inputs(_quads(quads), calls(impl), patch)
    return {"views": views, "projections": projections}


@PROBES.register
def probe_item_buffer(impl: Any, quads: list, patch: int, resolution: int, **given: np.ndarray) -> dict[str, np.ndarray]:
    """The unfolded item buffer of one hemicube as an image, drawn with the submission's shaders (H4)."""
    from ...formfactors import HemicubeFormFactors, item_buffer_image
    ff = HemicubeFormFactors(_quads(quads), calls(impl), resolution=resolution, rotate=False, proximity="none")
    return {"image": item_buffer_image(ff, int(patch), None, given=given or None)}


def run_demo(module: Any, output: Any, window: bool, frames: int | None, scene: str = "cornell-box",
         size: tuple[int, int] | None = None, screenshot: Any = None) -> list:
    """A patch's five views, unfolded item buffer, delta form factors and row painted on the scene
    (:mod:`cs451.stages.hemicube.demo`)."""
    run = part(__name__, "demo").demo
    return run(module, output, window, frames, scene=scene, size=size, screenshot=screenshot)


#: the demo's keys
DEMO_KEYS = (("← →", "patch"), ("click", "picks a patch (scene or item buffer)"), ("space", "sweep"),
             ("p", "proximity fix (H6)"), ("r", "rotation"), ("+ -", "resolution"), ("q", "quits"))


STAGE = Stage(
    name="hemicube", number=3, title="Hemi-cube form factors", handout="03-hemicube", tasks=TASKS, render=render,
    probes=PROBES, demo=run_demo, options_type=HemicubeOptions, draws=(Polygon, AreaLight), estimate=estimate,
    demo_keys=DEMO_KEYS,
)
