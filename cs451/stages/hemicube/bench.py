"""``cs451 bench hemicube``: form-factor error against run time, hemicube resolution 16 to 1024, next to ray casting.

Three parts, printed as tables and written to ``hemicube.json`` and ``hemicube.png``:

1. Closed-form configurations (autograder/hemicube/truth.py): a small patch under a
   coaxial disk (B-13) and under a unit square (exact by quadrature of the contour
   formula), small squares far apart and unit squares one apart (Howell C-11),
   unit squares at right angles (C-14), each without a fix, with the contour fix and with
   the shooter split into 4 × 4 hemicubes. The error
   is |F - exact| / exact; for the small squares, whose few cells alias, it is the RMS over
   16 seeded rotations of the hemicube.
2. The Cornell box (cs451/scenes/cornell-box.json) with every quad cut into k × k
   (k = 8: 1,024 patches): the full form-factor matrix at each resolution, timed, and its
   error against a converged answer (resolution 1024) on every 8th
   row: the mean over rows of Σ_j |F_ij - F*_ij| / Σ_j F*_ij. Row sums, reciprocity and
   closure are reported for every run.
3. Ray casting (Monte Carlo, Embree) on the same scene, rays from each patch's centre so
   that it estimates the same quantity as the hemicube, with the same error measure, at
   increasing sample counts; and the time each method needs for the full matrix at equal error.
4. Occlusion (:mod:`cs451.stages.hemicube.bench_occluded`): the Cornell box as whole polygons and cut 4 × 4, where
   patches hide each other, against the area average (ray casting from random points): the plain
   hemicube, the proximity fix and the split shooter, timed.

``--quick`` is a small run that shows every part works (the fast suite runs it): resolutions 16 to 64, the box's
whole polygons against resolution 128, every fourth of Howell's configurations; its numbers are not the measurement.
"""
from __future__ import annotations

import importlib.util
import json
import time
from pathlib import Path

import numpy as np

from autograder.hemicube import truth
from cs451 import import_from_kit
from cs451.formfactors import HemicubeFormFactors, formfactor_matrix_raycast
from cs451.gl import create_context, renderer_name
from cs451.impl import load_impl, resolve_impl
from cs451.patches import patch_areas, scene_polygons

from .bench_occluded import occluded, print_occluded
from cs451.scene import load_scene
from cs451.stages.hemicube import calls

#: The top-level keys of hemicube.json that the docs and decks read (tests/test_benches.py checks a quick run writes them).
KEYS = ("renderer", "quick", "closed_forms", "cornell", "family")

subdivide_uniform = import_from_kit("bench.meshes").subdivide_uniform    # the kit's fine meshes (bench/)


def _impl():
    return load_impl(resolve_impl("reference", "hemicube"), "hemicube")


def small_under_square(size: float = 0.05, side: float = 1.0, height: float = 1.0) -> tuple[list, float]:
    """A small square centred under a big one (well separated); exact F by Gauss quadrature of the contour formula."""
    h, H = size / 2, side / 2
    quads = [[[-h, -h, 0], [h, -h, 0], [h, h, 0], [-h, h, 0]],
             [[-H, -H, height], [-H, H, height], [H, H, height], [H, -H, height]]]
    x, w = np.polynomial.legendre.leggauss(8)
    exact = sum(wi * wj * truth.contour([h * xi, h * xj, 0], [0, 0, 1], quads[1])
                for xi, wi in zip(x, w) for xj, wj in zip(x, w)) / 4
    return quads, exact


