"""The radiosity deck's figures: the progressive solution shot by shot, the Gouraud display, and the bench measured small.
"""
from __future__ import annotations

from types import SimpleNamespace
from typing import Any, Callable

import numpy as np

from ...progress import Progress
from ...scene import parse_scene
from .solvers import energy
from .. import get_stage
from ...slides.records import declare_record
from ...slides.registry import Drawn, slide_figure
from ...slides.canvas import Panel, encoded, panel_grid, reference_impl, scene_data


RADIOSITY_KIT = ("cs451.stages.radiosity", "cs451.stages.base", "cs451.stages.radiosity.solvers", "cs451.patching", "cs451.patches",
                 "cs451.stages.radiosity.display", "cs451.viewing", "cs451.formfactors.rows", "cs451.formfactors.atlas",
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
    from .display import draw_solution, flat_corners
    stage, impl = get_stage("radiosity"), reference_impl("radiosity")
    corners = flat_corners if flat else (lambda quads, parent, values: stage.call(impl, "R5", quads, parent, values))
    patches = SimpleNamespace(quads=system["quads"], parent=system["parent"])
    image = draw_solution(scene, corners, patches, display, size, system["view"], stage.options(scene).exposure)
    return encoded(image, scene)


@slide_figure("radiosity-progress",
         "Progressive refinement (the reference's R3 through stage 4's probe) on the Cornell box after 1, 10 and 100 "
         "shots, drawn as B alone and as B + ρ·ambient (R4, the 1988 paper's preview term), with the unshot energy",
         full={"patch_size": 50.0, "resolution": 64, "shots": [1, 10, 100], "size": [256, 256]},
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
                           f"{k} shot{'s' * (k > 1)}: B alone\n{left:.0%} not shot yet"))
        ambient.append(Panel(_radiosity_image(scene, system, B + rho * term, tuple(size)),
                             f"{k} shot{'s' * (k > 1)}: B + ρ·ambient\nambient {term.mean():.3g}"))
        bar.advance(note=f"{k} shots")
    grid = panel_grid([plain, ambient], f"The ambient term stands in for the light not shot yet ({len(a)} patches)",
                      pad=8)
    return Drawn(grid, facts)


@slide_figure("radiosity-gouraud",
         "The converged radiosity of the Cornell box drawn flat (each patch its own B) and Gouraud-shaded from the "
         "vertex colours the reference's R5 averages from the adjoining patches",
         full={"patch_size": 100.0, "resolution": 64, "size": [540, 540]},
         quick={"patch_size": 140.0, "resolution": 32, "size": [64, 64]},
         stages=("radiosity",), engine=("hemicube",), kit=RADIOSITY_KIT, scenes=("cornell-box.json",), steps=2)
def _gouraud(bar: Progress, patch_size: float, resolution: int, size: list[int]) -> Drawn:
    scene, system = _radiosity_system("cornell-box.json", patch_size, resolution)
    B, _, order = _shoot(system, get_stage("radiosity").options(scene).tolerance)
    bar.advance(note="solve")
    panels = [Panel(_radiosity_image(scene, system, B, tuple(size), flat=True),
                    f"flat: each of the {len(B)} patches\nin its own B"),
              Panel(_radiosity_image(scene, system, B, tuple(size)),
                    "Gouraud: R5's vertex colours (the mean\nof the adjoining patches), interpolated")]
    grid = panel_grid([panels], "Displaying a radiosity solution (notes §2.3)", pad=8)
    bar.advance(note="drawn")
    return Drawn(grid, {"patches": len(B), "shots": len(order)})



#: how each method of the radiosity record is drawn
METHOD_STYLE = {"gauss-seidel": ("tab:blue", "o"), "sweeps": ("tab:red", ""), "maximum": ("tab:brown", "")}


def _style(method: str) -> tuple[str, str]:
    key = "gauss-seidel" if method.startswith("Gauss") else "maximum" if "largest" in method else "sweeps"
    return METHOD_STYLE[key]


def first_below(points: list[dict[str, Any]], target: float) -> dict[str, Any] | None:
    """The first point of a curve at or below ``target`` error."""
    return next((p for p in points if p["error"] <= target), None)


