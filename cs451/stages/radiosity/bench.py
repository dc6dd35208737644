"""``cs451 bench radiosity``: error against run time for progressive refinement and the full-matrix solvers.

First the main job itself (:mod:`cs451.stages.radiosity.bench_main_job`): ``cs451 render`` of the Cornell box and the room as a user runs
it, with the solve split into form factors and the shooting loop.

For each scene (the Cornell box, the room) and patch size, every method solves the same
equations B = E + ρF̃B on the same hemicube rows (F̃ from the shooters' rows; see
``shooting_matrix``), and its error is measured against the direct solve of the full matrix:
the area-weighted relative L1 error of the displayed radiosity over the non-emitting patches.

Run time counts the form factors. Progressive refinement renders a hemicube only when a
patch first shoots; Jacobi, Gauss-Seidel and the direct solve need every row first. Every
method is charged the same measured price per row (the cheaper of one row alone and all rows
in batches), so only the number of rows and the solver's own time differ. The table gives
the rows and seconds needed to reach 10%, 1% and 0.1%.

With Mitsuba 3 installed (``pip install -e '.[peers]'``), the Cornell box's mean radiance per
wall is compared with Mitsuba's path tracer on the same scene (optional: skipped cleanly
without it).
"""
from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from cs451.impl import load_impl, resolve_impl
from cs451.scene import load_scene
from cs451.stages import radiosity as R
from cs451.stages.radiosity import solvers as S
from cs451 import patching as P

from .bench_peer import mitsuba_reference, polygon_ids, wall_means

#: The top-level keys of radiosity.json that the docs and decks read (tests/test_benches.py checks a quick run writes them).
KEYS = ("main_job", "cases", "substructured", "table", "furnace", "solve_again")

#: (scene, patch sizes) for the full and the quick run
CASES = {False: [("cornell-box", [140.0, 100.0, 70.0, 50.0]), ("room", [0.5, 0.35, 0.25])],
         True: [("cornell-box", [100.0, 50.0]), ("room", [0.5])]}
#: progressive variants: (label, use_ambient, overshoot, order): the notes' sweeps (the student's R3) and the
#: 1988 paper's "always the current maximum" (cs451/stages/radiosity/bench_shooting_orders.py)
VARIANTS = [("progressive", False, 1.0, "sweeps"), ("progressive+ambient", True, 1.0, "sweeps"),
            ("progressive+overshoot", False, 1.5, "sweeps"), ("progressive+overshoot+ambient", True, 1.5, "sweeps"),
            ("maximum (1988)", False, 1.0, "maximum"), ("maximum (1988)+overshoot", False, 1.5, "maximum")]
TARGETS = (1e-1, 1e-2, 1e-3)
#: (scene, patch sizes) shot to 2 × 2 elements each, for the full and the quick run
SUBSTRUCTURED = {False: [("cornell-box", [100.0, 70.0]), ("room", [0.5])], True: [("cornell-box", [140.0])]}


def relative_error(shown: np.ndarray, truth: np.ndarray, areas: np.ndarray, mask: np.ndarray) -> float:
    """Σ A |shown − truth| / Σ A |truth| over the patches in ``mask`` and all channels."""
    w = areas[mask, None]
    return float((np.abs(shown[mask] - truth[mask]) * w).sum() / max((np.abs(truth[mask]) * w).sum(), 1e-300))


def first_below(curve: list[tuple[float, float, int]], target: float) -> tuple[float | None, int | None]:
    """(seconds, rows) of the first point of a (seconds, error, rows) curve at or below ``target``."""
    for seconds, error, rows in curve:
        if error <= target:
            return seconds, rows
    return None, None