def closed_forms(impl, resolutions: list[int], ctx) -> list[dict]:
    """Part 1: every closed-form configuration at every resolution, its relative error (RMS over 16 seeded
    rotations for the small squares) and its median seconds per row."""
    under, under_exact = small_under_square()
    configs = [
        ("0.05 square under a unit square 1 above", under, [1], under_exact, "none", 1),
        ("disk: dA under a coaxial disk, a = h = 1", truth.small_patch_under_disk(0.01, 1.0, 1.0, 256), list(range(1, 257)),
         truth.polygon_disk(1.0, 1.0, 256), "none", 1),
        ("C-11: 0.1 squares 1 apart (RMS of 16 rotations)", truth.opposed_squares(0.1, 1.0), [1],
         truth.howell_c11(0.1, 0.1, 1.0), "none", 16),
        ("C-11: unit squares 1 apart, no fix", truth.opposed_squares(1, 1), [1], truth.howell_c11(1, 1, 1), "none", 1),
        ("C-11: unit squares 1 apart, contour fix", truth.opposed_squares(1, 1), [1], truth.howell_c11(1, 1, 1), "contour", 1),
        ("C-11: unit squares 1 apart, shooter split 4×4", truth.opposed_squares(1, 1), [1], truth.howell_c11(1, 1, 1),
         "split4", 1),
        ("C-14: unit squares at 90°, no fix", truth.perpendicular_squares(1, 1), [1], truth.howell_c14(1, 1, 1), "none", 1),
        ("C-14: unit squares at 90°, shooter split 4×4", truth.perpendicular_squares(1, 1), [1], truth.howell_c14(1, 1, 1),
         "split4", 1),
        ("C-14: unit squares at 90°, contour fix", truth.perpendicular_squares(1, 1), [1], truth.howell_c14(1, 1, 1), "contour", 1),
    ]
    out = []
    for name, quads, receivers, exact, proximity, seeds in configs:
        for res in resolutions:
            errors, seconds = [], []
            for seed in range(seeds):
                split = 4 if proximity == "split4" else 1
                ff = HemicubeFormFactors(quads, calls(impl), resolution=res, proximity="none" if split > 1 else proximity,
                                         rotate=seeds > 1, seed=seed, shooter_split=split, ctx=ctx)
                ff.tables, ff.renderer               # build the GPU state outside the timing
                t0 = time.perf_counter()
                value = float(ff.row(0)[receivers].sum())
                seconds.append(time.perf_counter() - t0)
                errors.append((value - exact) / exact)
            err = float(np.sqrt(np.mean(np.square(errors))))
            out.append({"config": name, "resolution": res, "exact": exact, "error": err,
                        "seconds_per_row": float(np.median(seconds)), "proximity": proximity, "seeds": seeds})
    return out


def family(impl, ctx, resolution: int = 128, every: int = 1) -> list[dict]:
    """Howell's C-11 and C-14 and coaxial disks (truth.form_factor_family) at one resolution: the error with the
    default options (the proximity fix as it chooses) and with no fix, H6 calls and time per configuration
    (``every``: every that many-th configuration only, for a quick run)."""
    out = []
    for name, quads, shooters, receivers, exact in truth.form_factor_family()[::every]:
        q = np.array(quads, float)
        a = patch_areas(q)[shooters]
        row = {"config": name, "exact": exact}
        for label, options in (("default", {}), ("none", {"proximity": "none"})):
            ff = HemicubeFormFactors(q, calls(impl), resolution=resolution, ctx=ctx, **options)
            t0 = time.perf_counter()
            value = float((a[:, None] * ff.rows(shooters)[:, receivers]).sum() / a.sum())
            row[label] = {"error": value / exact - 1, "seconds": time.perf_counter() - t0,
                          "h6_calls": ff.counters["proximity_evaluations"],
                          "kernel_pairs": ff.counters["proximity_kernel_pairs"], "h6_pairs": ff.counters["proximity_pairs"]}
        out.append(row)
    return out


def print_family(rows: list[dict], resolution: int) -> None:
    """Print :func:`family`'s rows as a table, then the worst error with the default options."""
    print(f"\nHowell C-11, C-14 and coaxial disks at resolution {resolution}: error with the default options "
          "(the proximity fix as it chooses) and with none")
    print(f"{'configuration':44s} {'exact':>8s} {'default':>8s} {'none':>8s} {'H6 pairs':>8s} {'kernel':>6s} "
          f"{'H6 calls':>8s} {'s':>6s}")
    for r in rows:
        d = r["default"]
        print(f"{r['config']:44s} {r['exact']:8.5f} {d['error']:+8.2%} {r['none']['error']:+8.2%} {d['h6_pairs']:8d} "
              f"{d['kernel_pairs']:6d} {d['h6_calls']:8d} {d['seconds']:6.2f}")
    worst = max(rows, key=lambda r: abs(r["default"]["error"]))
    print(f"worst with the default options: {worst['default']['error']:+.2%} ({worst['config']})")


