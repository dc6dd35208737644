"""What the radiosity deck's benchmark figure shows (``cs451 slides record radiosity``): error and unshot energy
against time on the Cornell box, for Gauss-Seidel on the full matrix and for progressive shooting in the handout's
order and in the 1988 paper's, the form factors charged to each at one measured price per row.
"""
from __future__ import annotations

import time

import numpy as np

from cs451.impl import load_impl, resolve_impl
from cs451.scene import load_scene
from cs451.stages import radiosity as R
from cs451.stages.radiosity import solvers as S

from .bench import relative_error

#: what `cs451 slides record radiosity` measures: the scene as `cs451 render` solves it (the stage's patch size and
#: hemicube resolution), or small (--quick, for the tests)
SLIDE = {False: {"scene": "cornell-box", "patch_size": None, "resolution": None, "tolerance": 1e-5},
         True: {"scene": "cornell-box", "patch_size": 140.0, "resolution": 32, "tolerance": 1e-4}}
#: (label, how it solves): Gauss-Seidel on the full matrix, the handout's shooting (the reference's R3: sweeps in
#: order of unshot energy) and the 1988 paper's (R7: always the largest unshot energy now)
SLIDE_METHODS = (("Gauss-Seidel, full matrix", "gauss-seidel"), ("progressive, the handout's order (R3)", "sweeps"),
                 ("progressive, largest first (1988, R7)", "maximum"))
SLIDE_COLUMNS = {
    "method": "Gauss-Seidel on the full matrix; progressive shooting in the handout's order (R3: sweeps, each in "
              "order of unshot energy); progressive shooting largest first (the 1988 paper's order, R7)",
    "step": "sweeps (Gauss-Seidel) or shots (progressive) so far",
    "rows_computed": "rows of F computed so far (one hemicube each): all n before Gauss-Seidel's first sweep; "
                     "progressive computes a row when a patch first shoots",
    "seconds": "median seconds so far: rows_computed × the measured price of a row, plus the solver's own time",
    "seconds_min": "the same, with the fastest repeat of the solver and of the row price",
    "seconds_max": "the same, with the slowest",
    "solver_seconds": "median seconds of the solver alone (no form factors)",
    "error": "Σ A|B − B*| / Σ A|B*| over the patches that do not emit, all channels, against the direct solve B* of "
             "the same matrix",
    "unshot": "unshot energy Σ A·ΔB / Σ A·E (progressive only)",
}