def run_case(ref: Any, scene_name: str, patch_size: float, resolution: int) -> dict:
    """One scene at one patch size: every method's (seconds, error, rows) curve against the direct solve on the
    same hemicube rows, each method charged the same price per row, and the seconds and rows it needs for TARGETS."""
    scene = load_scene(scene_name)
    opts = R.STAGE.options(scene, patch_size=patch_size, resolution=resolution)
    patches = R.make_patches(scene, ref, patch_size)
    a, rho, E = patches.areas, patches.reflectance, patches.emission
    n = len(patches)
    mask = E.max(axis=1) == 0                                   # the error is over what is lit, not the lights

    full = R.hemicube_formfactors(patches.quads, resolution, opts.proximity)
    start = time.perf_counter()
    F = full.matrix()
    batched_seconds = time.perf_counter() - start
    # the cost of one row asked for on its own (a fresh engine, one hemicube per read-back), as shooting asks
    lazy = R.hemicube_formfactors(patches.quads, resolution, opts.proximity, batch=1)
    sample = np.linspace(0, n - 1, min(n, 40)).astype(int)
    lazy.row(int(sample[0]))                                    # the first row also builds the GPU state
    start = time.perf_counter()
    for i in sample[1:]:
        lazy.row(int(i))
    lazy_seconds = (time.perf_counter() - start) / max(len(sample) - 1, 1)
    # every method pays the same price per row, the cheaper of the two ways: only the number of rows differs
    row_seconds = min(lazy_seconds, batched_seconds / n)
    ff_seconds = n * row_seconds
    Fs = S.shooting_matrix(F, a)
    start = time.perf_counter()
    truth = S.solve_direct(Fs, rho, E)
    direct_seconds = time.perf_counter() - start
    out: dict[str, Any] = {"scene": scene_name, "patch_size": patch_size, "patches": n, "resolution": resolution,
                           "formfactor_seconds_all_rows_batched": batched_seconds,
                           "formfactor_seconds_per_lazy_row": lazy_seconds, "formfactor_seconds_per_row": row_seconds,
                           "methods": {}}
    out["methods"]["direct"] = {"curve": [(ff_seconds + direct_seconds, 0.0, n)], "rows": n}
    # how well the truth itself is known: the same system on independently rotated hemicubes
    other = R.hemicube_formfactors(patches.quads, resolution, opts.proximity, seed=1).matrix()
    out["formfactor_noise"] = relative_error(S.solve_direct(S.shooting_matrix(other, a), rho, E), truth, a, mask)

    for method in ("jacobi", "gauss-seidel"):
        curve: list[tuple[float, float, int]] = [(ff_seconds, relative_error(E, truth, a, mask), n)]
        spent = [0.0]
        last = [time.perf_counter()]

        def on_sweep(k: int, B: np.ndarray) -> None:
            now = time.perf_counter()
            spent[0] += now - last[0]
            curve.append((ff_seconds + spent[0], relative_error(B, truth, a, mask), n))
            last[0] = time.perf_counter()

        last[0] = time.perf_counter()
        S.solve_iterative(method, Fs, a, rho, E, tolerance=1e-5, max_sweeps=500, on_sweep=on_sweep)
        out["methods"][method] = {"curve": curve, "rows": n}

    from .bench_shooting_orders import with_maximum_order
    for label, use_ambient, overshoot, order in VARIANTS:
        impl = ref if order == "sweeps" else with_maximum_order(ref)
        rows = S.MatrixRows(F)                                  # the same rows, counted as they are first asked for
        checkpoints = set(int(round(x)) for x in np.geomspace(1, 200 * n, 120))
        curve = [(0.0, relative_error(E + (rho * R.call_ambient(ref, a, rho, E) if use_ambient else 0), truth, a, mask), 0)]
        excluded = [0.0]
        begin = time.perf_counter()

        def on_shot(k: int, i: int, B: np.ndarray, dB: np.ndarray) -> None:
            if k not in checkpoints:
                return
            t0 = time.perf_counter()
            shown = B + rho * R.call_ambient(ref, a, rho, dB) if use_ambient else B
            used = rows.counters["rows_computed"]
            curve.append((t0 - begin - excluded[0] + used * row_seconds, relative_error(shown, truth, a, mask), used))
            excluded[0] += time.perf_counter() - t0

        shot_start = time.perf_counter()
        sol = R.solve_progressive(impl, rows, a, rho, E, tolerance=1e-5, overshoot=overshoot, use_ambient=use_ambient,
                                  on_shot=on_shot)
        loop_seconds = time.perf_counter() - shot_start - excluded[0]
        used = rows.counters["rows_computed"]
        end = time.perf_counter() - begin - excluded[0] + used * row_seconds
        curve.append((end, relative_error(sol.display, truth, a, mask), used))
        out["methods"][label] = {"curve": curve, "rows": used, "shots": sol.steps, "loop_seconds": loop_seconds}
    for m in out["methods"].values():
        for target in TARGETS:
            m[f"seconds_to_{target:g}"], m[f"rows_to_{target:g}"] = first_below(m["curve"], target)
    return out