def row_error(F: np.ndarray, ref: np.ndarray) -> float:
    """Mean over rows of the relative L1 error, over rows that see anything."""
    total = ref.sum(axis=1)
    ok = total > 1e-9
    return float(np.mean(np.abs(F[ok] - ref[ok]).sum(axis=1) / total[ok]))


def cornell(impl, resolutions: list[int], reference_resolution: int, k: int, sample_counts: list[int], ctx,
            fix_resolution: int = 128) -> dict:
    """Parts 2 and 3: the Cornell box cut ``k`` × ``k``, its full matrix timed at each resolution and judged on
    every 8th row against ``reference_resolution``; the proximity fix and the 2 × 2 split at ``fix_resolution``;
    ray casting where Embree is installed."""
    quads, _, _ = scene_polygons(load_scene("cornell-box"))
    quads, _ = subdivide_uniform(quads, k)
    n = len(quads)
    probe_rows = list(range(0, n, 8))
    t0 = time.perf_counter()
    ref_ff = HemicubeFormFactors(quads, calls(impl), resolution=reference_resolution, proximity="none", ctx=ctx)
    reference = ref_ff.rows(probe_rows)
    ref_seconds = time.perf_counter() - t0
    hemi = []
    for res in resolutions:
        ff = HemicubeFormFactors(quads, calls(impl), resolution=res, proximity="none", ctx=ctx)
        ff.tables, ff.renderer
        t0 = time.perf_counter()
        F = ff.matrix()
        seconds = time.perf_counter() - t0
        report = ff.report()
        hemi.append({"resolution": res, "seconds_matrix": seconds, "seconds_per_row": seconds / n,
                     "error": row_error(F[probe_rows], reference), "row_sum_min": report["row_sum_min"],
                     "row_sum_max": report["row_sum_max"], "reciprocity_error_total": report["reciprocity_error_total"],
                     "readbacks": report["readbacks"], "patches_culled": report["patches_culled"],
                     "seconds_render": ff.seconds["render"], "seconds_sum": ff.seconds["sum"]})
    # with the proximity fix, once: what it costs and how far it moves the answer
    ff = HemicubeFormFactors(quads, calls(impl), resolution=fix_resolution, proximity="contour", ctx=ctx)
    ff.tables, ff.renderer
    t0 = time.perf_counter()
    ff.matrix()
    fix = {"resolution": fix_resolution, "seconds_matrix": time.perf_counter() - t0, "proximity_pairs": ff.counters["proximity_pairs"],
           "reciprocity_error_total": ff.report()["reciprocity_error_total"]}
    ff = HemicubeFormFactors(quads, calls(impl), resolution=fix_resolution, proximity="none", shooter_split=2, ctx=ctx)
    ff.tables, ff.renderer
    t0 = time.perf_counter()
    ff.matrix()
    fix["split2_seconds_matrix"] = time.perf_counter() - t0
    fix["split2_reciprocity_error_total"] = ff.report()["reciprocity_error_total"]
    rays = []
    if importlib.util.find_spec("embreex") is None:
        print("Embree (embreex, an optional peer) is not installed: the ray-casting comparison is skipped "
              "(pip install -e '.[peers]')")
        sample_counts = []
    for samples in sample_counts:
        t0 = time.perf_counter()
        F = formfactor_matrix_raycast(quads, samples, seed=1, origin="center")
        seconds = time.perf_counter() - t0
        rays.append({"samples": samples, "seconds_matrix": seconds, "seconds_per_row": seconds / n,
                     "error": row_error(F[probe_rows], reference)})
    return {"patches": n, "subdivision": k, "reference_resolution": reference_resolution, "probe_rows": len(probe_rows),
            "reference_seconds": ref_seconds, "hemicube": hemi, "raycast": rays, "proximity_fix": fix}


