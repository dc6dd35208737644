"""``cs451 bench walkthrough``: one radiosity solve serves every view; a path tracer pays for each.

A camera walks 30 views around the Cornell box's open side (``--quick``: 2 views against a truth of 64 spp, to show
it runs). The kit solves once and draws
each view; Mitsuba 3's path tracer (``scalar_rgb``, an optional peer) renders each view at a few sample counts.
Both are compared per view with a converged Mitsuba render of that view (the truth), wall by wall (mean radiance
over each wall's pixels away from its edges, :func:`cs451.stages.radiosity.bench_peer.wall_means`): the table gives each method's
total time and its worst and mean per-wall error over the views, and the samples per pixel Mitsuba needs for
its worst wall to be within 1%, from its measured error and the 1/√spp law of Monte Carlo noise.
"""
from __future__ import annotations

import dataclasses
import json
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from .bench_peer import mitsuba_cornell, mitsuba_reference, polygon_ids, wall_means
from cs451.impl import load_impl, resolve_impl
from cs451.scene import load_scene
from cs451.stages import radiosity as R

#: The top-level keys of walkthrough.json that the docs and decks read (tests/test_benches.py checks a quick run writes them).
KEYS = ("views", "size", "truth_spp", "solve_seconds", "draw_seconds", "methods")
#: Optional peers it cannot run without (it says so and writes nothing where one is missing).
NEEDS = ("mitsuba",)

SIZE = (128, 128)
TRUTH_SPP = 512
CANDIDATE_SPP = (16, 64)


def views(count: int) -> list[tuple[tuple[str, Any], ...]]:
    """``count`` cameras walking across the box's open side and back, rising and falling, looking at points inside.

    The eye stays within the side walls' planes (x in 48 .. 508) and in front of the opening: a one-sided wall seen
    from behind is black to Mitsuba's diffuse material and coloured to the kit's drawing, a difference of set-up."""
    out = []
    for k in range(count):
        t = k / max(count - 1, 1)
        eye = (278 + 230 * math.sin(2 * math.pi * t), 273 + 150 * math.sin(4 * math.pi * t), -800 + 300 * t)
        center = (278 + 120 * math.cos(2 * math.pi * t), 260.0, 300.0)
        out.append((("eye", eye), ("center", center)))
    return out


MIN_PIXELS = 100      # a wall shown by fewer pixels (after the edge erosion) is not compared: its mean is noise


def wall_errors(image: np.ndarray, truth: np.ndarray, ids: np.ndarray) -> dict[str, float]:
    """Relative error of each wall's mean radiance (channels averaged) against the truth's."""
    from .bench_peer import wall_masks
    big = {w for w, mask in wall_masks(ids).items() if mask.sum() >= MIN_PIXELS}
    ours, theirs = wall_means(image, ids), wall_means(truth, ids)
    return {w: float(np.mean(np.array(ours[w]) / np.maximum(theirs[w], 1e-12)) - 1) for w in big}


def main(output: Path, quick: bool = False) -> dict | None:
    """One radiosity solve drawn from every view against Mitsuba 3 at each sample count, judged per wall against a
    converged Mitsuba render: prints the table, writes ``walkthrough.json``, returns the data (None without Mitsuba)."""
    output = Path(output)
    output.mkdir(parents=True, exist_ok=True)
    try:
        import mitsuba  # noqa: F401
    except ImportError:
        print("Mitsuba 3 is not installed (pip install -e '.[peers]'): the walkthrough needs it for its truth")
        return None
    cameras = views(2 if quick else 30)
    truth_spp = TRUTH_SPP // 8 if quick else TRUTH_SPP          # quick: shows it runs, measures nothing
    base = load_scene("cornell-box")
    scenes = [dataclasses.replace(base, camera=dataclasses.replace(base.camera, **dict(c))) for c in cameras]
    ref = load_impl(resolve_impl("reference", "radiosity"), "radiosity")
    opts = R.STAGE.options(base)

    start = time.perf_counter()
    patches = R.make_patches(base, ref, opts.patch_size)
    solution = R.solve(patches, ref, opts)
    solve_seconds = time.perf_counter() - start
    start = time.perf_counter()
    kit_images = [R.draw_solution(s, ref, patches, solution.display, SIZE, opts.exposure, view=R.camera_view(s))
                  for s in scenes]
    draw_seconds = time.perf_counter() - start

    print(f"walkthrough of the Cornell box: {len(scenes)} views at {SIZE[0]}×{SIZE[1]}; truth: Mitsuba 3 at "
          f"{truth_spp} spp per view")
    rows = {"radiosity (one solve, a draw per view)": {"seconds": solve_seconds + draw_seconds, "errors": []}}
    for spp in CANDIDATE_SPP:
        rows[f"Mitsuba 3, {spp} spp per view"] = {"seconds": 0.0, "errors": [], "spp": spp}
    truth_seconds = 0.0
    for scene, camera, ours in zip(scenes, cameras, kit_images):
        ids = polygon_ids(scene, SIZE)
        truth = mitsuba_reference("cornell-box", SIZE, truth_spp, 64, camera)
        truth_seconds += truth["seconds"]
        rows["radiosity (one solve, a draw per view)"]["errors"].append(wall_errors(ours, truth["image"], ids))
        for spp in CANDIDATE_SPP:
            start = time.perf_counter()
            theirs = mitsuba_cornell(scene, SIZE, spp, 64, seed=1000 + spp)   # seeds apart from the truth's 0 and 1
            row = rows[f"Mitsuba 3, {spp} spp per view"]
            row["seconds"] += time.perf_counter() - start
            row["errors"].append(wall_errors(theirs, truth["image"], ids))
    print(f"{'method':40s} {'total s':>8s} {'worst wall':>10s} {'mean |err|':>10s} {'spp for 1%':>10s}")
    report = {"views": len(scenes), "size": list(SIZE), "truth_spp": truth_spp, "truth_seconds": truth_seconds,
              "solve_seconds": solve_seconds, "draw_seconds": draw_seconds, "methods": {}}
    for name, row in rows.items():
        errs = np.array([abs(e) for view in row["errors"] for e in view.values()])
        worst = float(errs.max())
        needed = row["spp"] * (worst / 0.01) ** 2 if "spp" in row else None
        print(f"{name:40s} {row['seconds']:8.1f} {worst:10.2%} {float(errs.mean()):10.2%} "
              f"{'—' if needed is None else f'{needed:.0f}':>10s}")
        report["methods"][name] = {"seconds": row["seconds"], "worst": worst, "mean": float(errs.mean()),
                                   "spp_for_1_percent": needed, "per_view": row["errors"]}
    mitsuba_64 = report["methods"][f"Mitsuba 3, {CANDIDATE_SPP[-1]} spp per view"]
    if mitsuba_64["spp_for_1_percent"]:
        at_1 = mitsuba_64["seconds"] * mitsuba_64["spp_for_1_percent"] / CANDIDATE_SPP[-1]
        kit = report["methods"]["radiosity (one solve, a draw per view)"]["seconds"]
        print(f"\nMitsuba at the samples its worst wall needs for 1%: about {at_1:.0f} s for the {len(scenes)} views; "
              f"the kit's walkthrough takes {kit / at_1:.2f}× that (its own worst wall: "
              f"{report['methods']['radiosity (one solve, a draw per view)']['worst']:.2%})")
        report["mitsuba_seconds_at_1_percent"] = at_1
    (output / "walkthrough.json").write_text(json.dumps(report, indent=1))
    print(f"wrote {output / 'walkthrough.json'}")
    return report
