"""Solving again after a change of colours or lights (task R6, notes §2.2): what keeping the rows saves.

The Cornell box is solved once at the stage's defaults with the reference's R6 and an empty ``known``; then it is
solved again three ways, each both fresh (a new hemicube engine, as a new ``cs451 render`` would) and through R6
with the rows the earlier solves left in ``known``: the light recoloured, the red wall painted blue, and both.
The table gives the hemicubes each re-solve rendered, its time, and how far its radiosities are from the fresh
solve's (they agree to the float32 precision the hemicube's rows have: the same rows, summed in another order).
"""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from cs451.impl import load_impl, resolve_impl
from cs451.scene import load_scene
from cs451.stages import radiosity as R


def _solve(ref: Any, patches: Any, opts: Any, reflectance: np.ndarray, emission: np.ndarray,
           known: dict | None, rows: Any = None) -> tuple[Any, int, float]:
    """One solve: (solution, hemicubes rendered, seconds)."""
    rows = rows or R.hemicube_formfactors(patches.quads, opts.resolution, opts.proximity, batch=R.ROWS_PER_BATCH)
    before = rows.counters["hemicubes_rendered"]
    start = time.perf_counter()
    sol = R.solve_progressive(ref, rows, patches.areas, reflectance, emission, opts.tolerance, opts.max_shots,
                              opts.overshoot, use_ambient=False, rows_ahead=R.ROWS_PER_BATCH - 1, known=known)
    return sol, rows.counters["hemicubes_rendered"] - before, time.perf_counter() - start


def measure(scene_name: str = "cornell-box", progress=print) -> dict:
    """The scene solved once through R6, then again three ways (the light recoloured, the red wall painted blue,
    both), each fresh and through R6 with the kept rows: hemicubes, seconds and the largest difference."""
    ref = load_impl(resolve_impl("reference", "radiosity"), "radiosity")
    scene = load_scene(scene_name)
    opts = R.STAGE.options(scene)
    patches = R.make_patches(scene, ref, opts.patch_size)
    rho, E = patches.reflectance, patches.emission
    red = [k for k, label in enumerate(patches.labels) if np.argmax(rho[patches.parent == k].mean(axis=0)) == 0
           and rho[patches.parent == k].mean(axis=0)[0] > 1.5 * rho[patches.parent == k].mean(axis=0)[1]]
    if not red:
        raise SystemExit(f"{scene_name}: no red polygon to paint blue")
    blue = rho.copy()
    blue[np.isin(patches.parent, red)] = rho[np.isin(patches.parent, red)][:, ::-1]    # red wall → blue
    changes = {"light recoloured": (rho, E * [1.0, 0.6, 0.3]), "red wall painted blue": (blue, E),
               "both": (blue, E * [1.0, 0.6, 0.3])}
    known: dict = {}
    rows = R.hemicube_formfactors(patches.quads, opts.resolution, opts.proximity, batch=R.ROWS_PER_BATCH)
    first, hemicubes, seconds = _solve(ref, patches, opts, rho, E, known, rows)
    progress(f"  first solve: {len(patches)} patches, {hemicubes} hemicubes, {seconds:.2f} s")
    out = {"scene": scene_name, "patches": len(patches), "resolution": opts.resolution,
           "first": {"hemicubes": hemicubes, "seconds": seconds, "rows_known_after": len(known)}, "cases": []}
    for name, (r, e) in changes.items():
        fresh, fresh_hemicubes, fresh_seconds = _solve(ref, patches, opts, r, e, None)
        again, again_hemicubes, again_seconds = _solve(ref, patches, opts, r, e, known, rows)
        diff = float(np.abs(again.radiosity - fresh.radiosity).max() / np.abs(fresh.radiosity).max())
        out["cases"].append({"change": name, "fresh_hemicubes": fresh_hemicubes, "fresh_seconds": fresh_seconds,
                             "reused_hemicubes": again_hemicubes, "reused_seconds": again_seconds,
                             "rows_known": len(known), "max_difference": diff})
        progress(f"  {name}: fresh {fresh_hemicubes} hemicubes {fresh_seconds:.2f} s; through R6 "
                 f"{again_hemicubes} hemicubes {again_seconds:.2f} s")
    return out


def print_table(result: dict) -> list[str]:
    """Print :func:`measure`'s table (fresh against R6: hemicubes, seconds, speed-up) and return its lines."""
    lines = [f"\nsolving again ({result['scene']}, {result['patches']} patches, resolution {result['resolution']}; "
             f"first solve {result['first']['hemicubes']} hemicubes in {result['first']['seconds']:.2f} s)",
             f"{'change':<24} {'fresh: hemicubes':>17} {'s':>6} {'R6: hemicubes':>14} {'s':>6} {'speed-up':>9} "
             f"{'max |ΔB|/max B':>15}"]
    for c in result["cases"]:
        lines.append(f"{c['change']:<24} {c['fresh_hemicubes']:>17d} {c['fresh_seconds']:>6.2f} "
                     f"{c['reused_hemicubes']:>14d} {c['reused_seconds']:>6.2f} "
                     f"{c['fresh_seconds'] / max(c['reused_seconds'], 1e-9):>8.1f}× {c['max_difference']:>15.1e}")
    print("\n".join(lines))
    return lines


if __name__ == "__main__":
    folder = Path(sys.argv[1] if len(sys.argv) > 1 else "bench-results")
    folder.mkdir(parents=True, exist_ok=True)
    result = measure()
    result["table"] = print_table(result)
    (folder / "solve_again.json").write_text(json.dumps(result, indent=1))
    print(f"wrote {folder / 'solve_again.json'}")
