"""``cs451 bench radiosity``: error against run time for progressive refinement and the full-matrix solvers.

First the main job itself (:mod:`bench.main_job`): ``cs451 render`` of the Cornell box and the room as a user runs
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

import functools
import json
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from cs451.impl import load_impl, resolve_impl
from cs451.scene import load_scene
from cs451.stages import radiosity as R
from cs451 import solvers as S
from cs451 import patching as P
from cs451 import drawing as D

#: (scene, patch sizes) for the full and the quick run
CASES = {False: [("cornell-box", [140.0, 100.0, 70.0, 50.0]), ("room", [0.5, 0.35, 0.25])],
         True: [("cornell-box", [100.0, 50.0]), ("room", [0.5])]}
#: progressive variants: (label, use_ambient, overshoot, order): the notes' sweeps (the student's R3) and the
#: 1988 paper's "always the current maximum" (bench/shooting_orders.py)
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

    from bench.shooting_orders import with_maximum_order
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
    from bench import substructuring as sub

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


# --- Mitsuba 3 as a peer: mean radiance per wall of the Cornell box ---------------------------------

WALLS = {"floor": [0], "ceiling": [1], "back": [2], "left (red)": [4], "right (green)": [3],
         "short block": [5, 6, 7, 8, 9], "tall block": [10, 11, 12, 13, 14]}


def polygon_ids(scene: Any, size: tuple[int, int], quads: np.ndarray | None = None, drawer: Any = None) -> np.ndarray:
    """Which polygon (or which of ``quads``) each pixel shows (-1: none), drawn with the kit's Gouraud drawer from the scene camera."""
    if quads is None:
        quads, _, _, _ = P.radiosity_surfaces(scene)
    if drawer is not None:
        from cs451.gl import make_current
        make_current(drawer.ctx)                   # other engines may have made their context current
    ids = np.arange(len(quads), dtype=np.float64)
    positions = quads.reshape(-1, 3)
    colors = np.repeat(np.column_stack([ids + 1, np.zeros((len(ids), 2))]), 4, axis=0)
    corners = np.arange(4 * len(quads)).reshape(-1, 4)
    image = (drawer or D.GouraudDrawer()).draw(positions, colors, corners,
                                               D.camera_matrix(scene, *size, R.camera_view(scene)), *size)
    return np.round(image[..., 0]).astype(int) - 1


def mitsuba_cornell(scene: Any, size: tuple[int, int], spp: int, max_depth: int, seed: int = 0) -> np.ndarray:
    """The scene rendered by Mitsuba 3's path tracer (scalar_rgb), linear radiance (h, w, 3); ``seed`` its sampler's."""
    import tempfile

    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    quads, reflectance, radiosity, _ = P.radiosity_surfaces(scene)
    cam = scene.camera
    objects: dict[str, Any] = {"type": "scene", "integrator": {"type": "path", "max_depth": max_depth},
                               "sensor": {"type": "perspective", "fov_axis": "y", "fov": cam.fovy,
                                          "near_clip": cam.near, "far_clip": cam.far,
                                          "to_world": mi.ScalarTransform4f().look_at(origin=list(cam.eye),
                                                                                      target=list(cam.center),
                                                                                      up=list(cam.up)),
                                          "film": {"type": "hdrfilm", "width": size[0], "height": size[1],
                                                   "rfilter": {"type": "box"}},
                                          "sampler": {"type": "independent", "sample_count": spp}}}
    folder = Path(tempfile.mkdtemp(prefix="cs451-mitsuba-"))
    for k, quad in enumerate(quads):
        path = folder / f"p{k}.obj"
        lines = [f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in quad] + ["f 1 2 3", "f 1 3 4"]
        path.write_text("\n".join(lines) + "\n")
        shape: dict[str, Any] = {"type": "obj", "filename": str(path), "face_normals": True,
                                 "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": list(reflectance[k])}}}
        if radiosity[k].max() > 0:
            shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": list(radiosity[k] / math.pi)}}
        objects[f"polygon{k}"] = shape
    image = mi.render(mi.load_dict(objects), seed=seed)
    return np.asarray(image, dtype=np.float64)[..., :3]


def wall_masks(ids: np.ndarray) -> dict[str, np.ndarray]:
    """Each wall's pixels away from its polygons' edges (each polygon eroded by 2 pixels on its own), for the walls shown.

    A block's faces are eroded one by one, not as their union: the union keeps the pixels along the crease between
    the lit top and a dark side, where one pixel's coverage (the kit's pixel centres against Mitsuba's box filter)
    moved a dark face's mean by 9% in the walkthrough."""
    out = {}
    for wall, polys in WALLS.items():
        eroded = np.zeros(ids.shape, dtype=bool)
        for poly in polys:
            inside = ids == poly
            kept = inside.copy()
            for dy in (-2, -1, 0, 1, 2):
                for dx in (-2, -1, 0, 1, 2):
                    kept &= np.roll(np.roll(inside, dy, axis=0), dx, axis=1)
            eroded |= kept
        if eroded.any():
            out[wall] = eroded
    return out


def wall_means(image: np.ndarray, ids: np.ndarray) -> dict[str, list[float]]:
    """Mean RGB per wall over its pixels, away from its edges (a 2-pixel erosion)."""
    return {wall: image[mask].mean(axis=0).tolist() for wall, mask in wall_masks(ids).items()}


@functools.lru_cache(maxsize=4)
def mitsuba_reference(scene_name: str, size: tuple[int, int], spp: int, max_depth: int = 64,
                      camera: tuple[tuple[str, Any], ...] = ()) -> dict[str, Any]:
    """Mitsuba's render of a bundled scene, once per run: two halves of ``spp // 2`` samples (seeds 0 and 1).

    ``image`` is their mean (``spp`` samples); ``halves`` let a comparison say how noisy it still is (their
    difference is twice the mean's noise, in the mean). ``seconds``: both renders. ``camera``: (field, value)
    pairs that replace the scene camera's (another view of the same scene).
    """
    import dataclasses

    start = time.perf_counter()
    scene = load_scene(scene_name)
    if camera:
        scene = dataclasses.replace(scene, camera=dataclasses.replace(scene.camera, **dict(camera)))
    halves = tuple(mitsuba_cornell(scene, size, max(spp // 2, 1), max_depth, seed=seed) for seed in (0, 1))
    return {"image": 0.5 * (halves[0] + halves[1]), "halves": halves, "spp": 2 * max(spp // 2, 1),
            "seconds": time.perf_counter() - start}


def compare_with_mitsuba(ref: Any, quick: bool) -> dict | None:
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
    ref = load_impl(resolve_impl("reference", "radiosity"), "radiosity")
    output.mkdir(parents=True, exist_ok=True)
    from bench import main_job
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
    from bench import solve_again as RS
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
    from bench import adaptive as AD
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


# --- the slides' record: `cs451 slides record radiosity` ---------------------------------------------------

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
    from bench.shooting_orders import with_maximum_order

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
