"""The demos compile nothing after set-up (issue 37): every numba kernel signature the Whitted demo runs (its refinement,
a ray tree, each switch, on a scene of spheres and on a mesh with its hierarchy) is one that set-up's `cs451 warm`
compiles, and numba's on-disk cache index lists it. The other stages' demos run no compiled kernel.

Seconds where set-up has run (the kernels load from numba's cache); on a cold cache this test compiles them first,
as `cs451 warm` would (minutes).
"""
from __future__ import annotations

import io
from typing import Any

import pytest

from cs451 import KIT_ROOT
from cs451.demos.player import play
from cs451.impl import load_impl
from cs451.stages import get_stage, stage_names
from cs451.warm import warm

REF = load_impl(KIT_ROOT / "reference" / "whitted", "whitted")


@pytest.fixture
def signatures(monkeypatch) -> set:
    """Every (kernel, argument types) the reference's speed layer compiles or loads while the test runs."""
    from numba import typeof
    from cs451.stages.whitted.accel import hierarchy, queries, running
    seen: set[tuple[Any, tuple]] = set()
    own = running.compiled

    def compiled(kernel: Any, args: tuple) -> None:
        seen.add((kernel, tuple(typeof(a) for a in args)))
        own(kernel, args)
    for module in (running, hierarchy, queries):
        monkeypatch.setattr(module, "compiled", compiled)
    return seen


def test_the_warm_step_compiles_every_kernel_signature_the_whitted_demo_runs(signatures, tmp_path):
    from cs451.stages.whitted import accel
    from cs451.stages.whitted.accel.hierarchy import HIERARCHIES, LAYOUTS
    from cs451.stages.whitted.demo import WhittedDemo
    accel.forget_compiled()                                          # as in a fresh process, whatever ran before
    HIERARCHIES.clear()
    LAYOUTS.clear()
    warm(["whitted"], stream=io.StringIO())
    warmed = set(signatures)
    signatures.clear()
    for scene, frames in (("whitted", None), ("rippled-torus", 6)):   # 6: the refinement, a ray tree, shadows off
        accel.forget_compiled()                                      # as in a fresh process
        HIERARCHIES.clear()
        LAYOUTS.clear()
        play(WhittedDemo(REF, scene), window=False, frames=frames, output=tmp_path / scene)
    names = {kernel.py_func.__name__ for kernel, _ in signatures}
    assert {"camera", "frame", "closest", "build"} <= names, names
    missing = {(kernel.py_func.__name__, sig) for kernel, sig in signatures - warmed}
    assert not missing, f"the demo compiles what `cs451 warm` does not: {missing}"
    for kernel, sig in signatures:
        index = kernel._cache._cache_file._load_index()          # numba's on-disk index: {(signature, …): file}
        assert sig in {key[0] for key in index}, f"{kernel.py_func.__name__}{sig} is not in numba's cache"


@pytest.mark.spawns
def test_no_other_demo_loads_numba(tmp_path):
    import subprocess
    import sys
    others = [s for s in stage_names() if get_stage(s).accelerator is None]      # the stages without a speed layer
    script = ("import sys; from cs451.demos import run_demo; "
              "[run_demo(stage=s, output=sys.argv[1] + '/' + s, window=False, frames=1, size='48x48') "
              f"for s in {others!r}]; print('numba' in sys.modules)")
    done = subprocess.run([sys.executable, "-c", script, str(tmp_path)], capture_output=True, text=True,
                          timeout=300, cwd=KIT_ROOT)
    assert done.returncode == 0 and done.stdout.strip().splitlines()[-1] == "False", done.stderr[-2000:]
