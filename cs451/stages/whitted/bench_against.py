"""The Whitted reference's compiled kernels against those of an earlier commit, in one process: the same
rays through both, alternating, so that the machine's drift weighs on both alike (``cs451 bench whitted``
compares against Embree and Mitsuba; this compares a change against what it replaced).

    python -m cs451.stages.whitted.bench_against REV        # e.g. HEAD~1, or a commit id

The earlier ``kernels.py`` and ``hierarchy.py`` are read from git into a scratch folder and imported from
there (numba compiles them once, into that folder). For each query the table says whether the answers are
bit-identical and the speed, now against then: the best of the runs and the median of the paired ratios.
"""
from __future__ import annotations

import argparse
import importlib.util
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from types import ModuleType
from typing import Callable

import numpy as np

from cs451 import KIT_ROOT
from cs451.impl import load_impl, resolve_impl
from cs451.progress import Progress
from cs451.scene import load_scene
from cs451.stages import whitted as stage

from .bench import _query_rays, _torus_only
from .bench_kernels import frame_rays, reference_parts


#: Where the speed layer's files were: in the stage's package since issue 35, in the reference before.
HOMES = ("cs451/stages/whitted/accel", "reference/whitted")


def _module_at(rev: str, file_name: str, name: str, folder: Path) -> ModuleType:
    """``file_name`` of the speed layer as it was at ``rev``, imported as ``name`` (its relative imports made
    absolute, to today's running.py and tracescene.py)."""
    errors = []
    for home in HOMES:
        try:
            text = subprocess.run(["git", "-C", str(KIT_ROOT), "show", f"{rev}:{home}/{file_name}"], check=True,
                                  capture_output=True, text=True).stdout
            break
        except subprocess.CalledProcessError as err:
            errors.append(err.stderr.strip())
    else:
        raise SystemExit(f"whitted_against: git has no {file_name} of the Whitted kernels at {rev!r}: {errors[-1]}")
    text = text.replace("from .running import", "from cs451.stages.whitted.accel.running import")
    file = folder / f"{name}.py"
    file.write_text(text.replace("from ....tracescene import", "from cs451.tracescene import"))
    spec = importlib.util.spec_from_file_location(name, file)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def _layout_function(hierarchy: ModuleType) -> Callable:
    """The function that lays a built hierarchy out for the kernels (``four_wide``, ``eight_wide``, ...)."""
    names = [n for n in vars(hierarchy) if n.endswith("_wide") and callable(getattr(hierarchy, n))]
    if len(names) != 1:
        raise SystemExit(f"whitted_against: cannot tell the layout function of that revision's hierarchy.py: {names}")
    return getattr(hierarchy, names[0])


def _paired(then: Callable[[], object], now: Callable[[], object], repeats: int) -> tuple[float, float]:
    """(best then / best now, median of the paired ratios), the two run alternately."""
    best, ratios = [np.inf, np.inf], []
    for _ in range(repeats):
        pair = []
        for fn in (then, now):
            start = time.perf_counter()
            fn()
            pair.append(time.perf_counter() - start)
        best = [min(b, p) for b, p in zip(best, pair)]
        ratios.append(pair[0] / pair[1])
    return best[0] / best[1], float(np.median(ratios))


def _measured(label: str, then: Callable, now: Callable, args: tuple, repeats: int) -> dict:
    """One row: whether then(*args) and now(*args) give the same arrays, and now's speed against then's."""
    same = all(np.array_equal(x, y) for x, y in zip(then(*args), now(*args)))
    best, median = _paired(lambda: then(*args), lambda: now(*args), repeats)
    return {"query": label, "identical": same, "best": best, "median": median}


class _Kernels:
    """One revision's kernels on one scene: closest hit, shadow rays and the whole frame, on one thread."""

    def __init__(self, kernels: ModuleType, ts, tree: tuple, impl: ModuleType):
        ref = reference_parts(impl)
        self.k, self.ts, self.run = kernels, ts, ref.running.in_threads
        self.closest_args = ref.hierarchy.closest_args(ts, tree)
        self.shadow_args = ref.hierarchy.shadow_args(ts, tree)
        self.frame_args = importlib.import_module(impl.__name__ + ".frame").frame_shared(ts, tree)

    def closest(self, o, d):
        n = len(o)
        out = (np.empty(n), np.empty(n, np.int64), np.empty((n, 3)), np.empty((n, 2), np.int64))
        self.run(self.k.closest, n, (o, d), self.closest_args, out, self.k.scratch(), threads=1)
        return out[:3]

    def shadow(self, o, d, length):
        n = len(o)
        out = (np.empty((n, 3)), np.empty((n, 2), np.int64))
        self.run(self.k.transmission, n, (o, d, length), self.shadow_args, out, self.k.scratch(), threads=1)
        return out[:1]

    def frame(self, o, d):
        n = len(o)
        out = (np.empty((n, 3)), np.empty((n, 5), np.int64))
        self.run(self.k.frame, n, (o, d), self.frame_args, out, self.k.scratch(int(self.ts.max_depth)), threads=1)
        return out[0], out[1][:, :3]          # colours, and the rays cast by kind (boxes tested may differ)