declare_record("radiosity", "Solving the Cornell box (patches of 50): Gauss-Seidel on the full matrix against progressive "
                            "shooting in the handout's order and in the paper's largest-first order, error and unshot energy "
                            "against time with the form factors charged", f"{__package__}.bench_record")


@slide_figure("bench-radiosity",
         "Solving the Cornell box, from the record (slides/records/radiosity.json, made by cs451 slides record "
         "radiosity, never timed while the deck is built): Gauss-Seidel on the full matrix against progressive "
         "shooting in the handout's order and largest first, the error of B against the direct solve over time with "
         "the form factors charged, and the unshot energy shot by shot",
         kit=("cs451.slides.records",), records=("radiosity",))
def _bench_radiosity(bar: Progress) -> Drawn:
    from ...slides.canvas import plain_log_ticks, plot_row
    from ...slides.records import facts as record_facts, load_record, provenance
    record = load_record("radiosity")
    rows, params = record["rows"], record["params"]
    methods = list(dict.fromkeys(r["method"] for r in rows))
    curves = {m: [r for r in rows if r["method"] == m] for m in methods}
    floor = 1e-6

    def against_time(ax: Any) -> None:
        for method, points in curves.items():
            colour, marker = _style(method)
            ax.plot([p["seconds"] for p in points], [max(p["error"], floor) for p in points], color=colour,
                    marker=marker, ms=4, lw=1.8)
        gs = next((points for method, points in curves.items() if method.startswith("Gauss")), None)
        if gs:
            ax.axvline(gs[0]["seconds"], color="tab:blue", ls=":", lw=1.2)
            ax.annotate(f"all {params['patches']} rows\ncomputed", (gs[0]["seconds"], 0.97),
                        xycoords=ax.get_xaxis_transform(), xytext=(-6, 0), textcoords="offset points", ha="right",
                        va="top", color="tab:blue")
        ax.axhline(0.01, color="grey", ls="--", lw=1)
        ax.set_yscale("log")
        ax.set_xlim(left=0)
        ax.set_xlabel("seconds: form factors + solver")
        ax.set_ylabel("relative error of B")
        ax.set_title("error against time")
        ax.grid(True, which="both", alpha=0.25)
        plain_log_ticks(ax)

    def against_shots(ax: Any) -> None:
        for method, points in curves.items():
            if method.startswith("Gauss"):
                continue
            colour, _ = _style(method)
            shown = [p for p in points if p["step"] > 0 and p["unshot"] is not None]
            ax.plot([p["step"] for p in shown], [p["unshot"] for p in shown], color=colour, lw=1.8)
        ax.axvline(params["patches"], color="grey", ls=":", lw=1.2)
        ax.annotate(f"{params['patches']} shots:\none a patch", (params["patches"], 0.03),
                    xycoords=ax.get_xaxis_transform(), xytext=(-6, 0), textcoords="offset points", ha="right",
                    va="bottom", color="grey")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("shots")
        ax.set_ylabel("unshot energy")
        ax.set_title("unshot energy, shot by shot")
        ax.grid(True, which="both", alpha=0.25)
        plain_log_ticks(ax)

    legend = [(method, {"color": _style(method)[0], "marker": _style(method)[1] or None, "lw": 2.5})
              for method in methods]
    milestones = {}
    for method, points in curves.items():
        for target in (0.1, 0.01):
            hit = first_below(points, target)
            milestones.setdefault(method, {})[f"{target:g}"] = (None if hit is None else
                                                                  {"seconds": hit["seconds"], "rows": hit["rows_computed"],
                                                                   "step": hit["step"]})
    note = (f"{params['patches']} patches, hemicubes of {params['resolution']}; the truth: the direct solve of the same "
            f"matrix. Time: every method pays the same measured {1e3 * params['row_seconds']:.1f} ms a row of F for the "
            f"rows it has computed (Gauss-Seidel all {params['patches']} before its first sweep), plus its solver's "
            f"own time. {provenance(record)}.")
    image = plot_row(1160, 300, [against_time, against_shots], f"The Cornell box, {params['patches']} patches: "
                     "three ways to solve it", legend, note, widths=[1.2, 1])
    bar.advance(note="plot")
    return Drawn(image, {"patches": params["patches"], "row_seconds": params["row_seconds"],
                         "milestones": milestones, **record_facts(record)})


#: Every figure by name, with one line that says what it shows and how it is made.
