"""``cs451 bench pathtrace``: the path tracer's error against time at 16, 64 and 256 samples per pixel, beside radiosity.

The Cornell box at 64 × 64 (32 × 32 with ``--quick``). Both methods are compared pixel by pixel with stage 4's
fine solution (patches of 25 scene units, hemicubes of resolution 256, shot to 1e-6): under each pixel's centre
ray, the radiance B/π of the patch it meets. Two errors a row:

- surface error: per visible surface, the mean over its pixels against radiosity's mean over the same pixels
  (relative), averaged over the surfaces weighted by their pixels; noise averages out here, bias does not.
- pixel error: the root mean square of the per-pixel relative difference; the path tracer's noise, which falls as
  1/√spp.

Radiosity's own rows: stage 4 at its defaults (patch size 50, resolution 128), timed to its solution, with the
same two errors against the fine solution. Every time is a fresh run on this machine, side by side in one process.
"""
from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from cs451.impl import load_impl, resolve_impl
from cs451.patches import patch_centers
from cs451.progress import Progress
from cs451.scene import load_scene
from cs451.stages import pathtrace as P
from cs451.stages import radiosity as R
from cs451.stages.pathtrace import paths

#: The top-level keys of pathtrace.json that the docs and decks read (tests/test_benches.py checks a quick run writes them).
KEYS = ("scene", "size", "fine_radiosity_seconds", "rows")


def radiosity_solution(scene, patch_size: float, resolution: int, tolerance: float) -> tuple:
    """Stage 4's reference on the scene: (patches, B, seconds)."""
    impl = load_impl(resolve_impl("reference", "radiosity"), "radiosity")
    opts = R.STAGE.options(scene, patch_size=patch_size, resolution=resolution, tolerance=tolerance,
                           max_shots=1_000_000)
    start = time.perf_counter()
    patches = R.make_patches(scene, impl, opts.patch_size)
    solution = R.solve(patches, impl, opts)
    return patches, solution.radiosity, time.perf_counter() - start


def per_pixel(scene, patches, radiosity: np.ndarray, hits: tuple) -> np.ndarray:
    """The radiance B/π of the patch under each pixel's centre ray (the nearest centre among its surface's patches)."""
    surface, points = hits
    centres = patch_centers(patches.quads)
    out = np.zeros((len(surface), 3))
    for s in np.unique(surface[surface >= 0]):
        mine = np.nonzero(patches.parent == s)[0]
        pixels = np.nonzero(surface == s)[0]
        d = np.linalg.norm(points[pixels, None, :] - centres[None, mine, :], axis=2)
        out[pixels] = radiosity[mine[np.argmin(d, axis=1)]] / np.pi
    return out


