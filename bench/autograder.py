"""``cs451 bench autograder``: what grading one submission costs, per stage, against Gradescope's limits.

Each stage's Gradescope zip is built and unpacked into a layout like Gradescope's,
its own ``setup.sh`` run there (it moves the kit out of reach and warms every
answer, once per image; apt and pip are skipped, the kit's environment reused),
then its own ``run_autograder`` grades the reference and the starter under each
sandbox this machine has (bubblewrap, and the uid-only fallback Gradescope's
container may force). Peak memory is the sum of the resident memory of the grader
and all its workers, sampled every 20 ms: what a container's memory cap
(Gradescope: 768 MB) sees.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from cs451 import KIT_ROOT
from cs451.grading.results import total_score
from cs451.packaging.gradescope import GRADESCOPE_BUDGET, build_gradescope, setup_like_gradescope
from cs451.stages import stage_names

#: The top-level keys of autograder.json that the docs and decks read (tests/test_benches.py checks a quick run writes them).
KEYS = ("machine_cpus", "rows")

GRADESCOPE_MEMORY_MB = 768


def _tree_rss_mb(pid: int) -> float:
    """Resident memory of a process and all its descendants, from /proc."""
    children: dict[int, list[int]] = {}
    rss: dict[int, int] = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            children.setdefault(int(fields[1]), []).append(int(entry))
            rss[int(entry)] = int(fields[21]) * os.sysconf("SC_PAGE_SIZE")
        except (OSError, IndexError, ValueError):
            continue
    total, todo = 0, [pid]
    while todo:
        p = todo.pop()
        total += rss.get(p, 0)
        todo += children.get(p, [])
    return total / 2**20


def _run_measured(args: list[str], env: dict) -> tuple[float, float, int]:
    start = time.perf_counter()
    proc = subprocess.Popen(args, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    peak = 0.0
    stop = threading.Event()

    def sample():
        nonlocal peak
        while not stop.is_set():
            peak = max(peak, _tree_rss_mb(proc.pid))
            time.sleep(0.02)
    sampler = threading.Thread(target=sample)
    sampler.start()
    code = proc.wait()
    stop.set()
    sampler.join()
    return time.perf_counter() - start, peak, code


def measure(stage: str, modes: tuple[str, ...] = ("bubblewrap", "uid"),
            submissions: tuple[str, ...] = ("reference", "starter")) -> list[dict]:
    """Build ``stage``'s zip, set it up as Gradescope does, and grade each of ``submissions`` under each sandbox mode:
    seconds, peak memory and score per run."""
    top = Path(tempfile.mkdtemp(prefix=f"cs451-bench-{stage}-"))
    os.chmod(top, 0o755)
    try:
        t0 = time.perf_counter()
        root, env = setup_like_gradescope(build_gradescope(stage, top / "autograder.zip"), top, sys.prefix)
        setup_s = time.perf_counter() - t0
        rows = []
        for mode in modes:
            for who in submissions:
                for sub in ("submission", "results"):
                    shutil.rmtree(root / sub, ignore_errors=True)
                    (root / sub).mkdir()
                    (root / sub).chmod(0o755)
                shutil.copytree(KIT_ROOT / who / stage, root / "submission" / stage)
                seconds, peak, code = _run_measured([str(root / "source" / "run_autograder")], {**env, "CS451_SANDBOX": mode})
                results = json.loads((root / "results" / "results.json").read_text())
                rows.append({"stage": stage, "sandbox": mode, "submission": who, "score": total_score(results),
                             "tests": len(results.get("tests", [])), "seconds": round(seconds, 1),
                             "peak_mb": round(peak), "setup_s": round(setup_s, 1), "exit": code})
        return rows
    finally:
        shutil.rmtree(top, ignore_errors=True)


def main(output: Path, quick: bool = False) -> None:
    """Every stage's zip, each graded with the reference and the starter under both sandboxes (``quick``: the first
    stage's reference under bubblewrap only, to show it runs; not a measurement), and ``autograder.json``."""
    stages = [s for s in stage_names() if (KIT_ROOT / "autograder" / s / "public.py").exists()
              and (KIT_ROOT / "starter" / s).is_dir()]
    if quick:
        stages = stages[:1]
    rows = [row for s in stages for row in (measure(s, ("bubblewrap",), ("reference",)) if quick else measure(s))]
    print(f"Grading one submission with the Gradescope zip's run_autograder (budget {GRADESCOPE_BUDGET:g} s of "
          f"Gradescope's 600 s, {GRADESCOPE_MEMORY_MB} MB); setup = its setup.sh without apt and pip (warming every answer)")
    print(f"{'stage':<10} {'sandbox':<11} {'submission':<10} {'score':>6} {'tests':>5} {'seconds':>8} {'peak MB':>8} {'setup s':>8}")
    for r in rows:
        print(f"{r['stage']:<10} {r['sandbox']:<11} {r['submission']:<10} {r['score']:>6g} {r['tests']:>5} "
              f"{r['seconds']:>8.1f} {r['peak_mb']:>8} {r['setup_s']:>8.1f}")
    output.mkdir(parents=True, exist_ok=True)
    (output / "autograder.json").write_text(json.dumps({"machine_cpus": os.cpu_count(), "rows": rows}, indent=2))
    print(f"wrote {output / 'autograder.json'}")