def time_at_error(points: list[dict], error: float, extrapolate: bool = False) -> float | None:
    """Seconds for the full matrix at ``error``, interpolated log-log between measured points.

    Below the smallest measured error: None, or with ``extrapolate`` the log-log line through the
    two most accurate points (for Monte Carlo, error ∝ 1/√samples ∝ 1/√time).
    """
    pts = sorted((p["error"], p["seconds_matrix"]) for p in points)
    if not pts:
        return None
    if pts[0][0] > error:
        if not extrapolate or len(pts) < 2:
            return None
        (e0, t0), (e1, t1) = pts[0], pts[1]
        slope = (np.log(t1) - np.log(t0)) / (np.log(e1) - np.log(e0))
        return float(np.exp(np.log(t0) + slope * (np.log(error) - np.log(e0))))
    for (e0, t0), (e1, t1) in zip(pts, pts[1:]):
        if e0 <= error <= e1 and e1 > e0:
            w = (np.log(error) - np.log(e0)) / (np.log(e1) - np.log(e0))
            return float(np.exp(np.log(t0) + w * (np.log(t1) - np.log(t0))))
    return min(t for e, t in pts if e <= error)


def main(output: Path, quick: bool = False) -> None:
    """Run every part, print its tables and write ``hemicube.json`` and ``hemicube.png`` in ``output`` (``quick``, a
    small run that shows every part works: resolutions to 64, every fourth of Howell's configurations at 32, the
    box's whole polygons against a converged answer at 128)."""
    output = Path(output)
    output.mkdir(parents=True, exist_ok=True)
    impl = _impl()
    ctx = create_context()
    resolutions = [16, 32, 64] if quick else [16, 32, 64, 128, 256, 512, 1024]
    print(f"hemicube bench on {renderer_name(ctx)}{' (quick)' if quick else ''}\n")

    forms = closed_forms(impl, resolutions, ctx)
    print("Closed-form configurations: relative error |F - exact| / exact, and time per row")
    print(f"{'configuration':48s} " + " ".join(f"{r:>9d}" for r in resolutions))
    for name in dict.fromkeys(f["config"] for f in forms):
        rows = [f for f in forms if f["config"] == name]
        print(f"{name:48s} " + " ".join(f"{f['error']:9.2%}" for f in rows))
    secs = [np.median([f["seconds_per_row"] for f in forms if f["resolution"] == r and f["proximity"] == "none"])
            for r in resolutions]
    print(f"{'time per row (s), two-patch scenes':48s} " + " ".join(f"{s:9.4f}" for s in secs))

    family_resolution = 32 if quick else 128
    howell = family(impl, ctx, family_resolution, every=4 if quick else 1)
    print_family(howell, family_resolution)

    k = 1 if quick else 8
    samples = [250, 1000] if quick else [250, 1000, 4000, 16000, 64000]
    box = cornell(impl, resolutions, 128 if quick else 1024, k, samples, ctx, fix_resolution=64 if quick else 128)
    n = box["patches"]
    print(f"\nCornell box, {n} patches ({k}×{k} per quad): full matrix; error against resolution "
          f"{box['reference_resolution']} on {box['probe_rows']} rows (reference took {box['reference_seconds']:.1f} s)")
    print(f"{'resolution':>10s} {'error':>9s} {'matrix s':>9s} {'ms/row':>8s} {'render s':>9s} {'sum s':>7s} "
          f"{'row sums':>15s} {'recipr.':>8s} {'readbacks':>9s}")
    for h in box["hemicube"]:
        mark = "*" if h["resolution"] == box["reference_resolution"] else " "
        print(f"{h['resolution']:9d}{mark} {h['error']:9.3%} {h['seconds_matrix']:9.2f} {1000 * h['seconds_per_row']:8.2f} "
              f"{h['seconds_render']:9.2f} {h['seconds_sum']:7.2f} {h['row_sum_min']:7.4f}..{h['row_sum_max']:.4f} "
              f"{h['reciprocity_error_total']:8.2%} {h['readbacks']:9d}")
    if any(h["resolution"] == box["reference_resolution"] for h in box["hemicube"]):
        print("  * the reference's own resolution: its error is the noise of batching (float32 tile placement), "
              "not convergence")
    fix = box["proximity_fix"]
    print(f"  with the proximity fix at {fix['resolution']}: {fix['seconds_matrix']:.2f} s, {fix['proximity_pairs']} close pairs, "
          f"reciprocity error {fix['reciprocity_error_total']:.2%}")
    print(f"  with the shooter split 2×2 at {fix['resolution']}: {fix['split2_seconds_matrix']:.2f} s, "
          f"reciprocity error {fix['split2_reciprocity_error_total']:.2%}")
    if not box["raycast"]:
        box["equal_error"] = []
        _finish(output, ctx, quick, forms, box, resolutions, howell)
        return
    hidden = occluded(impl, [r for r in resolutions if r <= 512], ctx, (1,) if quick else (1, 4), quick=quick)
    print_occluded(hidden)
    box["occluded"] = hidden
    print("\nRay casting (Embree, cosine-weighted rays from each patch's centre), same scene, same error measure")
    print(f"{'rays/patch':>10s} {'error':>9s} {'matrix s':>9s} {'ms/row':>8s}")
    for r in box["raycast"]:
        print(f"{r['samples']:10d} {r['error']:9.3%} {r['seconds_matrix']:9.2f} {1000 * r['seconds_per_row']:8.2f}")
    print("\nFull matrix at equal error (seconds; interpolated):")
    equal = []
    for target in (0.10, 0.05, 0.02, 0.01):
        th, tr = time_at_error(box["hemicube"], target), time_at_error(box["raycast"], target)
        extrapolated = tr is None
        if extrapolated:
            tr = time_at_error(box["raycast"], target, extrapolate=True)
        equal.append({"error": target, "hemicube_seconds": th, "raycast_seconds": tr, "raycast_extrapolated": extrapolated})
        fmt = lambda t: "not reached" if t is None else f"{t:.2f}"
        ratio = f"  (hemicube {tr / th:.0f}× faster)" if th and tr else ""
        mark = " (extrapolated)" if extrapolated and tr else ""
        print(f"  error {target:5.0%}: hemicube {fmt(th):>11s}, ray casting {fmt(tr):>11s}{mark}{ratio}")
    box["equal_error"] = equal
    _finish(output, ctx, quick, forms, box, resolutions, howell)


