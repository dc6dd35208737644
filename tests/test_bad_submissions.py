"""The corpus of bad submissions: each gets a fair score and a message, and the grader survives it.

(Hostile ones, which reach for what the grader keeps, are in ``test_attacks.py``.)

Each case breaks ``perspective`` (task S1) of an otherwise correct copy of the reference, and
grades S1 and S2: S1 must score what the table says, with the message, and S2 must keep its
full marks (one bad function never costs another task's points).
"""
from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

import pytest

from cs451 import KIT_ROOT
from cs451.grading.runner import grade

ORIGINAL = "    f = 1.0 / np.tan(np.radians(fovy) / 2.0)\n"
CORRECT_TAIL = ORIGINAL  # cases that stay correct keep this line after their own code

CASES = {
    # name: (code put in front of perspective's first line, expected S1 fraction, message fragment)
    "syntax error": ("    f = (\n", 0, "syntax error"),
    "nan": ("    return np.full((4, 4), np.nan)\n", 0, "NaN or infinite"),
    "inf": ("    return np.full((4, 4), np.inf)\n", 0, "NaN or infinite"),
    "wrong shape": ("    return np.eye(3)\n", 0, "shape (3, 3), expected (4, 4)"),
    "wrong dtype": ("    return [['a'] * 4] * 4\n", 0, "not an array"),
    "not implemented": ("    raise NotImplementedError('later')\n", 0, "not implemented yet"),
    "exception": ("    return {}[0]\n", 0, "KeyError"),
    "infinite loop": ("    while True:\n        pass\n", 0, "longer than the"),
    "sleeps forever": ("    import time\n    time.sleep(3600)\n", 0, "longer than the"),
    "memory bomb": ("    x = np.ones(10**10)\n", 0, "MemoryError"),
    "memory bomb by growth": ("    x = []\n    while True:\n        x.append(bytearray(10**8))\n", 0,
                              "MemoryError|out of memory|longer than the"),  # which limit bites first depends on the machine
    "sys.exit(0)": ("    import sys\n    sys.exit(0)\n", 0, "stopped before finishing"),
    "os._exit(0)": ("    import os\n    os._exit(0)\n", 0, "stopped before finishing"),
    "kills itself": ("    import os, signal\n    os.kill(os.getpid(), signal.SIGKILL)\n", 0, "killed"),
    "fork bomb": ("    import os\n    while True:\n        os.fork()\n", 0,
                  # the process cap stops it, or (under load, before the cap) the memory cap of everything it started
                  "BlockingIOError|stopped before finishing|longer than the|could not be read|ran out of memory"),
    "output flood": ("    import sys\n    while True:\n        sys.stdout.write('x' * 65536)\n", 0, "output"),
    "forged results": ("    print(json.dumps({'score': 100, 'tests': []}))\n    return np.zeros((4, 4))\n", 0, "is wrong"),
    "forged status file": ("    open('status.json', 'w').write('{\"ok\": true}')\n    import os\n    os._exit(0)\n", 0,
                           "could not be read"),
    "monkey-patches the grader": (
        "    import cs451.grading.checks as c, cs451.grading.spec as s\n"
        "    c.array_close = lambda *a, **k: (lambda *x: s.Verdict(1.0, 'ok'))\n"
        "    s.Verdict.passed = property(lambda self: True)\n    return np.zeros((4, 4))\n", 0, "is wrong"),
    "slow but correct": ("    import time\n    time.sleep(1.0)\n" + CORRECT_TAIL, 1, "matches"),
    "prints a lot but correct": ("    print('debug ' * 2000)\n" + CORRECT_TAIL, 1, "matches"),
}
@pytest.fixture(scope="module")
def corpus_dir():
    """World-readable, so that a root grader's unprivileged worker can import the submissions."""
    root = Path(tempfile.mkdtemp(prefix="cs451-corpus-"))
    os.chmod(root, 0o755)
    yield root
    shutil.rmtree(root, ignore_errors=True)


def make_case(root: Path, name: str, code: str) -> Path:
    folder = root / name.replace(" ", "-").replace("(", "").replace(")", "").replace(".", "")
    shutil.copytree(KIT_ROOT / "reference" / "sphere", folder / "sphere", ignore=shutil.ignore_patterns("__pycache__"))
    camera = folder / "sphere" / "camera.py"
    text = camera.read_text()
    assert ORIGINAL in text
    camera.write_text(text.replace("import numpy as np\n", "import json\n\nimport numpy as np\n", 1)
                      .replace(ORIGINAL, code + (ORIGINAL if code.endswith(CORRECT_TAIL) is False else ""), 1))
    for path in [folder, *folder.rglob("*")]:
        os.chmod(path, 0o755 if path.is_dir() else 0o644)
    return folder


def run_case(root: Path, name: str, code: str, fraction: float, fragment: str):
    result = grade("sphere", make_case(root, name, code), show_progress=False, tasks=["S1", "S2"], test_timeout=4)
    s1 = [r for r in result.results if r.test.task == "S1"]
    s2 = [r for r in result.results if r.test.task == "S2"]
    got = sum(r.score for r in s1) / sum(r.test.points for r in s1)
    messages = " | ".join(r.verdict.message for r in s1)
    assert got == fraction, f"{name}: S1 scored {got:.0%}: {messages}"
    assert all(any(f in r.verdict.message for f in fragment.split("|")) for r in s1), \
        f"{name}: expected {fragment!r} in: {messages}"
    if name != "syntax error":  # a file that does not parse takes the whole package down
        assert all(r.verdict.passed for r in s2), f"{name}: S2 lost points: {[r.verdict.message for r in s2]}"
    return result


@pytest.mark.spawns
@pytest.mark.parametrize("name", list(CASES))
def test01_bad_submission_is_scored_fairly(corpus_dir, name):
    run_case(corpus_dir, name, *CASES[name])


@pytest.mark.spawns
def test03_missing_function_and_wrong_signature_are_named(corpus_dir):
    folder = make_case(corpus_dir, "missing", CORRECT_TAIL)
    init = folder / "sphere" / "__init__.py"
    init.write_text(init.read_text().replace("look_at, perspective, reshape", "look_at, reshape"))
    camera = folder / "sphere" / "camera.py"
    camera.write_text(camera.read_text().replace("def look_at(eye, center, up)", "def look_at(eye, target)"))
    result = grade("sphere", folder, show_progress=False, tasks=["S1", "S2", "S4"], test_timeout=10)
    assert any("missing function perspective()" in p for p in result.problems)
    assert any("look_at(eye, target) should take (eye, center, up)" in p for p in result.problems)
    by_task = {}
    for r in result.results:
        by_task.setdefault(r.test.task, []).append(r)
    assert all(r.score == 0 and "missing" in r.verdict.message for r in by_task["S1"])
    assert all(r.score == 0 and "TypeError" in r.verdict.message for r in by_task["S2"])
    assert all(r.verdict.passed for r in by_task["S4"])