def _pair(impl: ModuleType, then_mods: tuple[ModuleType, ModuleType], ts) -> tuple[_Kernels, _Kernels]:
    """The earlier revision's kernels and the working tree's on one scene, each on its own layout of the
    scene's hierarchy (without one, neither reads the rows)."""
    ref = reference_parts(impl)
    then_kernels, then_hierarchy = then_mods
    p = ref.hierarchy.packed(ts)
    tree = p["tree"]
    if hasattr(then_hierarchy, "_layout"):   # that revision's own layout, with or without a hierarchy
        then_tree = then_hierarchy._layout(ts, p["tri"])["tree"]
    elif ts.bvh is None:
        then_tree = tree
    else:
        nf, ni, order, ltri, use = _layout_function(then_hierarchy)(ts.bvh, ts.n_spheres, p["tri"])
        then_tree = (nf.reshape(-1), ni.reshape(-1), order, ltri, use)
    return _Kernels(then_kernels, ts, then_tree, impl), _Kernels(ref.kernels, ts, tree, impl)


def compare(rev: str, repeats: int = 15) -> list[dict]:
    """One row per query (see the module's docstring), on the torus's rays and the three scenes' frames."""
    impl = load_impl(resolve_impl("reference", "whitted"), "whitted")
    rows: list[dict] = []
    bar = Progress(f"Whitted kernels against {rev}", 15)
    with tempfile.TemporaryDirectory() as tmp:
        mods = (_module_at(rev, "kernels.py", "kernels_then", Path(tmp)),
                _module_at(rev, "hierarchy.py", "hierarchy_then", Path(tmp)))
        scene = _torus_only()
        ts = stage.prepare(scene, impl, hierarchy=True)
        then, now = _pair(impl, mods, ts)
        for kind, (o, d) in _query_rays(scene, 480).items():
            o, d = np.ascontiguousarray(o), np.ascontiguousarray(d)
            a = then.closest(o, d)
            hit = a[1] >= 0
            oh, dh = np.ascontiguousarray(o[hit]), np.ascontiguousarray(d[hit])
            length = np.where(hit, a[0] * 0.999, 10.0)
            for label, fa, fb, args in ((f"closest hit, {kind} rays", then.closest, now.closest, (o, d)),
                                        ("  only those that hit", then.closest, now.closest, (oh, dh)),
                                        (f"shadow rays toward the {kind} rays' hits", then.shadow, now.shadow,
                                         (o, d, length))):
                rows.append(_measured(label, fa, fb, args, repeats))
                bar.advance(note=label.strip())
        for name in ("whitted", "cornell-spheres", "rippled-torus"):
            sc = load_scene(name)
            ts = stage.prepare(sc, impl)
            then, now = _pair(impl, mods, ts)
            o, d = (np.ascontiguousarray(a) for a in impl.camera_rays(sc.camera, 320, 240))
            own = frame_rays(reference_parts(impl), ts, o, d)   # the frame's own queries, each through its kernel
            queries = [(f"whole frame, {name} 320×240", then.frame, now.frame, (o, d)),
                       ("  its closest-hit queries", then.closest, now.closest, own["closest"]),
                       ("  its shadow rays", then.shadow, now.shadow, own["shadow"])]
            for label, fa, fb, args in queries:
                rows.append(_measured(label, fa, fb, args, repeats))
                bar.advance(note=label.strip())
    bar.close()
    return rows


def main() -> None:
    """The command line (``REV``, ``--repeats``): the working tree's kernels against REV's, printed as a table of
    same answers and speed (not a ``cs451 bench`` command: it takes no ``output``)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("rev", help="the earlier commit (anything git names: HEAD~1, a commit id)")
    parser.add_argument("--repeats", type=int, default=15, help="alternating pairs per query")
    args = parser.parse_args()
    rows = compare(args.rev, args.repeats)
    print(f"the working tree's Whitted kernels against {args.rev}'s, 1 thread, {args.repeats} alternating pairs")
    print(f"{'query':<44} {'same answers':>12} {'speed (best)':>12} {'(median pair)':>13}")
    for r in rows:
        print(f"{r['query']:<44} {str(r['identical']):>12} {r['best']:>11.3f}× {r['median']:>12.3f}×")


if __name__ == "__main__":
    main()
