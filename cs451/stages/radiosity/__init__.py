"""Stage 4, progressive refinement radiosity: its interface, and the scaffolding around a student's solver.

This module is the interface: the tasks, the options, the checked calls of a
submission, the probes the grader runs and ``render``. The engine does the rest
on those calls: :mod:`cs451.patching` turns a scene into patches with the
student's subdivision (R1), the hemicube engine of stage 3
(:class:`cs451.formfactors.HemicubeFormFactors`, lazily, one row when a patch
shoots) gives form factors, :mod:`cs451.stages.radiosity.solvers` runs the student's shooting
loop (R2, R3) and ambient term (R4), and :mod:`cs451.stages.radiosity.display` draws the student's
vertex colours (R5) Gouraud-shaded, adding the highlight of glossy materials
(:mod:`cs451.stages.radiosity.highlight`, notes §2.3) on top. The image shows radiance B/π, so it is
directly comparable with a path tracer.
"""
from __future__ import annotations

import contextlib
import math
import sys
from pathlib import Path
from typing import Any, Callable, Iterator

import numpy as np

from ... import patching, viewing
from . import cost, display as drawing, highlight as glossy, solvers   # `display`, `specular`: names used below
from ...patching import Patches
from ...errors import KitError
from .solvers import MatrixRows, Solution, solve_direct, shooting_matrix
from ...scene import AreaLight, Polygon, Scene, parse_scene
from ..base import Out, Probes, Stage, Task, check_returns, part, student_call
from .options import RadiosityOptions
from .shots_seen import ShotsSeen

TASKS = (
    Task("R1", "subdivide", "Subdividing into patches", ("quads", "max_edge"),
         (Out("patches", (None, 4, 3)), Out("parent", ("len(patches)",), kind="i", below="len(quads)"))),
    Task("R2", "shoot", "Shooting one patch", ("i", "row", "areas", "reflectance", "radiosity", "unshot"),
         (Out("radiosity", ("len(areas)", 3)), Out("unshot", ("len(areas)", 3)))),
    Task("R3", "progressive_refinement", "The shooting loop",
         ("row", "areas", "reflectance", "emission", "tolerance", "max_shots", "overshoot", "on_shot"),
         (Out("radiosity", ("len(areas)", 3)), Out("unshot", ("len(areas)", 3)),
          Out("order", (None,), kind="i", below="len(areas)"))),
    Task("R4", "ambient_term", "The ambient term", ("areas", "reflectance", "unshot"), (Out("ambient", (3,)),)),
    Task("R5", "vertex_colors", "Vertex colours", ("quads", "parent", "radiosity"),
         (Out("positions", (None, 3)), Out("colors", ("len(positions)", 3)),
          Out("corners", ("len(quads)", 4), kind="i", below="len(positions)"))),
    Task("R6", "solve_again", "Solving again with the rows already known",
         ("known", "row", "areas", "reflectance", "emission", "tolerance", "max_shots", "overshoot", "on_shot"),
         (Out("radiosity", ("len(areas)", 3)), Out("unshot", ("len(areas)", 3)),
          Out("order", (None,), kind="i", below="len(areas)"))),
    Task("R7", "shoot_largest_first", "The paper's order",
         ("row", "areas", "reflectance", "emission", "tolerance", "max_shots", "overshoot", "on_shot"),
         (Out("radiosity", ("len(areas)", 3)), Out("unshot", ("len(areas)", 3)),
          Out("order", (None,), kind="i", below="len(areas)")), optional=True),
)

SOLVERS = ("progressive", "jacobi", "gauss-seidel", "direct")
#: hemicubes per read-back while shooting: a row asked for is rendered with the rows of the next likely shooters
#: (:class:`cs451.stages.radiosity.solvers.RowsAhead`); measured in ``cs451 bench radiosity`` (rows ahead, and those never used)
ROWS_PER_BATCH = 16
#: ... doubling up to this many: the room shoots 2,381 of 2,408 patches (183 read-backs of 16 became 56)
ROWS_PER_BATCH_MOST = 64
#: a patch blind from its centre (under a block resting on it) shoots from the seeing part of a 3 × 3 grid over it
RESAMPLE_BLIND = 3


# --- calling the student's functions, with checks on what they return ------------