# --- substructuring: patches shoot, elements receive -------------------------------------------

def run_substructured(ref: Any, scene_name: str, patch_size: float, resolution: int, k: int = 2) -> dict:
    """Progressive refinement with patches shooting to k × k elements each, against the elements' full system.

    The full-matrix methods on the elements need one row per element; substructured shooting
    needs at most one per patch (k² fewer), at the price of shooting each patch's mean unshot
    radiosity from its centre. Its error is measured against the direct solve of the element
    system (the answer the full-matrix methods give), with the same price per row.
    """
    from cs451.patches import patch_areas
    from . import bench_substructuring as sub

    scene = load_scene(scene_name)
    patches = R.make_patches(scene, ref, patch_size)
    elements, parent = sub.split_patches(patches.quads, k)
    a = patch_areas(elements)
    rho, E = patches.reflectance[parent], patches.emission[parent]
    mask = E.max(axis=1) == 0
    engine = R.hemicube_formfactors(elements, resolution, "none")
    start = time.perf_counter()
    F = engine.matrix()
    row_seconds = (time.perf_counter() - start) / len(elements)
    truth = S.solve_direct(S.shooting_matrix(F, a), rho, E)
    # every patch row rendered up front, so that the solve's clock holds the shooting alone; rows are charged per shooter
    rows = S.MatrixRows(sub.PatchToElementRows(engine, patches.quads, parent).matrix())
    curves: dict[str, list] = {}
    for label, use_ambient in (("substructured", False), ("substructured+ambient", True)):
        curve: list[tuple[float, float, int]] = []
        shooters: set[int] = set()
        excluded = [0.0]
        begin = time.perf_counter()

        def on_shot(shots: int, p: int, B: np.ndarray, dB: np.ndarray) -> None:
            t0 = time.perf_counter()
            shooters.add(p)
            shown = B + rho * R.call_ambient(ref, a, rho, dB) if use_ambient else B
            curve.append((t0 - begin - excluded[0] + len(shooters) * row_seconds,
                          relative_error(shown, truth, a, mask), len(shooters)))
            excluded[0] += time.perf_counter() - t0

        sub.solve_substructured(rows, parent, a, rho, E, tolerance=1e-5, on_shot=on_shot)
        curves[label] = curve
    out: dict[str, Any] = {"scene": scene_name, "patch_size": patch_size, "patches": len(patches),
                           "elements": len(elements), "resolution": resolution, "row_seconds": row_seconds,
                           "element_matrix_seconds": row_seconds * len(elements), "methods": {}}
    for label, curve in curves.items():
        m: dict[str, Any] = {"curve": curve, "rows": curve[-1][2] if curve else 0,
                             "final_error": curve[-1][1] if curve else None}
        for target in TARGETS:
            m[f"seconds_to_{target:g}"], m[f"rows_to_{target:g}"] = first_below(curve, target)
        out["methods"][label] = m
    return out


