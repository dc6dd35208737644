"""The main job's time, split: where ``cs451 render SCENE`` spends its seconds on the bundled radiosity scenes.

``cs451 bench radiosity`` prints this table first. Each scene is rendered twice: as a user runs it (a fresh
process, ``python -m cs451 render SCENE``, wall clock from start to exit), and in this process with the rows
timed as they are fetched, which splits the solve into form factors (drawing and reading back hemicubes,
summing rows: the engine's own clocks) and the shooting loop (the solve less the time inside row fetches).
"""
from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from cs451.scene import load_scene
from cs451.stages import radiosity as R

#: the scenes of the main job, in the order the table shows them
SCENES = ("cornell-box", "room")


class TimedRows:
    """A row source that counts the seconds spent inside it (the engine's work, rows ahead included)."""

    def __init__(self, rows: Any):
        self.source, self.seconds = rows, 0.0

    def _timed(self, fn: Any, *args: Any) -> Any:
        start = time.perf_counter()
        try:
            return fn(*args)
        finally:
            self.seconds += time.perf_counter() - start

    def row(self, i: int) -> Any:
        """Row ``i`` of the source, its seconds counted."""
        return self._timed(self.source.row, i)

    def rows(self, indices: Any) -> Any:
        """Rows ``indices`` of the source in one batch, ``(k, n)``, its seconds counted."""
        return self._timed(self.source.rows, indices)

    def has_row(self, i: int) -> bool:
        """Whether the source holds row ``i`` already (untimed: no work), so that rows ahead batch as they would
        without the timer."""
        return self.source.has_row(i)

    def matrix(self) -> Any:
        """The source's full matrix ``(n, n)``, its seconds counted."""
        return self._timed(self.source.matrix)

    @property
    def counters(self) -> dict:
        """The source's own counters (rows computed, read-backs), which the solve reports."""
        return self.source.counters


def split(ref: Any, scene_name: str) -> dict:
    """One solve of a bundled scene at its own options, with the time split (seconds)."""
    scene = load_scene(scene_name)
    opts = R.STAGE.options(scene)
    start = time.perf_counter()
    patches = R.make_patches(scene, ref, opts.patch_size)
    subdivide = time.perf_counter() - start
    engine = R.hemicube_formfactors(patches.quads, opts.resolution, opts.proximity, batch=R.ROWS_PER_BATCH_MOST)
    rows = TimedRows(engine)
    sol = R.solve(patches, ref, opts, rows=rows)
    start = time.perf_counter()
    R.draw_solution(scene, ref, patches, sol.display, None, opts.exposure)
    draw = time.perf_counter() - start
    return {"scene": scene_name, "patches": len(patches), "shots": sol.steps, "rows": engine.counters["rows_computed"],
            "solve": sol.seconds, "rows_seconds": rows.seconds, "loop": sol.seconds - rows.seconds,
            "render": engine.seconds["render"], "sum": engine.seconds["sum"], "proximity": engine.seconds["proximity"],
            "readbacks": engine.counters["readbacks"], "subdivide": subdivide, "draw": draw}


def as_a_user_runs_it(scene_name: str) -> float:
    """Wall-clock seconds of ``python -m cs451 render SCENE -o ...`` in a fresh process."""
    with tempfile.TemporaryDirectory(prefix="cs451-bench-") as folder:
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "cs451", "render", scene_name, "-o", str(Path(folder) / "out.png")],
                       check=True, capture_output=True)
        return time.perf_counter() - start


def measure(ref: Any) -> list[dict]:
    """The split of every main-job scene, and its wall clock as a user runs it."""
    out = []
    for name in SCENES:
        row = split(ref, name)
        row["wall"] = as_a_user_runs_it(name)
        out.append(row)
    return out


def print_split(rows: list[dict]) -> list[str]:
    """The table, printed and returned as lines."""
    lines = ["", "The main job, `cs451 render SCENE` (seconds): wall clock of a fresh process, and the solve split into "
                 "form factors (rows fetched: hemicubes set up, drawn and read back; summed; proximity fix) and the shooting loop"]
    lines.append(f"{'scene':<12} {'patches':>7} {'shots':>6} {'rows':>5} {'wall':>6} {'solve':>6} {'rows s':>7} "
                 f"{'hemicubes':>9} {'sum':>5} {'prox':>5} {'loop':>5} {'loop %':>6} {'image':>6}")
    for r in rows:
        lines.append(f"{r['scene']:<12} {r['patches']:>7} {r['shots']:>6} {r['rows']:>5} {r['wall']:>6.1f} "
                     f"{r['solve']:>6.2f} {r['rows_seconds']:>7.2f} {r['render']:>9.2f} {r['sum']:>5.2f} "
                     f"{r['proximity']:>5.2f} {r['loop']:>5.2f} {r['loop'] / r['solve']:>6.1%} {r['draw']:>6.2f}")
    print("\n".join(lines))
    return lines
