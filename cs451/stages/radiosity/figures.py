"""The radiosity deck's figures: the progressive solution shot by shot, the Gouraud display, and the bench measured small.
"""
from __future__ import annotations

import tempfile
from pathlib import Path
from types import SimpleNamespace
from typing import Any, Callable

import numpy as np

from ...bench import bench_module
from ...progress import Progress
from ...scene import parse_scene
from ...solvers import energy
from .. import get_stage
from ...slides.registry import Drawn, slide_figure
from ...slides.canvas import Panel, encoded, panel_grid, png_pixels, quietly, reference_impl, scene_data
from ..hemicube.figures import flat_corners


RADIOSITY_KIT = ("cs451.stages.radiosity", "cs451.stages.base", "cs451.solvers", "cs451.patching", "cs451.patches",
                 "cs451.drawing", "cs451.viewing", "cs451.formfactors.rows", "cs451.formfactors.atlas",
                 "cs451.formfactors.geometry", "cs451.formfactors.proximity", "cs451.gl", "cs451.scene",
                 "cs451.imageio", "cs451.stages.hemicube.figures")


def _radiosity_system(scene_file: str, patch_size: float, resolution: int) -> tuple[Any, dict[str, np.ndarray]]:
    """A scene's patches (R1) and full form-factor matrix (stage 3's hemicube), as stage 4's system probe gives the
    grader them."""
    data = scene_data(scene_file)
    system = get_stage("radiosity").probes["system"](reference_impl("radiosity"), data, patch_size=patch_size,
                                                     resolution=resolution)
    return parse_scene(data, scene_file), system


def _shoot(system: dict[str, np.ndarray], tolerance: float, shots: int = 0,
           on_shot: Callable[..., None] | None = None) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """(B, ΔB, the shooters in order) from the reference's shooting loop (R3, a checked call) on the system's rows,
    stopped at ``tolerance`` or after ``shots`` shots (0: 1000 a patch, as the stage does); ``on_shot`` sees each."""
    F = system["F"]
    return get_stage("radiosity").call(reference_impl("radiosity"), "R3", lambda i: F[int(i)].copy(), system["areas"].copy(),
                                       system["reflectance"].copy(), system["emission"].copy(), float(tolerance),
                                       int(shots or 1000 * len(F)), 1.0, on_shot)


def _radiosity_image(scene: Any, system: dict[str, np.ndarray], display: np.ndarray, size: tuple[int, int],
                     flat: bool = False) -> np.ndarray:
    """Per-patch radiosities drawn as the stage draws them (radiance B/π, the scene's exposure and encoding), with
    R5's vertex colours (Gouraud) or each patch in its own value (``flat``)."""
    from ...drawing import draw_solution
    stage, impl = get_stage("radiosity"), reference_impl("radiosity")
    corners = flat_corners if flat else (lambda quads, parent, values: stage.call(impl, "R5", quads, parent, values))
    patches = SimpleNamespace(quads=system["quads"], parent=system["parent"])
    image = draw_solution(scene, corners, patches, display, size, system["view"], stage.options(scene).exposure)
    return encoded(image, scene)


@slide_figure("radiosity-progress",
         "Progressive refinement (the reference's R3 through stage 4's probe) on the Cornell box after 1, 10 and 100 "
         "shots, drawn as B alone and as B + ρ·ambient (R4, the 1988 paper's preview term), with the unshot energy",
         full={"patch_size": 50.0, "resolution": 64, "shots": [1, 10, 100], "size": [220, 220]},
         quick={"patch_size": 140.0, "resolution": 32, "shots": [1, 10], "size": [64, 64]},
         stages=("radiosity",), engine=("hemicube",), kit=RADIOSITY_KIT, scenes=("cornell-box.json",), steps=5)
def _progress(bar: Progress, patch_size: float, resolution: int, shots: list[int], size: list[int]) -> Drawn:
    stage, impl = get_stage("radiosity"), reference_impl("radiosity")
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
    grid = panel_grid([plain, ambient], f"Progressive refinement on the Cornell box ({len(a)} patches):\n"
                                         f"the ambient term stands in for the light not shot yet")
    return Drawn(grid, facts)


@slide_figure("radiosity-gouraud",
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
    grid = panel_grid([panels], "Displaying a radiosity solution (notes §2.3)")
    bar.advance(note="drawn")
    return Drawn(grid, {"patches": len(B), "shots": len(order)})



@slide_figure("bench-radiosity",
         "cs451 bench radiosity's plot, measured small with its own functions: every solver and shooting variant on "
         "the Cornell box at one patch size (bench.radiosity.run_case), error of B against the direct solve over "
         "time with the form factors charged",
         full={"patch_size": 100.0, "resolution": 64}, quick={"patch_size": 140.0, "resolution": 32},
         stages=("radiosity",), engine=("hemicube",), kit=RADIOSITY_KIT, bench=("radiosity", "shooting_orders"),
         scenes=("cornell-box.json",), steps=2)
def _bench_radiosity(bar: Progress, patch_size: float, resolution: int) -> Drawn:
    bench = bench_module("radiosity")
    case = quietly(lambda: bench.run_case(reference_impl("radiosity"), "cornell-box", patch_size, resolution))
    bar.advance(note="solvers")
    with tempfile.TemporaryDirectory(prefix="cs451-figure-") as folder:
        bench.plot([case], Path(folder) / "radiosity.png")
        image = png_pixels(Path(folder) / "radiosity.png")
    bar.advance(note="plot")
    methods = {label: {k: m[k] for k in m if k.startswith(("seconds_to", "rows_to")) or k in ("rows", "shots")}
               for label, m in case["methods"].items()}
    return Drawn(image, {"patches": case["patches"], "methods": methods,
                         "formfactor_seconds_per_row": case["formfactor_seconds_per_row"]})


#: Every figure by name, with one line that says what it shows and how it is made.