def centre_hits(scene, ref, size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Each pixel's surface (stage 4's numbering) and hit point, by the centre ray; -1 where the pixel shows the light,
    nothing, or more than one surface (its corners' rays meet others): a pixel's samples spread over its square, and
    one that straddles an edge mixes two surfaces' light (beside the light, 100 times a wall's)."""
    w, h = size
    ps = paths.build(scene)
    owner = paths.polygon_of_triangles(scene)

    def surface_at(jitter: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
        o, d = ref.camera_rays(scene.camera, w, h, np.tile(jitter, (w * h, 1)))
        t, tri = ref.closest_hit(ps, o, d)
        found = np.where((tri >= 0) & ~ps.emitter[np.maximum(tri, 0)], owner[np.maximum(tri, 0)], -1)
        return found, o + np.where(np.isfinite(t), t, 0.0)[:, None] * d

    surface, points = surface_at((0.5, 0.5))
    for corner in ((0.0, 0.0), (0.999, 0.0), (0.0, 0.999), (0.999, 0.999)):
        surface = np.where(surface_at(corner)[0] == surface, surface, -1)
    return surface, points


def errors(image: np.ndarray, truth: np.ndarray, surface: np.ndarray) -> dict[str, float]:
    """An image's error against the truth, both ``(n, 3)``, over the pixels that show a single surface: per surface
    (its mean colour's relative error, weighted by its pixels) and per pixel (the RMS of relative errors)."""
    seen = surface >= 0
    rel = np.abs(image[seen] - truth[seen]) / np.maximum(truth[seen], 1e-12)
    per_surface, weights = [], []
    for s in np.unique(surface[seen]):
        mine = surface == s
        a, b = image[mine].mean(axis=0), truth[mine].mean(axis=0)
        per_surface.append(float(np.mean(np.abs(a - b) / np.maximum(b, 1e-12))))
        weights.append(int(mine.sum()))
    return {"surface_error": float(np.average(per_surface, weights=weights)),
            "pixel_error": float(np.sqrt(np.mean(rel ** 2)))}


def main(output: Path, quick: bool = False) -> dict:
    """Radiosity at its defaults and path tracing at rising sample counts on the Cornell box, timed and judged against
    a fine radiosity solution: prints the table, writes ``pathtrace.json`` and ``pathtrace.png``, returns the data."""
    scene = load_scene("cornell-box")
    size = (32, 32) if quick else (64, 64)
    spps = (4, 16) if quick else (16, 64, 256)
    ref = load_impl(resolve_impl("reference", "pathtrace"), "pathtrace")
    bar = Progress("pathtrace bench", 2 + len(spps))
    fine = radiosity_solution(scene, 25.0, 256, 1e-6)
    bar.advance(note="fine radiosity")
    hits = centre_hits(scene, ref, size)
    truth = per_pixel(scene, fine[0], fine[1], hits)
    rows = []
    defaults = R.STAGE.options(scene)
    patches, B, seconds = radiosity_solution(scene, defaults.patch_size, defaults.resolution, defaults.tolerance)
    rows.append({"method": "radiosity", "setting": f"patch size {defaults.patch_size:g}, resolution "
                 f"{defaults.resolution}", "seconds": seconds, **errors(per_pixel(scene, patches, B, hits), truth, hits[0])})
    bar.advance(note="radiosity at its defaults")
    for spp in spps:
        start = time.perf_counter()
        image, counters = P.render_traced(scene, ref, size, spp=spp)
        took = time.perf_counter() - start
        rows.append({"method": "path tracing", "setting": f"{spp} spp", "spp": spp, "seconds": took,
                     "bounces_per_path": counters["bounce"] / counters["camera"],
                     **errors(image.reshape(-1, 3), truth, hits[0])})
        bar.advance(note=f"{spp} spp")
    bar.close()
    print(f"stage 5 pathtrace, the Cornell box at {size[0]}×{size[1]}; errors against stage 4's fine solution "
          f"(patch size 25, resolution 256: {fine[2]:.1f} s)")
    print(f"{'method':>13} {'setting':>28} {'seconds':>8} {'surface error':>14} {'pixel error':>12}")
    for r in rows:
        print(f"{r['method']:>13} {r['setting']:>28} {r['seconds']:>8.2f} {r['surface_error']:>14.2%} "
              f"{r['pixel_error']:>12.2%}")
    output.mkdir(parents=True, exist_ok=True)
    result = {"scene": "cornell-box", "size": list(size), "fine_radiosity_seconds": fine[2], "rows": rows}
    (output / "pathtrace.json").write_text(json.dumps(result, indent=2))
    _plot(output / "pathtrace.png", rows, size)
    print(f"wrote {output / 'pathtrace.json'} and {output / 'pathtrace.png'}")
    return result


def _plot(path: Path, rows: list[dict], size: tuple[int, int]) -> None:
    """Time against both errors: the path tracer's line of sample counts, radiosity's point beside it."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    traced = [r for r in rows if r["method"] == "path tracing"]
    for key, marker, label in (("pixel_error", "o-", "path tracing, per pixel"),
                               ("surface_error", "s--", "path tracing, per surface")):
        ax.loglog([r["seconds"] for r in traced], [max(r[key], 1e-5) for r in traced], marker, label=label)
        for r in traced:
            ax.annotate(r["setting"], (r["seconds"], max(r[key], 1e-5)), fontsize=7)
    rad = next(r for r in rows if r["method"] == "radiosity")
    ax.loglog([rad["seconds"]], [max(rad["pixel_error"], 1e-5)], "k^", label="radiosity (defaults), per pixel")
    ax.loglog([rad["seconds"]], [max(rad["surface_error"], 1e-5)], "kv", label="radiosity (defaults), per surface")
    ax.set_xlabel("seconds")
    ax.set_ylabel("relative error against fine radiosity")
    ax.set_title(f"stage 5: the Cornell box at {size[0]}×{size[1]}", fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