def compare_with_mitsuba(ref: Any, quick: bool) -> dict | None:
    """The Cornell box's mean radiance per wall, radiosity's render against Mitsuba 3's path tracer (cached),
    with both images; None, saying so, where Mitsuba is not installed."""
    try:
        import mitsuba  # noqa: F401
    except ImportError:
        print("Mitsuba 3 is not installed (pip install -e '.[peers]'): skipping the path-tracer comparison")
        return None
    scene = load_scene("cornell-box")
    size = (128, 128) if quick else (256, 256)
    spp = 64 if quick else 512
    start = time.perf_counter()
    ours = R.render(scene, ref, size, quiet=True)
    ours_seconds = time.perf_counter() - start
    peer = mitsuba_reference("cornell-box", size, spp, 64)         # cached: the adaptive comparison renders it too
    theirs, mitsuba_seconds = peer["image"], peer["seconds"]
    ids = polygon_ids(scene, size)
    a, b = wall_means(ours, ids), wall_means(theirs, ids)
    rows = {w: {"radiosity": a[w], "mitsuba": b[w], "ratio": (np.array(a[w]) / np.maximum(b[w], 1e-12)).tolist()}
            for w in a if w in b}
    return {"size": list(size), "spp": spp, "max_depth": 64, "radiosity_seconds": ours_seconds,
            "mitsuba_seconds": mitsuba_seconds, "walls": rows, "images": (ours, theirs)}


# --- the white furnace: B = E / (1 − ρ) --------------------------------------------------------

def furnace_figures(ref: Any, quick: bool) -> list[dict]:
    """The furnace box (E = 1) at ρ = 0.5, 0.9, 0.99: exact form factors (Howell's cube) and hemicube rows."""
    from cs451.patches import patch_areas, patch_normals

    import sys
    from cs451 import KIT_ROOT
    if str(KIT_ROOT) not in sys.path:
        sys.path.insert(0, str(KIT_ROOT))
    from autograder.radiosity import truth as T

    scene = load_scene("furnace")
    cube, _, _, _ = P.radiosity_surfaces(scene)
    patches = R.make_patches(scene, ref, R.STAGE.options(scene).patch_size)
    hemicube = S.MatrixRows(R.hemicube_formfactors(patches.quads, 128, "none").matrix())
    cases = [("exact (Howell, 6 patches)", S.MatrixRows(T.cube_formfactors(patch_normals(cube))), patch_areas(cube)),
             (f"hemicube 128, {len(patches)} patches", hemicube, patches.areas),
             ("hemicube 128 + reciprocity", S.reciprocal_rows(hemicube, patches.areas)[0], patches.areas)]
    out = []
    for label, rows, areas in cases:
        n = len(areas)
        for rho in (0.5, 0.9, 0.99):
            for overshoot in (1.0, 1.5):
                sol = R.solve_progressive(ref, rows, areas, np.full((n, 3), rho), np.ones((n, 3)), tolerance=1e-4,
                                          max_shots=200_000, overshoot=overshoot, use_ambient=False)
                err = sol.radiosity[:, 0] / T.furnace(1.0, rho) - 1
                mean = float((sol.radiosity[:, 0] * areas).sum() / areas.sum() / T.furnace(1.0, rho) - 1)
                out.append({"form_factors": label, "albedo": rho, "overshoot": overshoot, "shots": sol.steps,
                            "converged": sol.converged, "mean_error": mean, "max_abs_error": float(np.abs(err).max()),
                            "patch_min": float(sol.radiosity[:, 0].min()), "patch_max": float(sol.radiosity[:, 0].max())})
    print("\nwhite furnace, E = 1, tolerance 1e-4: B against E/(1 − ρ)")
    print(f"{'form factors':<28} {'ρ':>5} {'ω':>4} {'shots':>7} {'mean error':>11} {'max |error|':>12}")
    for r in out:
        print(f"{r['form_factors']:<28} {r['albedo']:>5} {r['overshoot']:>4} {r['shots']:>7} {r['mean_error']:>+11.2e} "
              f"{r['max_abs_error']:>12.2e}" + ("" if r["converged"] else "  (not converged)"))
    print("per patch at ρ = 0.5 (B = 2): " + "; ".join(f"{r['form_factors']} {r['patch_min']:.4f} .. {r['patch_max']:.4f}"
                                                       for r in out if r["albedo"] == 0.5 and r["overshoot"] == 1.0))
    return out


# --- output ---------------------------------------------------------------------------------

