"""``cs451 bench tolerance``: how far a correct render can move between machines, against the image tolerance.

The reference renders every image test's scene again under other rasterisers and
thread counts and each render is compared with the default llvmpipe render the
autograder uses, with the autograder's own comparison. Mesa's softpipe stands in
for "another GPU": an independent rasteriser with its own precision and rules.
An NVIDIA run is added where a device is lent (see docs/tolerances.md).
"""
from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from cs451 import KIT_ROOT
from cs451.compare import compare_images
from cs451.grading.checks import image_tolerance
from cs451.grading.expected import ReferenceAnswers
from cs451.grading.loader import load_tests
from cs451.grading.runner import run_trusted_probe
from cs451.impl import resolve_impl
from cs451.stages import stage_names

#: The keys of each row of tolerance.json that the docs read (tests/test_benches.py checks a quick run writes them).
KEYS = ("stage", "test", "variant", "raw_max")

VARIANTS = {  # name: environment for the reference's worker
    "llvmpipe, 1 thread": {"LP_NUM_THREADS": "1"},
    "llvmpipe, 2 threads": {"LP_NUM_THREADS": "2"},
    "llvmpipe, 8 threads": {"LP_NUM_THREADS": "8"},
    "llvmpipe, again": {},
    "softpipe": {"GALLIUM_DRIVER": "softpipe"},
}


def _render(stage: str, test, inputs, env: dict[str, str]) -> np.ndarray:
    saved = {k: os.environ.get(k) for k in env}
    os.environ.update(env)
    try:
        result = run_trusted_probe(stage, resolve_impl("reference", stage), test.probe, test.params, inputs,
                                   timeout=600)
    finally:
        for k, v in saved.items():
            os.environ.pop(k, None) if v is None else os.environ.__setitem__(k, v)
    if not result.ok:
        raise RuntimeError(f"{test.number}: {result.error}")
    return result.outputs["image"]


def main(output: Path, quick: bool = False) -> None:
    rows = []
    for stage in stage_names():
        if not (KIT_ROOT / "autograder" / stage / "public.py").exists():
            continue
        reference = ReferenceAnswers(stage)
        imaged = [t for t in load_tests(stage) if t.expected == "reference" and image_tolerance(t.check) is not None]
        for test in imaged[:1] if quick else imaged:       # quick: a stage's first image test, to show it runs
            tol = image_tolerance(test.check)
            inputs = reference.get(test.given, test.params) if test.given else None
            base = reference.get(test.probe, test.params, inputs)["image"]
            for name, env in VARIANTS.items():
                if quick and name not in ("llvmpipe, again", "softpipe"):
                    continue
                img = _render(stage, test, inputs, env)
                raw = float(np.abs(img.astype(float) - base.astype(float)).max())
                cmp = compare_images(base, img, tol) if tol else None
                rows.append({"stage": stage, "test": test.number, "variant": name, "raw_max": raw,
                             "shifted_max": cmp.max_error if cmp else None,
                             "bad_fraction": cmp.bad_fraction if cmp else None,
                             "bad_pixels": int((cmp.error_map > tol.threshold).sum()) if cmp else None,
                             "pixels": int(base.shape[0] * base.shape[1]),
                             "threshold": tol.threshold if tol else None,
                             "allowed_fraction": tol.max_bad_fraction if tol else None,
                             "passes": cmp.passed if cmp else None})
    print(f"{'stage':<10} {'test':<6} {'variant':<20} {'raw max':>8} {'3×3 max':>8} {'bad px':>12} {'allowed':>12}  ok")
    for r in rows:
        allowed = f"{r['threshold']:g}/{r['allowed_fraction']:.0%}" if r["threshold"] is not None else "?"
        print(f"{r['stage']:<10} {r['test']:<6} {r['variant']:<20} {r['raw_max']:>8.4f} "
              f"{(r['shifted_max'] or 0):>8.4f} {r['bad_pixels'] or 0:>5}/{r['pixels']:<6} {allowed:>12}  "
              f"{'yes' if r['passes'] else 'NO'}")
    worst = max((r["bad_fraction"] or 0) / r["allowed_fraction"] for r in rows if r["allowed_fraction"])
    print(f"worst case uses {worst:.1%} of the allowed fraction of bad pixels "
          f"(margin ×{1 / worst:.0f})" if worst else "every variant is identical after the 3×3 shift")
    output.mkdir(parents=True, exist_ok=True)
    (output / "tolerance.json").write_text(json.dumps(rows, indent=2))
    print(f"wrote {output / 'tolerance.json'}")
