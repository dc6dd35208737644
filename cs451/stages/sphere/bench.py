"""``cs451 bench sphere``: frame time against error over the sphere's tessellation, Gouraud and Phong.

Error is measured against a converged render (Phong, 512×512 tessellation) of the
same scene; times are per frame, drawing into an offscreen framebuffer after the
buffers are built (the display-list idea), on whatever GL the machine has.
"""
from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from cs451.gl import create_context, renderer_name
from cs451.impl import load_impl, resolve_impl
from cs451.scene import load_scene
from cs451.stages import sphere as s1

#: The top-level keys of sphere.json that the docs and decks read (tests/test_benches.py checks a quick run writes them).
KEYS = ("renderer", "size", "rows")


def _frame_time(ctx, renderer, scene, view, projection, repeats: int) -> float:
    model_views = [view]  # the bundled sphere sits at the origin: its modelview matrix is the view
    renderer.draw(scene, view, model_views, projection, True)
    ctx.finish()
    start = time.perf_counter()
    for _ in range(repeats):
        renderer.draw(scene, view, model_views, projection, True)
        ctx.finish()
    return (time.perf_counter() - start) / repeats


def main(output: Path, quick: bool = False) -> dict:
    """Frame time and error against a converged render (Phong, 512 × 512) for each tessellation and shading: prints
    the table, writes ``sphere.json`` and ``sphere.png`` in ``output``, returns the data (``quick``: fewer repeats)."""
    impl = load_impl(resolve_impl("reference", "sphere"), "sphere")
    scene = load_scene("sphere")
    w, h = scene.image.width, scene.image.height
    ctx = create_context()
    fbo = ctx.framebuffer(color_attachments=[ctx.renderbuffer((w, h), 4)], depth_attachment=ctx.depth_renderbuffer((w, h)))
    fbo.use()
    cam = scene.camera
    viewport, projection = impl.reshape(w, h, cam)
    ctx.viewport = viewport
    view = impl.look_at(cam.eye, cam.center, cam.up)

    def image_of(renderer) -> np.ndarray:
        renderer.draw(scene, view, [view], projection, True)
        ctx.finish()
        return s1._read_pixels(fbo, w, h)

    converged = image_of(s1.SphereRenderer(ctx, impl.phong_shaders(), [impl.sphere_mesh(1.0, 512, 512)]))
    repeats = 5 if quick else 30
    rows = []
    for n in (8, 16, 32, 64, 128, 256):
        for shading in ("gouraud", "phong"):
            shaders = impl.gouraud_shaders() if shading == "gouraud" else impl.phong_shaders()
            renderer = s1.SphereRenderer(ctx, shaders, [impl.sphere_mesh(1.0, n, n)])
            err = np.abs(image_of(renderer) - converged).max(axis=2)
            rows.append({"tessellation": n, "shading": shading, "triangles": 2 * n * (n - 1),
                         "frame_ms": 1000 * _frame_time(ctx, renderer, scene, view, projection, repeats),
                         "mean_error": float(err.mean()), "max_error": float(err.max())})
    base = next(r["frame_ms"] for r in rows if r["tessellation"] == 32 and r["shading"] == "gouraud")
    print(f"stage 1 sphere, {w}×{h}, {renderer_name(ctx)}; error against Phong at 512×512")
    print(f"{'slices=stacks':>13} {'shading':>8} {'triangles':>9} {'frame ms':>9} {'× 32 Gouraud':>13} {'mean err':>9} {'max err':>8}")
    for r in rows:
        print(f"{r['tessellation']:>13} {r['shading']:>8} {r['triangles']:>9} {r['frame_ms']:>9.2f} "
              f"{r['frame_ms'] / base:>13.2f} {r['mean_error']:>9.5f} {r['max_error']:>8.3f}")
    output.mkdir(parents=True, exist_ok=True)
    result = {"renderer": renderer_name(ctx), "size": [w, h], "rows": rows}
    (output / "sphere.json").write_text(json.dumps(result, indent=2))
    _plot(output / "sphere.png", rows, result["renderer"])
    print(f"wrote {output / 'sphere.json'} and {output / 'sphere.png'}")
    return result


def _plot(path: Path, rows: list[dict], renderer: str) -> None:
    """Frame time against mean error, one line per shading, each point labelled with its tessellation."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    for shading, marker in (("gouraud", "o-"), ("phong", "s-")):
        mine = [r for r in rows if r["shading"] == shading]
        ax.loglog([r["frame_ms"] for r in mine], [max(r["mean_error"], 1e-6) for r in mine], marker, label=shading)
        for r in mine:
            ax.annotate(str(r["tessellation"]), (r["frame_ms"], max(r["mean_error"], 1e-6)), fontsize=7)
    ax.set_xlabel("frame time, ms")
    ax.set_ylabel("mean error against Phong at 512 × 512")
    ax.set_title(f"stage 1: tessellation (labels) against error\n{renderer}", fontsize=9)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