def _fmt(x: float | None) -> str:
    return "—" if x is None else f"{x:.2f}"


def print_table(results: list[dict]) -> list[str]:
    """Print :func:`run_case`'s results as a table (rows and seconds to each target) and return its lines."""
    head = "".join(f"  rows/s to {t:g}".rjust(19) for t in TARGETS)
    lines = [f"{'scene':<12} {'patches':>7}  {'method':<30}{head}  {'shots':>7} {'loop s':>7}",
             "-" * (68 + 19 * len(TARGETS))]
    for case in results:
        for label, m in case["methods"].items():
            cells = "".join(f"{str(m[f'rows_to_{t:g}'] or '—'):>10} /{_fmt(m[f'seconds_to_{t:g}']):>7}" for t in TARGETS)
            shots = f"{m['shots']:>7} {m['loop_seconds']:>7.2f}" if "shots" in m else f"{'':>7} {'':>7}"
            lines.append(f"{case['scene']:<12} {case['patches']:>7}  {label:<30}{cells}  {shots}")
        lines.append(f"{'':<21}form factors: {1e3 * case['formfactor_seconds_per_row']:.2f} ms a row charged to every "
                     f"method (all rows batched {case['formfactor_seconds_all_rows_batched']:.2f} s, "
                     f"one row alone {1e3 * case['formfactor_seconds_per_lazy_row']:.2f} ms)")
        lines.append(f"{'':<21}the truth's own uncertainty: independently rotated hemicubes give a solution "
                     f"{100 * case['formfactor_noise']:.2f}% away")
    print("\n".join(lines))
    return lines


def print_substructured(results: list[dict]) -> list[str]:
    """Print :func:`run_substructured`'s results (rows and seconds to 10% and 1%, final error) and return the
    lines."""
    head = "".join(f"  rows/s to {t:g}".rjust(19) for t in TARGETS[:2])
    lines = ["", "substructuring: patches shoot to 2 × 2 elements; error against the elements' direct solve",
             f"{'scene':<12} {'patches':>7} {'elements':>8}  {'method':<24}{head}  {'final error':>11}  "
             f"{'element matrix (rows/s)':>23}", "-" * 120]
    for case in results:
        for label, m in case["methods"].items():
            cells = "".join(f"{str(m[f'rows_to_{t:g}'] or '—'):>10} /{_fmt(m[f'seconds_to_{t:g}']):>7}" for t in TARGETS[:2])
            lines.append(f"{case['scene']:<12} {case['patches']:>7} {case['elements']:>8}  {label:<24}{cells}  "
                         f"{100 * m['final_error']:>10.2f}%  {case['elements']:>14} /{case['element_matrix_seconds']:>7.2f}")
    print("\n".join(lines))
    return lines