def call_subdivide(impl: Any, quads: np.ndarray, max_edge: float) -> tuple[np.ndarray, np.ndarray]:
    """R1, checked: the patches ``(m, 4, 3)`` of ``quads`` cut to ``max_edge``, and the quad each came from
    ``(m,) int``."""
    return STAGE.call(impl, "R1", np.array(quads, dtype=np.float64), float(max_edge))


def call_shoot(impl: Any, i: int, row: np.ndarray, areas: np.ndarray, reflectance: np.ndarray,
               radiosity: np.ndarray, unshot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """R2 on copies, checked: patch ``i`` shoots its unshot radiosity along ``row``; the new radiosity and unshot,
    ``(n, 3)`` each (the caller's arrays stay as they were)."""
    return STAGE.call(impl, "R2", int(i), row.copy(), areas.copy(), reflectance.copy(), radiosity.copy(), unshot.copy())


def call_ambient(impl: Any, areas: np.ndarray, reflectance: np.ndarray, unshot: np.ndarray) -> np.ndarray:
    """R4 on copies, checked: the ambient term ``(3,)`` of the unshot radiosity, for previews."""
    return STAGE.call(impl, "R4", areas.copy(), reflectance.copy(), unshot.copy())


def call_vertex_colors(impl: Any, quads: np.ndarray, parent: np.ndarray, radiosity: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """R5 on copies, checked: the shared vertices ``(k, 3)``, their colours ``(k, 3)`` and each patch's corners
    ``(m, 4) int``, which the display draws Gouraud-shaded."""
    return STAGE.call(impl, "R5", quads.copy(), parent.copy(), radiosity.copy())


def call_progressive(impl: Any, row: Callable, areas: np.ndarray, reflectance: np.ndarray, emission: np.ndarray,
                     tolerance: float, max_shots: int, overshoot: float, on_shot: Callable | None
                     ) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """R3, checked: the shooting loop on ``row(i)``'s form factors; the radiosity and unshot ``(n, 3)`` and the
    order of shots as a list of ints."""
    return _shooting_call(impl, "R3", (row, areas, reflectance, emission, tolerance, max_shots, overshoot, on_shot))


def call_solve_again(impl: Any, known: dict, row: Callable, areas: np.ndarray, reflectance: np.ndarray,
                 emission: np.ndarray, tolerance: float, max_shots: int, overshoot: float, on_shot: Callable | None
                 ) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """R6, checked: R3's loop, taking rows from ``known`` (patch index to row) and adding those it computes; returns
    what R3 returns. ``known`` is passed as it is, not copied: filling it is the task."""
    return _shooting_call(impl, "R6", (known, row, areas, reflectance, emission, tolerance, max_shots, overshoot,
                                       on_shot))


def _shooting_call(impl: Any, task_id: str, args: tuple) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """R3 or R6: both return R3's ``(radiosity, unshot, order)``."""
    task = STAGE.task(task_id)
    out = student_call(STAGE, impl, task_id, *args)
    if isinstance(out, (tuple, list)) and len(out) == 3 and not isinstance(out[2], np.ndarray):
        try:                              # the order may be any iterable of indices (a list, a generator)
            out = (out[0], out[1], list(out[2]))
        except TypeError:
            pass                          # not iterable: check_returns names it
    radiosity, unshot, order = check_returns(task, out, dict(zip(task.params, args)))
    return radiosity, unshot, [int(i) for i in order]


class _Calls:
    """A stage-4 implementation as the engine's solvers, patching and drawing ask for it, every answer checked."""

    def __init__(self, impl: Any):
        self.impl = impl

    def split(self, quads: np.ndarray, max_edge: float) -> tuple[np.ndarray, np.ndarray]:
        return call_subdivide(self.impl, quads, max_edge)

    def progressive(self, *args: Any) -> tuple[np.ndarray, np.ndarray, list[int]]:
        return call_progressive(self.impl, *args)

    def again(self, *args: Any) -> tuple[np.ndarray, np.ndarray, list[int]]:
        return call_solve_again(self.impl, *args)

    def ambient(self, areas: np.ndarray, reflectance: np.ndarray, unshot: np.ndarray) -> np.ndarray:
        return call_ambient(self.impl, areas, reflectance, unshot)

    def corner_colors(self, quads: np.ndarray, parent: np.ndarray, radiosity: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return call_vertex_colors(self.impl, quads, parent, radiosity)


def calls(impl: Any) -> Any:
    """What the engine's solvers, patching and drawing take from a stage-4 implementation."""
    return _Calls(impl)


# --- the engine, on this stage's calls ------------------------------------------------

def make_patches(scene: Scene, impl: Any, patch_size: float) -> Patches:
    """The scene's polygons, subdivided by the implementation's R1 (:func:`cs451.patching.make_patches`)."""
    return patching.make_patches(scene, calls(impl).split, patch_size)


def solve_progressive(impl: Any, rows: Any, *args: Any, **kwargs: Any) -> Solution:
    """The implementation's shooting loop on ``rows`` (:func:`cs451.stages.radiosity.solvers.solve_progressive`)."""
    return solvers.solve_progressive(calls(impl), rows, *args, **kwargs)


def solve(patches: Patches, impl: Any, opts: RadiosityOptions, rows: Any = None, on_shot: Callable | None = None) -> Solution:
    """Solve with the chosen solver; rows from the hemicube engine unless given (``opts.reciprocity``: every row,
    made reciprocal first, :func:`cs451.stages.radiosity.solvers.solve`)."""
    if rows is None:
        rows = hemicube_formfactors(patches.quads, opts.resolution, opts.proximity, batch=ROWS_PER_BATCH_MOST)
    return solvers.solve(patches, calls(impl), opts, rows, on_shot, rows_ahead=ROWS_PER_BATCH - 1,
                         rows_ahead_most=ROWS_PER_BATCH_MOST - 1)


def camera_view(scene: Scene) -> np.ndarray:
    """World to eye for the scene camera, from the stage-3 implementation's H2 (see :mod:`cs451.viewing`)."""
    from ...viewing import camera_view as view_from
    from .. import hemicube as H

    return view_from(scene.camera, H.calls(STAGE.trusted("hemicube")).views)


def draw_solution(scene: Scene, impl: Any, patches: Patches, display: np.ndarray, size: tuple[int, int] | None,
                  exposure: float = 1.0, drawer: Any = None, view: np.ndarray | None = None,
                  highlight: glossy.Highlight | None = None) -> np.ndarray:
    """The Gouraud-shaded image of per-patch radiosities through the implementation's R5 (:mod:`cs451.stages.radiosity.display`),
    with the glossy materials' highlight (:func:`cs451.stages.radiosity.highlight.highlight`) on top when one is given."""
    return drawing.draw_solution(scene, calls(impl).corner_colors, patches, display, size,
                                 camera_view(scene) if view is None else view, exposure, drawer, highlight)

def hemicube_formfactors(quads: np.ndarray, resolution: int = 128, proximity: str | None = None, ctx: Any = None,
                         batch: int = 256, seed: int = 0) -> Any:
    """Stage 3's hemicube engine over the stage-3 implementation this copy has (lazy, cached rows).

    That is the reference in the kit (see :func:`cs451.impl.earlier_stage_impl`). Pass the GL context you draw with
    as ``ctx`` when you draw while rows are still being computed (the demo): the engine makes its own context current
    for each batch and leaves it so. ``batch`` hemicubes (at most) share a read-back. ``seed`` picks the hemicubes'
    random rotations (another seed: an independent estimate of F). The kit's reference stage-3 code is trusted: on
    a CPU rasteriser each face draws only the patches that can land in it, a polygon's patches as one quad
    (:mod:`cs451.formfactors.grids`), and rows are summed a batch at a time (on the device where it has compute
    shaders), not by H5 per hemicube. A student's own stage-3 package is drawn unculled and summed by its H5.
    """
    from ...formfactors import HemicubeFormFactors
    from ...impl import KIT_ROOT, earlier_stage_impl
    from .. import hemicube as H

    if proximity is None:       # the stage's default, so that `cs451 render` and the grader's systems agree
        proximity = RadiosityOptions.__dataclass_fields__["proximity"].default
    reference = earlier_stage_impl("hemicube").resolve() == (KIT_ROOT / "reference" / "hemicube").resolve()
    return HemicubeFormFactors(quads, H.calls(STAGE.trusted("hemicube")), resolution=resolution, proximity=proximity, ctx=ctx,
                               batch=batch, seed=seed, resample_blind=RESAMPLE_BLIND, trusted=reference)


@contextlib.contextmanager
def shooting_progress(patches: Patches, opts: RadiosityOptions) -> Iterator[Callable | None]:
    """An ``on_shot`` that moves a bar from the emitted energy to the tolerance (on a log scale)."""
    from ...progress import Progress
    emitted = solvers.energy(patches.emission, patches.areas)
    if opts.solver != "progressive" or emitted <= 0:
        yield None
        return
    bar = Progress("radiosity: shooting", 100, unit="%")
    stop = math.log(opts.tolerance)

    def on_shot(shots: int, i: int, radiosity: np.ndarray, unshot: np.ndarray) -> None:
        if shots % 32:
            return
        left = solvers.energy(np.asarray(unshot), patches.areas) / emitted
        done = 100 if left <= opts.tolerance else int(100 * max(0.0, math.log(max(left, 1e-300)) / stop))
        bar.advance(max(0, min(done, 100) - bar.bar.n), note=f"{shots} shots")
    try:
        yield on_shot
    finally:
        bar.close()


def render(scene: Scene, impl: Any, size: tuple[int, int] | None = None, quiet: bool = False,
           **overrides: Any) -> np.ndarray:
    """Subdivide, solve and draw a scene with an implementation; returns linear radiance (h, w, 3).

    Glossy materials get their highlight (``options.radiosity.specular``), prepared before the solve so that a
    refusal comes first. Prints a one-line summary (every counter with ``--verbose``, nothing when ``quiet``)
    and shows the shooting's progress toward the tolerance.
    """
    from ...progress import quiet as quiet_line, verbose, warn
    viewing.import_in_background()          # pyrender (the display's projection) loads while form factors are drawn
    opts = STAGE.options(scene, **overrides)
    patches = make_patches(scene, impl, opts.patch_size)
    gloss = glossy.highlight(scene, patches, opts.specular_samples) if opts.specular else None  # refused before solving
    with shooting_progress(patches, opts) as on_shot:
        sol = solve(patches, impl, opts, on_shot=on_shot)
    text = sol.message if verbose() else sol.summary
    if not sol.converged:
        warn(text)
    elif not (quiet or quiet_line()):
        print(text, file=sys.stderr)
    return draw_solution(scene, impl, patches, sol.display, size, opts.exposure, highlight=gloss)


# --- probes: what the autograder's worker asks a submission for -----------------------

PROBES = Probes()


@PROBES.register
def probe_subdivide(impl: Any, quads: list, max_edge: float) -> dict[str, np.ndarray]:
    """R1 alone on given quads: the patches ``(m, 4, 3)`` and their parents ``(m,)``, against the bilinear grid."""
    patches, parent = call_subdivide(impl, np.asarray(quads, dtype=np.float64), max_edge)
    return {"patches": patches, "parent": parent}


@PROBES.register
def probe_shoot(impl: Any, i: int, F: list, areas: list, reflectance: list, radiosity: list, unshot: list
                ) -> dict[str, np.ndarray]:
    """R2 alone on a small system given whole: patch ``i`` shoots along row ``i`` of ``F``; the new radiosity and
    unshot ``(n, 3)``, compared with the truth's shot."""
    F_ = np.asarray(F, dtype=np.float64)
    B, dB = call_shoot(impl, i, F_[i], np.asarray(areas, float), np.asarray(reflectance, float),
                  np.asarray(radiosity, float), np.asarray(unshot, float))
    return {"radiosity": B, "unshot": dB}


def _system(params: dict, given: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The system to shoot on, as data: a scene's trusted arrays (``given``, from ``probe_system`` on the reference),
    else the parameters. A grading worker has no stage-3 code to compute form factors with."""
    names = ("F", "areas", "reflectance", "emission")
    source = given if "F" in given else params
    if any(source.get(k) is None for k in names):
        raise KitError("this test gives no form factors: a scene test takes the reference's 'system' as its trusted input")
    return tuple(np.asarray(source[k], dtype=np.float64) for k in names)  # type: ignore[return-value]


@PROBES.register
def probe_progressive(impl: Any, tolerance: float, max_shots: int, overshoot: float = 1.0, scene: dict | None = None,
                      patch_size: float = 0.0, resolution: int = 64, F: list | None = None, areas: list | None = None,
                      reflectance: list | None = None, emission: list | None = None, **given: np.ndarray
                      ) -> dict[str, np.ndarray]:
    """The shooting loop on a given system (small hand-worked scenes in the parameters, or a scene's trusted arrays)."""
    F_, a, rho, E = _system({"F": F, "areas": areas, "reflectance": reflectance, "emission": emission}, given)
    rows, seen = MatrixRows(F_), ShotsSeen(E)
    sol = solve_progressive(impl, rows, a, rho, E, tolerance, max_shots, overshoot, use_ambient=False, on_shot=seen)
    return {"radiosity": sol.radiosity, "unshot": sol.unshot, "order": np.asarray(sol.order, dtype=np.int64),
            **seen.outputs(),
            "rows_computed": np.asarray(rows.counters["rows_computed"]),
            "rows_requested": np.asarray(rows.counters["rows_computed"] + rows.counters["rows_cached_hits"]),
            "direct": solve_direct(shooting_matrix(F_, a), rho, E),
            "areas": a, "emission": E, "reflectance": rho}


@PROBES.register
def probe_solve_again(impl: Any, known_rows: list, tolerance: float, max_shots: int, overshoot: float = 1.0,
                  F: list | None = None, areas: list | None = None, reflectance: list | None = None,
                  emission: list | None = None, **given: np.ndarray) -> dict[str, np.ndarray]:
    """R6 on a small system: ``known`` starts with the rows of ``known_rows``; which rows it asks ``row`` for, and
    what ``known`` holds afterwards."""
    F_, a, rho, E = _system({"F": F, "areas": areas, "reflectance": reflectance, "emission": emission}, given)
    known: dict = {int(i): F_[int(i)].copy() for i in known_rows}
    asked: list[int] = []

    def row(i: Any) -> np.ndarray:
        i = int(i)
        if not 0 <= i < len(F_):
            raise KitError(f"R6 solve_again() asked for row {i} of {len(F_)}")
        asked.append(i)
        return F_[i].copy()

    radiosity, unshot, order = call_solve_again(impl, known, row, a.copy(), rho.copy(), E.copy(), float(tolerance),
                                            int(max_shots), float(overshoot), None)
    keys = [k for k in known if isinstance(k, (int, np.integer)) and 0 <= k < len(F_)]
    right = len(keys) == len(known) and all(
        np.shape(known[k]) == (len(F_),) and np.array_equal(np.asarray(known[k], dtype=np.float64), F_[int(k)])
        for k in keys)
    return {"radiosity": radiosity, "unshot": unshot, "order": np.asarray(order, dtype=np.int64),
            "rows_asked": np.asarray(asked, dtype=np.int64), "known_after": np.asarray(keys, dtype=np.int64),
            "known_rows_right": np.asarray(right)}


@PROBES.register
def probe_largest_first(impl: Any, tolerance: float, max_shots: int, overshoot: float = 1.0, **system: Any
                        ) -> dict[str, np.ndarray]:
    """R7 on a small system given in the parameters."""
    F_, a, rho, E = _system(system, {})
    seen = ShotsSeen(E)
    B, dB, order = _shooting_call(impl, "R7", (MatrixRows(F_).row, a, rho, E, tolerance, max_shots, overshoot, seen))
    return {"radiosity": B, "unshot": dB, "order": np.asarray(order, dtype=np.int64), **seen.outputs()}


@PROBES.register
def probe_ambient(impl: Any, areas: list, reflectance: list, unshot: list) -> dict[str, np.ndarray]:
    """R4 alone on given areas, reflectances and unshot radiosity: the ambient term ``(3,)``, against the truth's."""
    return {"ambient": call_ambient(impl, np.asarray(areas, float), np.asarray(reflectance, float), np.asarray(unshot, float))}


@PROBES.register
def probe_vertex_colors(impl: Any, quads: list, parent: list, radiosity: list) -> dict[str, np.ndarray]:
    """R5 alone on given patches: the positions ``(k, 3)``, colours ``(k, 3)`` and corners ``(m, 4)``, for the
    vertex tests."""
    positions, colors, corners = call_vertex_colors(impl, np.asarray(quads, float), np.asarray(parent, dtype=np.int64),
                                               np.asarray(radiosity, float))
    return {"positions": positions, "colors": colors, "corners": corners}


@PROBES.register
def probe_system(impl: Any, scene: dict, patch_size: float = 0.0, resolution: int = 64, **_: Any) -> dict[str, np.ndarray]:
    """Trusted inputs for the scene tests (run on the reference only): patches, colours, the full F and the camera view."""
    sc = parse_scene(scene, "<probe scene>")
    p = make_patches(sc, impl, patch_size)
    F = hemicube_formfactors(p.quads, resolution, STAGE.options(sc).proximity).matrix()   # as `cs451 render` would
    return {"quads": p.quads, "parent": p.parent, "areas": p.areas, "reflectance": p.reflectance,
            "emission": p.emission, "F": np.asarray(F, dtype=np.float64), "view": camera_view(sc)}


@PROBES.register
def probe_solved_system(impl: Any, scene: dict, size: list[int] | None = None, tolerance: float = 1e-3,
                        use_ambient: bool = True, max_shots: int = 0, patch_size: float = 0.0, resolution: int = 64
                        ) -> dict[str, np.ndarray]:
    """Trusted inputs for R5's image tests (run on the reference only): the system, and the per-patch values
    the reference's R3 and R4 display on it, so that an image test judges R5 alone."""
    out = probe_system(impl, scene, patch_size, resolution)
    sol = solve_progressive(impl, MatrixRows(out["F"]), out["areas"], out["reflectance"], out["emission"], tolerance,
                            max_shots, 1.0, use_ambient)
    out["display"] = sol.display
    return out


@PROBES.register
def probe_render(impl: Any, scene: dict, size: list[int], tolerance: float = 1e-3, use_ambient: bool = True,
                 max_shots: int = 0, patch_size: float = 0.0, resolution: int = 64, **given: np.ndarray
                 ) -> dict[str, np.ndarray]:
    """Draw ``scene`` on the trusted patches, form factors and camera view (``given``) with the submission's R5.

    The per-patch values shown come from ``given["display"]`` when the test gives them (the reference's
    R3 and R4), else from the submission's own R3 and R4. Everything stage 3 would compute arrives as data.
    """
    sc = parse_scene(scene, "<probe scene>")
    if "view" not in given or "quads" not in given:
        raise KitError("this test gives no trusted system (the reference's 'solved_system' or 'system'): a grading "
                       "worker has no stage-3 code for the patches' form factors or the camera's view")
    quads, parent = given["quads"], given["parent"]
    p = Patches(quads, parent, given["areas"], given["reflectance"], given["emission"], quads)
    if "display" in given:
        display = given["display"]
    else:
        display = solve_progressive(impl, MatrixRows(given["F"]), p.areas, p.reflectance, p.emission, tolerance,
                                    max_shots, 1.0, use_ambient).display
    image = draw_solution(sc, impl, p, display, (int(size[0]), int(size[1])), STAGE.options(sc).exposure,
                          view=given["view"])
    return {"image": np.clip(image * sc.image.exposure, 0.0, 1.0), "display": display}


def run_demo(module: Any, output: Path, window: bool, frames: int | None) -> list[Path]:
    """B beside B + ambient as the shots go by (:mod:`cs451.stages.radiosity.demo`)."""
    run = part(__name__, "demo").demo
    return run(module, output, window, frames)


def handout_diagrams() -> dict:
    """The handout's picture of the glossy box without and with its highlight (:mod:`cs451.stages.radiosity.diagrams`)."""
    return part(__name__, "diagrams").PICTURES


#: the demo's keys
DEMO_KEYS = (("space", "pauses / resumes"), ("n →", "one shot"), ("r", "starts again"), ("g", "flat patches / Gouraud"),
             ("a", "ambient preview on / off"), ("q", "quits"))


STAGE = Stage(
    name="radiosity", number=4, title="Progressive refinement radiosity", handout="04-radiosity", tasks=TASKS,
    render=render,
    probes=PROBES,
    demo=run_demo, demo_keys=DEMO_KEYS,
    builds_on=("hemicube",),
    options_type=RadiosityOptions,
    draws=(Polygon, AreaLight),
    estimate=cost.estimate,
    diagrams=handout_diagrams,
)

