"""Grading a class folder: a gradebook row and a report per student; one crash never stops the batch."""
from __future__ import annotations

import csv
import shutil

import pytest

from cs451 import KIT_ROOT
from cs451.grading.roster import grade_roster

BREAKS = [  # (file, old, new): a spread of partly right submissions
    ("camera.py", "s, u, -f", "s, u, f"),
    ("mesh.py", "phi = -2.0 * np.pi", "phi = 2.0 * np.pi"),
    ("controls.py", 'if key in ("q", "Q", "escape"):', 'if key == "q":'),
    ("camera.py", "def perspective(", "def perspective(:"),
    ("camera.py", "    height = max(int(height), 1)\n", "    while True:\n        pass\n"),
]


def make_roster(root, n):
    """``n`` submissions: the reference, the starter, an empty folder, and reference copies with one break each."""
    for i in range(n):
        folder = root / f"student{i:02d}" / "sphere"
        if i % 7 == 1:
            shutil.copytree(KIT_ROOT / "starter" / "sphere", folder)
            continue
        if i % 7 == 2:
            folder.mkdir(parents=True)   # submitted nothing
            continue
        shutil.copytree(KIT_ROOT / "reference" / "sphere", folder, ignore=shutil.ignore_patterns("__pycache__"))
        if i % 7 >= 3:
            file, old, new = BREAKS[(i % 7 - 3 + i // 7) % len(BREAKS)]
            path = folder / file
            path.write_text(path.read_text().replace(old, new, 1))


def check_gradebook(out, n):
    rows = list(csv.DictReader(open(out / "gradebook.csv")))
    assert [r["student"] for r in rows] == [f"student{i:02d}" for i in range(n)]
    scores = {r["student"]: float(r["score"]) for r in rows}
    assert scores["student00"] == 100 and scores["student01"] == 0 and scores["student02"] == 0
    assert all((out / r["student"] / "results.json").exists() for r in rows)
    assert "no 'sphere' package" in rows[2]["problems"] or "__init__" in rows[2]["problems"]
    return scores


@pytest.mark.spawns
def test01_small_roster(tmp_path):
    make_roster(tmp_path / "class", 4)
    out = tmp_path / "grades"
    assert grade_roster(stage="sphere", roster=tmp_path / "class", output=out, show_progress=False).exists()
    scores = check_gradebook(out, 4)
    assert 0 < scores["student03"] < 100
    assert (out / "student00" / "report.html").exists()


@pytest.mark.spawns
@pytest.mark.slow
def test02_roster_of_twenty(tmp_path):
    make_roster(tmp_path / "class", 20)
    grade_roster(stage="sphere", roster=tmp_path / "class", output=tmp_path / "grades", show_progress=False)
    scores = check_gradebook(tmp_path / "grades", 20)
    assert len(set(scores.values())) >= 4
