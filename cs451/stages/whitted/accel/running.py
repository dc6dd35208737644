"""Running the reference's compiled kernels: compiled once (numba's on-disk cache keeps them for later
runs, and the first compile says so), then over chunks of rays in threads. A student's starter has no copy of it.
"""
from __future__ import annotations

import sys
import time
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np

#: What compiling a render's kernels (the hierarchy build and the frame) took on the kit's two-core test
#: machine, numba 0.68 (115-122 s, from a fresh clone and from the wheel); the closest-hit and shadow kernels
#: (the demo's ray trees, tests, bench) take ~85 s more.
COMPILE_SECONDS = 120
_said = [False]


def _say_compiling() -> Any:
    """A numba event listener: the first real compile (not a load from the cache) prints one line."""
    from numba.core import event

    class SayCompiling(event.Listener):
        def on_start(self, event: Any) -> None:
            _say()

        def on_end(self, event: Any) -> None:
            pass

    return SayCompiling()


def _say() -> None:
    from ....progress import quiet
    if not _said[0]:
        _said[0] = True
        if quiet():
            return
        print(f"compiling the ray tracer's kernels, once (~{COMPILE_SECONDS} s on two cores; later runs load them "
              f"from numba's cache)", file=sys.stderr, flush=True)


#: Per kernel, the argument fingerprints already compiled: a frame's 31 arguments take ~7 µs to fingerprint
#: and ~270 µs to type with ``numba.typeof``, about 1% of a 320×240 frame of the whitted scene, on every call.
_READY: dict[Any, set] = {}


def _fingerprints(args: tuple) -> tuple | None:
    """Numba's own per-value type fingerprints (what its dispatcher matches calls by), or None where numba
    has none for some argument or lacks the function (it is internal): then ``compiled`` types every call."""
    try:
        from numba._dispatcher import compute_fingerprint
        return tuple(compute_fingerprint(a) for a in args)
    except Exception:
        return None


def compiled(kernel: Any, args: tuple) -> None:
    """Compile (or load from numba's cache) kernel for these arguments with LLVM's SLP vectoriser on.

    Numba leaves it off by default; it lets ``kernels._slabs8`` test eight boxes in a few vector
    instructions. The switch is numba's own config value, set only while this compiles (results are the
    same either way).
    """
    key = _fingerprints(args)
    ready = _READY.setdefault(kernel, set())
    if key is not None and key in ready:
        return
    from numba import typeof
    from numba.core import config, event
    sig = tuple(typeof(a) for a in args)
    if sig in kernel.overloads:
        if key is not None:
            ready.add(key)
        return
    old = config.SLP_VECTORIZE
    config.SLP_VECTORIZE = 1
    start = time.perf_counter()
    try:
        with event.install_listener("numba:compile", _say_compiling()):
            kernel.compile(sig)
    finally:
        config.SLP_VECTORIZE = old
    if key is not None:
        ready.add(key)
    from ....progress import quiet
    if _said[0] and time.perf_counter() - start > 1.0 and not quiet():
        print(f"  {kernel.__name__}: {time.perf_counter() - start:.0f} s", file=sys.stderr, flush=True)


#: Threads the kernels run in unless told otherwise (the bench sets 1 and 2 in turn).
THREADS = 2


def in_threads(kernel: Any, n: int, row_args: tuple, shared: tuple, outs: tuple, scratch: tuple,
               threads: int | None = None, chunks: int = 4) -> None:
    """Run ``kernel(*rows, *shared, *outs, *scratch)`` over ``threads · chunks`` runs of the n rays, in threads.

    The kernels release the GIL. ``row_args`` and ``outs`` are split by rows; ``shared`` goes whole;
    each run gets its own copy of the ``scratch`` arrays (working memory). ``threads``: THREADS by default.
    """
    threads = THREADS if threads is None else threads
    compiled(kernel, (*row_args, *shared, *outs, *scratch))
    if n < 4096 or threads <= 1:
        kernel(*row_args, *shared, *outs, *scratch)
        return
    bounds = np.linspace(0, n, threads * chunks + 1).astype(int)

    def run(k: int) -> None:
        s, e = bounds[k], bounds[k + 1]
        kernel(*(a[s:e] for a in row_args), *shared, *(a[s:e] for a in outs), *(np.empty_like(a) for a in scratch))

    with ThreadPoolExecutor(threads) as pool:
        list(pool.map(run, range(len(bounds) - 1)))
