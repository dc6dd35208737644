"""``cs451 bench fair_share``: how much a classmate who burns the CPU slows an honest student's roster grading.

Rosters of two are graded with ``grade_roster`` (both submissions at once, as on a machine with two or more
cores): the honest student (the reference's sphere package) beside an honest classmate (the same package), and
beside a burner (the same package whose every test first starts ``SPINNERS`` children, each in a session of its
own: ``setsid`` gives each its own autogroup, the kernel's per-session share, so without a share of its own the
submission takes the CPU in proportion to its sessions). Each round grades both rosters with the kit's CPU share
per submission (``cgroups.create_share``) and without it (``CS451_NO_CPU_SHARE=1``), interleaved, so load from
elsewhere falls on all alike. Reported: the honest student's grading time beside the burner over its time beside
the honest classmate, per round and the median, with and without the share. Needs root and a cpu cgroup
controller (else both columns grade without a share).
"""
from __future__ import annotations

import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from cs451 import KIT_ROOT

#: The top-level keys of fair_share.json that the docs and decks read (tests/test_benches.py checks a quick run writes them).
KEYS = ("tasks", "spinners", "cpus", "rounds", "median_ratio_share", "median_ratio_no_share")

TASKS = ["S1", "S2", "S3", "S4"]
SPINNERS = 8
#: At import, in every test the burner runs: children in sessions of their own spin until the test ends (the
#: sandbox kills them), and the worker waits 2 s before going on, so the burner is busy through the roster.
BURNER = '''import os as _os, time as _time
for _ in range({spinners}):
    if _os.fork() == 0:
        _os.setsid()
        while True:
            pass
_time.sleep(2)
'''

GRADE = """
import csv, sys
from pathlib import Path
from cs451.grading.roster import grade_roster
out = Path(sys.argv[2])
grade_roster(stage="sphere", roster=Path(sys.argv[1]), output=out, show_progress=False, only=sys.argv[3].split(","),
             parallel=2)
rows = {r["student"]: r for r in csv.DictReader(open(out / "gradebook.csv"))}
print(rows["alice"]["seconds"], rows["alice"]["score"])
"""


def _roster(top: Path, name: str, classmate_prelude: str) -> Path:
    roster = top / name
    for student, prelude in (("alice", ""), ("classmate", classmate_prelude)):
        package = roster / student / "sphere"
        shutil.copytree(KIT_ROOT / "reference" / "sphere", package, ignore=shutil.ignore_patterns("__pycache__"))
        if prelude:
            init = package / "__init__.py"
            init.write_text(prelude + init.read_text())
    for path in [roster, *roster.rglob("*")]:
        os.chmod(path, 0o755 if path.is_dir() else 0o644)
    return roster


def _alice_seconds(roster: Path, output: Path, share: bool, tasks: list[str]) -> float:
    env = {k: v for k, v in os.environ.items() if k != "CS451_NO_CPU_SHARE"}
    if not share:
        env["CS451_NO_CPU_SHARE"] = "1"
    shutil.rmtree(output, ignore_errors=True)
    done = subprocess.run([sys.executable, "-c", GRADE, str(roster), str(output), ",".join(tasks)], env=env,
                          capture_output=True, text=True, timeout=1800, cwd=KIT_ROOT)
    if done.returncode != 0:
        raise RuntimeError(done.stderr[-2000:])
    seconds, score = done.stdout.split()
    if float(score) <= 0:
        raise RuntimeError(f"the honest student scored {score}: {done.stdout}")
    return float(seconds)


def main(output: Path, quick: bool = False) -> dict:
    """Alice's roster grading beside an honest classmate and beside a CPU burner, with and without the kit's CPU share
    (``quick``: one round of S1's tests, to show it runs; not a measurement), and ``fair_share.json``."""
    rounds = 1 if quick else 3
    tasks = TASKS[:1] if quick else TASKS
    top = Path(tempfile.mkdtemp(prefix="cs451-bench-share-"))
    os.chmod(top, 0o755)
    rows: list[dict] = []
    try:
        honest = _roster(top, "honest", "")
        burner = _roster(top, "burner", BURNER.format(spinners=SPINNERS))
        for r in range(rounds):
            row = {"round": r + 1}
            for share in (True, False):
                key = "share" if share else "no_share"
                beside_honest = _alice_seconds(honest, top / "out", share, tasks)
                beside_burner = _alice_seconds(burner, top / "out", share, tasks)
                row[key] = {"beside_honest_s": beside_honest, "beside_burner_s": beside_burner,
                            "ratio": beside_burner / beside_honest}
            rows.append(row)
            print(f"round {r + 1}: alice beside the burner / beside an honest classmate: "
                  f"with a share {row['share']['ratio']:.2f}x ({row['share']['beside_burner_s']:.1f} s / "
                  f"{row['share']['beside_honest_s']:.1f} s), without {row['no_share']['ratio']:.2f}x "
                  f"({row['no_share']['beside_burner_s']:.1f} s / {row['no_share']['beside_honest_s']:.1f} s)", flush=True)
    finally:
        shutil.rmtree(top, ignore_errors=True)
    summary = {"tasks": tasks, "spinners": SPINNERS, "cpus": os.cpu_count(), "rounds": rows,
               "median_ratio_share": statistics.median(r["share"]["ratio"] for r in rows),
               "median_ratio_no_share": statistics.median(r["no_share"]["ratio"] for r in rows)}
    print(f"median slowdown of the honest student beside a CPU burner: {summary['median_ratio_share']:.2f}x with the "
          f"kit's CPU share per submission, {summary['median_ratio_no_share']:.2f}x without ({os.cpu_count()} CPUs)")
    output.mkdir(parents=True, exist_ok=True)
    (output / "fair_share.json").write_text(json.dumps(summary, indent=1) + "\n")
    return summary
