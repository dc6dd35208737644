"""``cs451 bench hemicube``, part 4: form factors where patches hide each other, against the area average.

The closed forms and the converged hemicube of parts 1-3 measure what a hemicube at a patch's centre
computes. A form factor is the average over the shooter's area, and the two part where something stands
between two close patches: the Cornell box's floor, as one polygon, lies partly under the blocks, so its
centre sees what most of it does not. Truth here is Monte Carlo ray casting on Embree from uniformly random
points of each patch (an optional peer; 400,000 rays a patch, standard error under 0.1% of a row), and the
error is the mean over rows of Σ_j |F_ij - F*_ij| / Σ_j F*_ij. Methods: the plain hemicube, the proximity fix
(H6 over the shooter, with its sight lines past occluders), and the shooter split into k × k hemicubes.
"""
from __future__ import annotations

import time

import numpy as np

from cs451.formfactors import HemicubeFormFactors, formfactor_matrix_raycast
from cs451.patches import scene_polygons
from cs451.scene import load_scene
from cs451.stages.hemicube import calls

from bench.meshes import subdivide_uniform

TRUTH_RAYS = 400_000


def _row_error(F: np.ndarray, ref: np.ndarray) -> float:
    total = ref.sum(axis=1)
    ok = total > 1e-9
    return float(np.mean(np.abs(F[ok] - ref[ok]).sum(axis=1) / total[ok]))


def occluded(impl, resolutions: list[int], ctx, subdivisions: tuple[int, ...] = (1, 4)) -> list[dict]:
    """Rows of the Cornell box (each quad cut k × k for k in ``subdivisions``), every method, timed, with errors."""
    out = []
    for k in subdivisions:
        quads, _ = subdivide_uniform(scene_polygons(load_scene("cornell-box"))[0], k)
        rows = list(range(len(quads))) if len(quads) <= 64 else list(range(0, len(quads), max(1, len(quads) // 64)))
        t0 = time.perf_counter()
        truth = formfactor_matrix_raycast(quads, TRUTH_RAYS, seed=11, rows=rows)
        truth_seconds = time.perf_counter() - t0
        methods = [("hemicube", r, dict(proximity="none")) for r in resolutions]
        methods += [("proximity fix", r, dict(proximity="contour")) for r in resolutions if r <= 256]
        methods += [("shooter split 4×4", 128, dict(proximity="none", shooter_split=4))]
        for name, res, kwargs in methods:
            ff = HemicubeFormFactors(quads, calls(impl), resolution=res, rotate=False, ctx=ctx, **kwargs)
            ff.tables, ff.renderer
            t0 = time.perf_counter()
            F = ff.rows(rows)
            seconds = time.perf_counter() - t0
            out.append({"patches": len(quads), "subdivision": k, "method": name, "resolution": res, "rows": len(rows),
                        "seconds": seconds, "error": _row_error(F, truth), "truth_seconds": truth_seconds,
                        "worst_entry": float(np.abs(F - truth).max()),
                        "floor_row_sum": float(F[0].sum()) if rows[0] == 0 else None,
                        "floor_truth": float(truth[0].sum()) if rows[0] == 0 else None})
    return out


def print_occluded(results: list[dict]) -> None:
    print("\nOccluded: the Cornell box against the area average (ray casting from random points, "
          f"{TRUTH_RAYS:,} rays a patch)")
    print(f"{'patches':>7s} {'method':18s} {'res':>5s} {'rows':>5s} {'seconds':>8s} {'row error':>9s} {'worst F':>8s} "
          f"{'floor sum':>9s}")
    for r in results:
        floor = "" if r["floor_row_sum"] is None else f"{r['floor_row_sum']:.4f}/{r['floor_truth']:.4f}"
        print(f"{r['patches']:7d} {r['method']:18s} {r['resolution']:5d} {r['rows']:5d} {r['seconds']:8.2f} "
              f"{r['error']:9.2%} {r['worst_entry']:8.4f} {floor:>9s}")