def plot(results: list[dict], path: Path) -> None:
    """Error against seconds for every method, a panel per scene and patch size, written to ``path`` as a PNG."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenes = list(dict.fromkeys(case["scene"] for case in results))
    cols = max(sum(case["scene"] == s for case in results) for s in scenes)
    fig, grid = plt.subplots(len(scenes), cols, figsize=(4.2 * cols, 3.6 * len(scenes)), squeeze=False)
    axes, used = [], set()
    for case in results:                            # one row of plots per scene, patch counts left to right
        row = scenes.index(case["scene"])
        col = sum(c["scene"] == case["scene"] for c in results[:results.index(case)])
        axes.append(grid[row][col])
        used.add((row, col))
    for r in range(len(scenes)):
        for c in range(cols):
            if (r, c) not in used:
                grid[r][c].axis("off")
    styles = {"direct": ("k", "o"), "jacobi": ("tab:blue", "."), "gauss-seidel": ("tab:green", "."),
              "progressive": ("tab:red", ""), "progressive+ambient": ("tab:orange", ""),
              "progressive+overshoot": ("tab:purple", ""), "progressive+overshoot+ambient": ("tab:pink", ""),
              "maximum (1988)": ("tab:brown", ""), "maximum (1988)+overshoot": ("tab:olive", "")}
    for ax, case in zip(axes, results):
        for label, m in case["methods"].items():
            t = [max(p[0], 1e-3) for p in m["curve"]]
            e = [max(p[1], 1e-6) for p in m["curve"]]
            color, marker = styles.get(label, ("gray", ""))
            name = "direct (the truth; drawn at 1e-6)" if label == "direct" else label
            ax.loglog(t, e, color=color, marker=marker, label=name, lw=1.2, ms=4)
        ax.axhline(1e-2, color="gray", ls=":", lw=0.8)
        if "formfactor_noise" in case:               # below this, the error is finer than the form factors are known
            ax.axhline(case["formfactor_noise"], color="gray", ls="--", lw=0.8,
                       label="the truth's own uncertainty (other hemicube rotations)")
        ax.set_title(f"{case['scene']}, {case['patches']} patches", fontsize=9)
        ax.set_xlabel("seconds (form factors included)")
        ax.set_ylabel("relative error of B")
        ax.grid(True, which="both", alpha=0.2)
    axes[0].legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(output: Path, quick: bool = False) -> None:
    """The main job's split, every case, substructuring, the white furnace, solving again and the optional peers
    (Mitsuba, adaptive meshes): prints the tables and writes ``radiosity.json`` and ``radiosity.png`` in ``output``."""
    ref = load_impl(resolve_impl("reference", "radiosity"), "radiosity")
    output.mkdir(parents=True, exist_ok=True)
    from . import bench_main_job as main_job
    split = main_job.measure(ref)                      # first, on a quiet machine: the main job's time, split
    main_table = main_job.print_split(split)
    results = []
    for scene_name, sizes in CASES[quick]:
        for patch_size in sizes:
            results.append(run_case(ref, scene_name, patch_size, resolution=64 if quick else 128))
            print(f"  {scene_name} at {patch_size}: {results[-1]['patches']} patches done", flush=True)
    table = print_table(results)
    substructured = [run_substructured(ref, scene_name, size, resolution=64 if quick else 128)
                     for scene_name, sizes in SUBSTRUCTURED[quick] for size in sizes]
    table += print_substructured(substructured)
    furnace = furnace_figures(ref, quick)
    from . import bench_solve_again as RS
    resolved = RS.measure()
    table += RS.print_table(resolved)
    peer = compare_with_mitsuba(ref, quick)
    table = main_table + table
    report: dict[str, Any] = {"main_job": split, "cases": results, "substructured": substructured, "table": table,
                              "furnace": furnace, "solve_again": resolved}
    if peer is not None:
        from cs451.imageio import save_png

        ours, theirs = peer.pop("images")
        save_png(output / "radiosity-cornell.png", ours, 1.0, True)
        save_png(output / "mitsuba-cornell.png", theirs, 1.0, True)
        print(f"\nCornell box, mean radiance per wall (R, G, B): radiosity ({peer['radiosity_seconds']:.1f} s) "
              f"against Mitsuba 3 path tracing ({peer['spp']} spp, {peer['mitsuba_seconds']:.1f} s)")
        for wall, row in peer["walls"].items():
            print(f"  {wall:<14} {np.round(row['radiosity'], 4)}  {np.round(row['mitsuba'], 4)}  ratio {np.round(row['ratio'], 3)}")
        report["mitsuba"] = peer
    from . import bench_adaptive_runs as AD
    adaptive = AD.compare_adaptive(ref, quick)
    if adaptive is not None:
        table += AD.print_adaptive(adaptive)
        figure = adaptive.pop("figure")
        written = [AD.mesh_figure(figure, output / "adaptive-mesh.png")]
        if not quick:                              # the handout's copy comes from the full run only
            written.append(AD.mesh_figure(figure, AD.HANDOUT_FIGURE))
        print("wrote " + " and ".join(str(p) for p in written))
        report["adaptive"] = adaptive
    (output / "radiosity.json").write_text(json.dumps(report, indent=1))
    plot(results, output / "radiosity.png")
    print(f"wrote {output / 'radiosity.json'} and {output / 'radiosity.png'}")
