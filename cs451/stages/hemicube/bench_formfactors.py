"""``cs451 bench formfactors``: hemicubes per second of the form-factor engine, and where the time goes.

On whatever GL the kit's context gets (named in the first line), the full form-factor matrix of the bundled
radiosity scenes is drawn by each way the engine can run, side by side in one process, alternately, best of
the rounds. The split: drawing (culling on the CPU, the draw calls), reading the atlas back (with any wait for a
software rasteriser still drawing), summing the rows (H5 per hemicube, the atlas reduction on the CPU, or the
device reduction, which includes the wait for the GPU), and the rest (views, the proximity fix, blind patches).
Every configuration's matrix is compared with H5's, drawn patch by patch: the largest difference is printed
(float64 rounding when the hemicubes land in the same tiles, as they do here; with grids, a few cells' delta form
factors where a pixel on a patch edge went to the neighbour, which tests/hemicube/test_formfactor_grids.py shows costs
nothing in accuracy against a finer hemicube).
"""
from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from cs451.formfactors import HemicubeFormFactors
from cs451.gl import create_context, is_software, renderer_name
from cs451.impl import load_impl, resolve_impl
from cs451.scene import load_scene
from cs451.stages import hemicube as H
from cs451.stages import radiosity as R

#: The top-level keys of formfactors.json that the docs and decks read (tests/test_benches.py checks a quick run writes them).
KEYS = ("device", "software", "rounds", "results")

#: (label, cull, reduction, grids): the first is the stage's own way (H5 per hemicube, every face drawn whole,
#: patch by patch), the student's path; the others are the trusted engine's choices. Grids (a polygon's patches
#: drawn as one quad, cs451/formfactors/grids.py) differ from H5's rows on patch-edge pixels only
CONFIGS = (("H5 per hemicube, unculled", False, "stage", False),
           ("atlas reduction, culled", True, "atlas", False),
           ("atlas reduction, unculled", False, "atlas", False),
           ("device reduction, culled", True, "device", False),
           ("device reduction, unculled", False, "device", False),
           ("grids, atlas reduction, culled", True, "atlas", True),
           ("grids, device reduction, unculled", False, "device", True))


def patches_of(scene_name: str) -> tuple[np.ndarray, str]:
    """The scene's patches at its own patch size, and its proximity option (as ``cs451 render`` solves it)."""
    scene = load_scene(scene_name)
    opts = R.STAGE.options(scene)
    radiosity = load_impl(resolve_impl("reference", "radiosity"), "radiosity")
    return R.make_patches(scene, radiosity, opts.patch_size).quads, opts.proximity


def one_matrix(quads: np.ndarray, proximity: str, resolution: int, cull: bool, reduction: str, grids: bool,
               ctx: Any) -> tuple[dict, np.ndarray]:
    """The full matrix by one configuration, with its time split (seconds) and hemicubes per second."""
    calls = H.calls(load_impl(resolve_impl("reference", "hemicube"), "hemicube"))
    ff = HemicubeFormFactors(quads, calls, resolution=resolution, proximity=proximity, batch=256,
                             resample_blind=R.RESAMPLE_BLIND, trusted=True, cull=cull, reduction=reduction, grids=grids,
                             ctx=ctx)
    ff.renderer                                         # the atlas and its programs: not part of the timing
    start = time.perf_counter()
    F = ff.matrix()
    total = time.perf_counter() - start
    draw, readback = ff.renderer.seconds["draw"], ff.renderer.seconds["readback"]
    reduce = ff.seconds["sum"]
    out = {"seconds": total, "hemicubes": ff.counters["hemicubes_rendered"], "readbacks": ff.counters["readbacks"],
           "batch": ff.renderer.batch, "draw": draw, "readback": readback, "reduction": reduce,
           "other": max(0.0, total - draw - readback - reduce), "triangles_per_face":
           ff.renderer.triangles["drawn"] / max(1, 5 * ff.counters["hemicubes_rendered"])}
    out["hemicubes_per_second"] = out["hemicubes"] / total
    return out, F


def main(output: Path, quick: bool = False) -> None:
    """Time every configuration on the bundled scenes (best of the rounds), print each scene's table with its largest
    difference from H5's matrix, and write ``formfactors.json`` in ``output`` (``quick``: one round, the Cornell box at
    resolution 32, to show every configuration runs; not a measurement)."""
    output = Path(output)
    output.mkdir(parents=True, exist_ok=True)
    ctx = create_context()
    device = renderer_name(ctx)
    software = is_software(ctx)
    rounds = 1 if quick else 2
    cases = [("cornell-box", 32)] if quick else [("cornell-box", 128), ("room", 128), ("room", 256)]
    print(f"form-factor bench on {device} ({'a CPU rasteriser' if software else 'a GPU'}); best of {rounds} "
          f"round{'s' if rounds > 1 else ''}, configurations alternating\n")
    results = []
    for scene_name, resolution in cases:
        quads, proximity = patches_of(scene_name)
        best: dict[str, dict] = {}
        truth = None
        for _ in range(rounds):
            for label, cull, reduction, grids in CONFIGS:
                row, F = one_matrix(quads, proximity, resolution, cull, reduction, grids, ctx)
                if label not in best or row["seconds"] < best[label]["seconds"]:
                    best[label] = row
                if reduction == "stage":
                    truth = F
                else:
                    row["max_difference_from_h5"] = float(np.abs(F - truth).max())
                    best[label].setdefault("max_difference_from_h5", row["max_difference_from_h5"])
        base = best[CONFIGS[0][0]]["hemicubes_per_second"]
        print(f"{scene_name}, {len(quads)} patches, resolution {resolution}: the full matrix")
        print(f"{'configuration':34s} {'hemicubes/s':>11s} {'× H5':>6s} {'s':>6s} {'draw':>6s} {'read':>6s} "
              f"{'reduce':>6s} {'other':>6s} {'batch':>5s} {'tris/face':>9s} {'max |ΔF|':>9s}")
        for label, *_ in CONFIGS:
            r = best[label]
            diff = r.get("max_difference_from_h5")
            print(f"{label:34s} {r['hemicubes_per_second']:11.0f} {r['hemicubes_per_second'] / base:6.2f} "
                  f"{r['seconds']:6.2f} {r['draw']:6.2f} {r['readback']:6.2f} {r['reduction']:6.2f} {r['other']:6.2f} "
                  f"{r['batch']:5d} {r['triangles_per_face']:9.0f} {'—' if diff is None else f'{diff:9.1e}':>9s}")
            results.append({"scene": scene_name, "resolution": resolution, "patches": len(quads),
                            "configuration": label, **r})
        print()
    chosen = "grids, atlas reduction, culled" if software else "device reduction, unculled"
    print(f"The engine's choice on this device: {chosen} (radiosity's reference, benches and slides).")
    (output / "formfactors.json").write_text(json.dumps({"device": device, "software": software, "rounds": rounds,
                                                         "results": results}, indent=1))
    print(f"wrote {output / 'formfactors.json'}")
