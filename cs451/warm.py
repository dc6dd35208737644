"""``cs451 warm``: pay once, during set-up, what a first render or demo would otherwise pay (setup.sh calls it).

The reference's ray tracer compiles its kernels on first use: minutes on a laptop, which a student's first
``cs451 render whitted`` or a lecturer's first demo must not spend looking hung. Each stage declares the steps
that compile what it needs (``Stage.warm``); this runs them with the reference, one line per step. numba's
cache keeps the result, so a second ``cs451 warm`` loads and takes seconds.
"""
from __future__ import annotations

import sys
import time
from typing import TextIO

from .impl import load_impl, resolve_impl
from .stages import get_stage, stage_names


def warm(stages: list[str] | None = None, impl: str = "reference", stream: TextIO | None = None) -> list[tuple[str, float]]:
    """Run every warming step of ``stages`` (all by default) with ``impl``; returns (step, seconds) for each."""
    stream = stream or sys.stderr
    steps = []
    for name in stages or stage_names():
        st = get_stage(name)
        if st.warm is not None:
            module = load_impl(resolve_impl(impl, name), name)
            steps += [(f"{name}: {what}", do) for what, do in st.warm(module)]
    done = []
    for k, (what, do) in enumerate(steps, 1):
        print(f"warm [{k}/{len(steps)}] {what} ...", file=stream, flush=True)
        start = time.perf_counter()
        do()
        done.append((what, time.perf_counter() - start))
        print(f"warm [{k}/{len(steps)}] {what}: {done[-1][1]:.1f} s", file=stream, flush=True)
    return done