def slide_record(quick: bool = False, repeats: int = 3) -> dict:
    """The radiosity deck's record (``cs451 slides record radiosity``): the Cornell box as ``cs451 render`` solves
    it, Gauss-Seidel on the full matrix against progressive shooting in the handout's order and largest first, each
    solver run ``repeats`` times one after another (median, fastest, slowest at every point of its curve), every
    method charged the same measured price per row of form factors (the cheaper of a row alone and all rows
    batched, each the median of ``repeats``)."""
    from cs451.progress import Progress
    from .bench_shooting_orders import with_maximum_order

    plan = SLIDE[quick]
    ref = load_impl(resolve_impl("reference", "radiosity"), "radiosity")
    scene = load_scene(plan["scene"])
    opts = R.STAGE.options(scene)
    patch_size = plan["patch_size"] or opts.patch_size
    resolution = plan["resolution"] or opts.resolution
    patches = R.make_patches(scene, ref, patch_size)
    a, rho, E = patches.areas, patches.reflectance, patches.emission
    n = len(patches)
    mask = E.max(axis=1) == 0
    emitted = S.energy(E, a)
    bar = Progress("radiosity: solvers", 2 + 3 * repeats, unit="run")
    try:
        batched, lazy = [], []
        for _ in range(repeats):
            full = R.hemicube_formfactors(patches.quads, resolution, opts.proximity)
            full.tables, full.renderer                       # the GPU state, built before the clock starts
            start = time.perf_counter()
            F = full.matrix()
            batched.append(time.perf_counter() - start)
            one = R.hemicube_formfactors(patches.quads, resolution, opts.proximity, batch=1)
            sample = np.linspace(0, n - 1, min(n, 40)).astype(int)
            one.row(int(sample[0]))                          # the first row builds the GPU state
            start = time.perf_counter()
            for i in sample[1:]:
                one.row(int(i))
            lazy.append((time.perf_counter() - start) / max(len(sample) - 1, 1))
        bar.advance(note="form factors")
        prices = [min(l_, b / n) for l_, b in zip(lazy, batched)]
        row_seconds = float(np.median(prices))
        Fs = S.shooting_matrix(F, a)
        start = time.perf_counter()
        truth = S.solve_direct(Fs, rho, E)
        direct_seconds = time.perf_counter() - start
        bar.advance(note="direct solve")
        error = lambda B: relative_error(B, truth, a, mask)          # noqa: E731
        curves: dict[str, dict[int, dict]] = {}
        for label, how in SLIDE_METHODS:
            points: dict[int, dict] = {}
            for _ in range(repeats):
                spent, last = [0.0], [0.0]
                if how == "gauss-seidel":
                    points.setdefault(0, {"rows": n, "error": error(E), "unshot": None, "times": []})["times"].append(0.0)

                    def on_sweep(k: int, B: np.ndarray) -> None:
                        spent[0] += time.perf_counter() - last[0]
                        p = points.setdefault(k, {"rows": n, "error": error(B), "unshot": None, "times": []})
                        p["times"].append(spent[0])
                        last[0] = time.perf_counter()
                    last[0] = time.perf_counter()
                    S.solve_iterative("gauss-seidel", Fs, a, rho, E, tolerance=plan["tolerance"], max_sweeps=500,
                                      on_sweep=on_sweep)
                else:
                    impl = ref if how == "sweeps" else with_maximum_order(ref)
                    rows = S.MatrixRows(F)
                    checkpoints = set(int(round(x)) for x in np.geomspace(1, 200 * n, 80))
                    points.setdefault(0, {"rows": 0, "error": error(E), "unshot": 1.0, "times": []})["times"].append(0.0)

                    def on_shot(k: int, i: int, B: np.ndarray, dB: np.ndarray) -> None:
                        if k not in checkpoints:
                            return
                        spent[0] += time.perf_counter() - last[0]
                        p = points.setdefault(k, {"rows": rows.counters["rows_computed"], "error": error(B),
                                                  "unshot": S.energy(dB, a) / emitted, "times": []})
                        p["times"].append(spent[0])
                        last[0] = time.perf_counter()
                    last[0] = time.perf_counter()
                    sol = R.solve_progressive(impl, rows, a, rho, E, tolerance=plan["tolerance"], overshoot=1.0,
                                              use_ambient=False, on_shot=on_shot)
                    spent[0] += time.perf_counter() - last[0]
                    p = points.setdefault(-1, {"rows": rows.counters["rows_computed"], "error": error(sol.radiosity),
                                               "unshot": S.energy(sol.unshot, a) / emitted if hasattr(sol, "unshot")
                                               else None, "steps": sol.steps, "times": []})
                    p["times"].append(spent[0])
                bar.advance(note=label)
            curves[label] = points
    finally:
        bar.close()
    out = []
    for label, points in curves.items():
        for step, p in sorted(points.items(), key=lambda kv: (kv[0] < 0, kv[0])):
            times = p["times"]
            if len(times) < repeats:                         # a point only some repeats reached: not a median
                continue
            rows_cost = p["rows"] * np.array([row_seconds, min(prices), max(prices)])
            out.append({"method": label, "step": p.get("steps", step), "rows_computed": int(p["rows"]),
                        "seconds": float(rows_cost[0] + np.median(times)),
                        "seconds_min": float(rows_cost[1] + min(times)),
                        "seconds_max": float(rows_cost[2] + max(times)), "solver_seconds": float(np.median(times)),
                        "error": float(p["error"]), "unshot": None if p["unshot"] is None else float(p["unshot"])})
    return {"rows": out, "columns": SLIDE_COLUMNS, "gl_renderer": _renderer_name(),
            "params": {"scene": plan["scene"], "patch_size": patch_size, "patches": n, "resolution": resolution,
                       "proximity": opts.proximity, "tolerance": plan["tolerance"],
                       "row_seconds": row_seconds, "row_seconds_alone": float(np.median(lazy)),
                       "matrix_seconds_batched": float(np.median(batched)), "direct_seconds": direct_seconds,
                       "time": "seconds include the form factors: every method pays the same measured price per row "
                               "of F (the cheaper of a row alone and all rows batched), times the rows it has "
                               "computed, plus its solver's own time; the error measurement is not timed",
                       "truth": "the direct solve of the same full matrix"}}


def _renderer_name() -> str:
    from cs451.gl import create_context, renderer_name
    return renderer_name(create_context())
