"""How fast `cs451 demo whitted` refines, against the frame it ends on.

For each bundled Whitted scene at 320×240 on the reference, headless, as the player drives it (``step`` for
``STEP_SECONDS``, then a frame drawn): the time from a fresh demo to the finished picture, the frames shown
on the way (frames per second), and the same after the shadow switch (which replaces W7, so the reference
traces bounce by bounce instead of in its compiled frame). Beside each, the same run's time of one
``render_traced`` of that scene and size (``whitted_frames``, two threads, as the demo runs): the ratio says
what the refinement costs over the frame itself.
"""
from __future__ import annotations

import math
import time
from types import ModuleType

from cs451.demos.player import STEP_SECONDS
from cs451.progress import Progress
from cs451.stages.whitted.demo import WhittedDemo

from .bench_frames import SIZE


def _refine(demo: WhittedDemo) -> tuple[float, int]:
    """Seconds and frames from now until the demo's picture is finished, as the player runs it (its set-up, the
    camera rays and the hierarchy, done before the clock starts: the window shows it as "preparing")."""
    demo.ready()
    start, shown = time.perf_counter(), 0
    while demo.busy():
        demo.step(STEP_SECONDS)
        demo.frame()
        shown += 1
    return time.perf_counter() - start, shown


def demo_speed(impl: ModuleType, quick: bool, render_s: dict[str, float]) -> list[dict]:
    """One row per scene; ``render_s``: each scene's render time at ``SIZE``, measured by ``whitted_frames``."""
    rows = []
    bar = Progress("demo refinement", len(render_s))
    for name in render_s:
        WhittedDemo(impl, name, (32, 24))            # warm up: compile or load the kernels
        frame_s = render_s[name]
        best = {"refine_s": math.inf, "switched_s": math.inf}
        for _ in range(1 if quick else 3):
            demo = WhittedDemo(impl, name, SIZE)
            seconds, shown = _refine(demo)
            if seconds < best["refine_s"]:
                best.update(refine_s=seconds, frames=shown)
            demo.handle(("key", "s"))
            seconds, shown = _refine(demo)
            if seconds < best["switched_s"]:
                best.update(switched_s=seconds, switched_frames=shown)
        rows.append({"scene": name, "frame_s": frame_s, **best, "fps": best["frames"] / best["refine_s"],
                     "refine_over_frame": best["refine_s"] / frame_s})
        bar.advance(note=name)
    bar.close()
    return rows


def print_demo_speed(rows: list[dict]) -> None:
    """Print :func:`demo_speed`'s rows: each scene's render time beside the demo's refinement (seconds, frames,
    fps, the ratio) and the same after the shadow switch."""
    print(f"\ncs451 demo whitted at {SIZE[0]}×{SIZE[1]}, reference, headless: from a fresh demo to the finished picture "
          f"(steps of {STEP_SECONDS * 1e3:.0f} ms, a frame drawn after each), beside one render_traced of the same scene")
    print(f"{'scene':<16} {'render s':>8} {'refine s':>8} {'frames':>6} {'fps':>5} {'refine/render':>13} "
          f"{'shadows off s':>13} {'frames':>6}")
    for r in rows:
        print(f"{r['scene']:<16} {r['frame_s']:>8.3f} {r['refine_s']:>8.2f} {r['frames']:>6} {r['fps']:>5.1f} "
              f"{r['refine_over_frame']:>13.1f} {r['switched_s']:>13.2f} {r['switched_frames']:>6}")