def _finish(output: Path, ctx, quick: bool, forms: list[dict], box: dict, resolutions: list[int],
            howell: list[dict] | None = None) -> None:
    data = {"renderer": renderer_name(ctx), "quick": quick, "closed_forms": forms, "cornell": box, "family": howell}
    (output / "hemicube.json").write_text(json.dumps(data, indent=1))
    _plot(output / "hemicube.png", forms, box, resolutions)
    print(f"\nwrote {output / 'hemicube.json'} and {output / 'hemicube.png'}")


def _plot(path: Path, forms: list[dict], box: dict, resolutions: list[int]) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a, b) = plt.subplots(1, 2, figsize=(12, 4.8))
    for name in dict.fromkeys(f["config"] for f in forms):
        rows = [f for f in forms if f["config"] == name]
        a.loglog([f["resolution"] for f in rows], [max(f["error"], 1e-6) for f in rows], "o-", label=name)
    a.axhline(0.01, color="grey", ls=":", lw=1)
    a.set_xscale("log", base=2)
    a.set_xlabel("hemicube resolution")
    a.set_ylabel("relative error (0 drawn at 1e-6)")
    a.set_title("closed-form configurations")
    a.legend(fontsize=7)
    h, r = box["hemicube"], box["raycast"]
    b.loglog([p["seconds_matrix"] for p in h], [p["error"] for p in h], "o-", label="hemicube")
    for p in h:
        b.annotate(str(p["resolution"]), (p["seconds_matrix"], p["error"]), fontsize=7)
    if r:   # Embree is an optional peer: no line, and no legend entry, without it
        b.loglog([p["seconds_matrix"] for p in r], [p["error"] for p in r], "s-", label="ray casting (Embree)")
    for p in r:
        b.annotate(str(p["samples"]), (p["seconds_matrix"], p["error"]), fontsize=7)
    b.set_xlabel("seconds for the full matrix")
    b.set_ylabel("mean relative row error")
    b.set_title(f"Cornell box, {box['patches']} patches")
    b.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
