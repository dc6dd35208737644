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

from cs451 import import_from_kit
from cs451.formfactors import HemicubeFormFactors, formfactor_matrix_raycast
from cs451.patches import scene_polygons
from cs451.scene import load_scene
from cs451.stages.hemicube import calls

subdivide_uniform = import_from_kit("bench.meshes").subdivide_uniform    # the kit's fine meshes (bench/)


TRUTH_RAYS = 400_000


def _row_error(F: np.ndarray, ref: np.ndarray) -> float:
    total = ref.sum(axis=1)
    ok = total > 1e-9
    return float(np.mean(np.abs(F[ok] - ref[ok]).sum(axis=1) / total[ok]))


def occluded(impl, resolutions: list[int], ctx, subdivisions: tuple[int, ...] = (1, 4), quick: bool = False) -> list[dict]:
    """Rows of the Cornell box (each quad cut k × k for k in ``subdivisions``), every method, timed, with errors
    (``quick``: the proximity fix and the split shooter at the smallest resolution only)."""
    out = []
    for k in subdivisions:
        quads, _ = subdivide_uniform(scene_polygons(load_scene("cornell-box"))[0], k)
        rows = list(range(len(quads))) if len(quads) <= 64 else list(range(0, len(quads), max(1, len(quads) // 64)))
        t0 = time.perf_counter()
        truth = formfactor_matrix_raycast(quads, TRUTH_RAYS, seed=11, rows=rows)
        truth_seconds = time.perf_counter() - t0
        methods = [("hemicube", r, dict(proximity="none")) for r in resolutions]
        fixed = resolutions[:1] if quick else [r for r in resolutions if r <= 256]
        methods += [("proximity fix", r, dict(proximity="contour")) for r in fixed]
        methods += [("shooter split 4×4", resolutions[0] if quick else 128, dict(proximity="none", shooter_split=4))]
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
    """Print :func:`occluded`'s rows as a table, with the floor's row sum beside the truth's where it was measured."""
    print("\nOccluded: the Cornell box against the area average (ray casting from random points, "
          f"{TRUTH_RAYS:,} rays a patch)")
    print(f"{'patches':>7s} {'method':18s} {'res':>5s} {'rows':>5s} {'seconds':>8s} {'row error':>9s} {'worst F':>8s} "
          f"{'floor sum':>9s}")
    for r in results:
        floor = "" if r["floor_row_sum"] is None else f"{r['floor_row_sum']:.4f}/{r['floor_truth']:.4f}"
        print(f"{r['patches']:7d} {r['method']:18s} {r['resolution']:5d} {r['rows']:5d} {r['seconds']:8.2f} "
              f"{r['error']:9.2%} {r['worst_entry']:8.4f} {floor:>9s}")


# --- the slides' record: `cs451 slides record hemicube` ----------------------------------------------------

def embree_available() -> bool:
    """Whether embreex (Embree, an optional peer) is installed: the slides' record casts its rays with it if so."""
    import importlib.util
    return importlib.util.find_spec("embreex") is not None


_KERNEL: list = []


def _closest_kernel():
    """A compiled brute-force closest hit (numba, compiled once, in a second): every ray against every triangle,
    Möller-Trumbore, either side, t > 0."""
    if not _KERNEL:
        from numba import njit

        @njit(cache=False, nogil=True)
        def closest(v0, e1, e2, o, d, t_out, k_out):           # pragma: no cover - compiled
            for r in range(o.shape[0]):
                best, found = np.inf, -1
                for m in range(v0.shape[0]):
                    px = d[r, 1] * e2[m, 2] - d[r, 2] * e2[m, 1]
                    py = d[r, 2] * e2[m, 0] - d[r, 0] * e2[m, 2]
                    pz = d[r, 0] * e2[m, 1] - d[r, 1] * e2[m, 0]
                    det = px * e1[m, 0] + py * e1[m, 1] + pz * e1[m, 2]
                    if det == 0.0:
                        continue
                    inv = 1.0 / det
                    wx, wy, wz = o[r, 0] - v0[m, 0], o[r, 1] - v0[m, 1], o[r, 2] - v0[m, 2]
                    a = (wx * px + wy * py + wz * pz) * inv
                    if a < 0.0 or a > 1.0:
                        continue
                    qx = wy * e1[m, 2] - wz * e1[m, 1]
                    qy = wz * e1[m, 0] - wx * e1[m, 2]
                    qz = wx * e1[m, 1] - wy * e1[m, 0]
                    b = (d[r, 0] * qx + d[r, 1] * qy + d[r, 2] * qz) * inv
                    if b < 0.0 or a + b > 1.0:
                        continue
                    t = (e2[m, 0] * qx + e2[m, 1] * qy + e2[m, 2] * qz) * inv
                    if 0.0 < t < best:
                        best, found = t, m
                t_out[r] = best
                k_out[r] = found
        _KERNEL.append(closest)
    return _KERNEL[0]


def _closest(tris: np.ndarray, o: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Brute-force closest hit (t > 0, either side) of rays against triangles: (t, triangle), inf and -1 for a
    miss. Enough for whole polygons: a few dozen triangles."""
    t, k = np.empty(len(o)), np.empty(len(o), dtype=np.int64)
    v0 = np.ascontiguousarray(tris[:, 0], dtype=np.float64)
    e1 = np.ascontiguousarray(tris[:, 1] - tris[:, 0], dtype=np.float64)
    e2 = np.ascontiguousarray(tris[:, 2] - tris[:, 0], dtype=np.float64)
    _closest_kernel()(v0, e1, e2, np.ascontiguousarray(o, dtype=np.float64), np.ascontiguousarray(d, dtype=np.float64),
                      t, k)
    return t, k


def _inverse_bilinear(x: np.ndarray, quads: np.ndarray) -> np.ndarray:
    """(s, t) in [0, 1]² of points ``x`` (n, 3) on their planar quads (n, 4, 3), for the bilinear map of
    bench.meshes.subdivide_uniform: (1-s)(1-t)a + s(1-t)b + st·c + (1-s)t·d."""
    normal = np.cross(quads[:, 2] - quads[:, 0], quads[:, 3] - quads[:, 1])       # the diagonals' cross product
    drop = np.argmax(np.abs(normal), axis=1)                    # project on the two other axes
    keep = np.array([[1, 2], [0, 2], [0, 1]])[drop]
    rows = np.arange(len(x))[:, None]
    a, b, c, d = (quads[:, i][rows, keep] for i in range(4))
    h = x[rows, keep] - a
    e, f, g = b - a, d - a, a - b + c - d

    def cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
        return u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]
    k2, k1, k0 = cross(g, f), cross(e, f) + cross(h, g), cross(h, e)
    with np.errstate(divide="ignore", invalid="ignore"):
        # k2 t² + k1 t + k0 = 0, its roots in the stable form: k0 / q is the one left when k2 → 0 (a parallelogram)
        q = -0.5 * (k1 + np.copysign(np.sqrt(np.maximum(k1 * k1 - 4 * k0 * k2, 0.0)), k1))
        t = k0 / q
        other = q / k2
        t = np.where(np.isfinite(t) & (t >= -1e-6) & (t <= 1 + 1e-6), t, other)
        across = e + g * t[:, None]
        axis = np.argmax(np.abs(across), axis=1)
        n = np.arange(len(x))
        s = (h[n, axis] - f[n, axis] * t) / across[n, axis]
    return np.clip(np.c_[s, t], 0.0, 1.0 - 1e-12)


def raycast_numpy(polygons: np.ndarray, k: int, samples: int, seed: int, rows: list[int]) -> np.ndarray:
    """Form factors F_ij of the polygons cut k × k (bench.meshes.subdivide_uniform's patches), by Monte Carlo ray
    casting on the CPU (numpy, and a small compiled kernel for the hits): ``samples`` cosine-weighted rays per patch from uniformly random points of it (the area
    average, as :func:`cs451.formfactors.formfactor_matrix_raycast` with ``origin="area"``). Rays are cast against
    the whole polygons and a hit is placed in its patch by the subdivision's own map, so the cost does not grow with
    k. The kit's ray caster where Embree (an optional peer) is not installed. Returns (len(rows), n·k²)."""
    from cs451.formfactors.raycast import cosine_rays
    from cs451.patches import patch_normals, patch_triangles
    quads, _ = subdivide_uniform(polygons, k)
    n = len(quads)
    tris, ids = patch_triangles(polygons)
    normals = patch_normals(polygons)
    sub_tris, _ = patch_triangles(quads)
    sub_normals = patch_normals(quads)
    tri_area = 0.5 * np.linalg.norm(np.cross(sub_tris[:, 1] - sub_tris[:, 0], sub_tris[:, 2] - sub_tris[:, 0]), axis=1)
    rng = np.random.default_rng(seed)
    out = np.zeros((len(rows), n))
    chunk = max(1, 1_000_000 // max(samples, 1))
    for start in range(0, len(rows), chunk):
        block = rows[start:start + chunk]
        m = len(block)
        b = np.repeat(np.array(block), samples)
        o, d = cosine_rays(sub_tris, tri_area, sub_normals, b, rng)
        hit_t, tri = _closest(tris, o, d)
        hit = tri >= 0
        polygon = ids[np.where(hit, tri, 0)]
        front = hit & (np.einsum("ij,ij->i", d, normals[polygon]) < 0)
        if k == 1:
            j = polygon[front]
        else:
            st = _inverse_bilinear(o[front] + hit_t[front, None] * d[front], polygons[polygon[front]])
            j = polygon[front] * k * k + (st[:, 0] * k).astype(int) * k + (st[:, 1] * k).astype(int)
        key = np.repeat(np.arange(m), samples)[front] * n + j
        out[start:start + m] = np.bincount(key, minlength=m * n).reshape(m, n) / samples
    return out


#: what `cs451 slides record hemicube` measures (full; --quick: the tests' small run)
SLIDE = {False: {"subdivisions": (1, 4), "resolutions": (16, 32, 64, 128, 256, 512), "fix": (32, 128),
                 "split": (32, 64, 128), "rays": (1000, 4000, 16000, 64000), "truth_rays": TRUTH_RAYS},
         True: {"subdivisions": (1,), "resolutions": (16, 32), "fix": (), "split": (16,), "rays": (200, 800),
                "truth_rays": 4000}}
SLIDE_COLUMNS = {
    "patches": "patches of the Cornell box (its 16 polygons, each cut k × k)",
    "subdivision": "k: each polygon cut k × k",
    "method": "hemicube (no fix); proximity fix (H6 over the shooter, the stage's default); shooter split 4×4 "
              "(16 hemicubes a row); ray casting (Monte Carlo from random points of the shooter)",
    "setting": "hemicube resolution, or rays per patch for ray casting",
    "rows": "rows of F computed (all rows, or every n/64-th)",
    "seconds": "median wall-clock seconds for those rows (GPU state built before the clock starts)",
    "seconds_min": "fastest of the repeats", "seconds_max": "slowest of the repeats",
    "error": "mean over rows of Σ_j |F_ij − F*_ij| / Σ_j F*_ij against the area-averaged truth F*",
    "worst_entry": "largest |F_ij − F*_ij|",
}


def slide_record(quick: bool = False, repeats: int = 3) -> dict:
    """The hemicube deck's time-against-error record (``cs451 slides record hemicube``): the Cornell box where
    patches hide each other, as whole polygons and cut 4 × 4, every method timed ``repeats`` times one after
    another (median, fastest, slowest) on the same rows, its error against the area average F* (ray casting from
    random points of each shooter: Embree where embreex is installed, else :func:`raycast_numpy`; its own noise
    measured from two independent halves)."""
    from cs451.gl import create_context, renderer_name
    from cs451.impl import load_impl, resolve_impl
    from cs451.formfactors import formfactor_matrix_raycast
    from cs451.progress import Progress

    plan = SLIDE[quick]
    impl = load_impl(resolve_impl("reference", "hemicube"), "hemicube")
    ctx = create_context()
    embree = embree_available()
    caster = ("Embree 4 through embreex" if embree else
              "the kit's CPU ray caster (cs451.stages.hemicube.bench_occluded.raycast_numpy: Embree, an optional peer, "
              "is not installed)")
    polygons = scene_polygons(load_scene("cornell-box"))[0]
    out, truths = [], {}
    steps = len(plan["subdivisions"]) * (1 + len(plan["resolutions"]) + len(plan["fix"]) + len(plan["split"])
                                         + len(plan["rays"]))
    bar = Progress("hemicube: time against error", steps)
    try:
        for k in plan["subdivisions"]:
            quads, _ = subdivide_uniform(polygons, k)
            n = len(quads)
            rows = list(range(n)) if n <= 64 else list(range(0, n, n // 64))

            def cast(samples: int, seed: int) -> np.ndarray:
                if embree:
                    return formfactor_matrix_raycast(quads, samples, seed=seed, rows=rows)
                return raycast_numpy(polygons, k, samples, seed, rows)
            bar.advance(0, note=f"{n} patches: the truth")
            start = time.perf_counter()
            halves = [cast(plan["truth_rays"] // 2, seed) for seed in (11, 12)]
            truth = 0.5 * (halves[0] + halves[1])
            truths[str(n)] = {"rays_per_patch": plan["truth_rays"], "seconds": time.perf_counter() - start,
                              "noise": _row_error(halves[0], halves[1]) / 2, "rows": len(rows),
                              "floor_row_sum": float(truth[0].sum())}
            bar.advance(note=f"{n} patches: the truth")
            methods = [("hemicube", r, dict(proximity="none")) for r in plan["resolutions"]]
            methods += [("proximity fix", r, dict(proximity="contour")) for r in plan["fix"]]
            methods += [("shooter split 4×4", r, dict(proximity="none", shooter_split=4)) for r in plan["split"]]
            methods += [("ray casting", s, None) for s in plan["rays"]]
            for name, setting, options in methods:
                seconds = []
                for _ in range(repeats):
                    if options is None:
                        start = time.perf_counter()
                        F = cast(setting, 3)
                    else:
                        ff = HemicubeFormFactors(quads, calls(impl), resolution=setting, rotate=False, ctx=ctx,
                                                 **options)
                        ff.tables, ff.renderer               # the GPU state, built before the clock starts
                        start = time.perf_counter()
                        F = ff.rows(rows)
                    seconds.append(time.perf_counter() - start)
                out.append({"patches": n, "subdivision": k, "method": name, "setting": setting, "rows": len(rows),
                            "seconds": float(np.median(seconds)), "seconds_min": min(seconds),
                            "seconds_max": max(seconds), "error": _row_error(F, truth),
                            "worst_entry": float(np.abs(F - truth).max())})
                bar.advance(note=f"{n} patches: {name} {setting}")
    finally:
        bar.close()
    return {"rows": out, "columns": SLIDE_COLUMNS, "gl_renderer": renderer_name(ctx),
            "params": {"scene": "cornell-box", "ray_caster": caster, "embree": embree, "truth": truths,
                       "error": SLIDE_COLUMNS["error"], "rotate": False}}
