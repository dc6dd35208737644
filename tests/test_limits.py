"""Input that once took the machine down or crashed: refused before any work, in one line, in little memory.

Each case is a scene file or a command line that used to allocate gigabytes, print a traceback or write
a wrong image; each now exits 2 with one line naming the file and the field (or the option), and the
process stays small (its peak memory is measured, not guessed).
"""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from cs451.errors import InputError
from cs451.limits import Cost, memory_budget, parse_bytes, refuse_over_budget
from cs451.scene import BUNDLED_DIR

#: runs a command and reports its peak memory (KB on Linux) on the last line of stderr
MEASURED = ("import resource, subprocess, sys\n"
            "p = subprocess.run(sys.argv[1:])\n"
            "print('peak', resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss, file=sys.stderr)\n"
            "sys.exit(p.returncode)\n")
PEAK_KB = 600_000


def variant(tmp_path: Path, scene: str, change: str) -> str:
    data = json.loads((BUNDLED_DIR / f"{scene}.json").read_text())
    exec(change, {"d": data})
    path = tmp_path / f"{scene}-{abs(hash(change)) % 10**6}.json"
    path.write_text(json.dumps(data))
    return str(path)


CASES = [  # (scene, change to it, extra arguments, what the one line must name)
    ("cornell-box", "d['options']['radiosity']['patch_size'] = 1e-4", [], "options.radiosity.patch_size"),
    ("whitted", "d['options']['whitted'].update(spp=10000)", [], "options.whitted.spp"),
    ("whitted", "d['options']['whitted'].update(max_depth=1000)", [], "options.whitted.max_depth"),
    ("sphere", "d['objects'][0].update(slices=100000, stacks=100000)", [], "objects[0].slices"),
    ("sphere", "d['image'].update(width=100000, height=100000)", [], "image.width"),
    ("sphere", "d['image'].update(width=1e30)", [], "image.width"),
    ("sphere", "d['objects'][0].update(center=[1e308, 0, 0])", [], "objects[0].center[0]"),
    ("sphere", "d['camera'].update(fovy=1e-300)", [], "camera.fovy"),
    ("cornell-box", "d['objects'][0]['vertices'][0][1] += 50", ["--stage", "whitted"], "objects[0].vertices[0]"),
    ("cornell-box", "d['options']['hemicube'] = {'resolution': 100000}", ["--stage", "hemicube"],
     "options.hemicube.resolution"),
]
COMMANDS = [  # (command line, what the one line must name)
    (["render", "sphere", "-o", "outdir/"], "-o outdir/"),
    (["render", "sphere", "-o", "picture.jpg"], "-o picture.jpg"),
    (["render", "whitted", "--shading", "phong", "-o", "w.png"], "--shading"),
    (["render", "sphere", "--size", "-5x10", "-o", "a.png"], "--size"),
    (["render", "sphere", "--size", "20000x10", "-o", "a.png"], "--size"),
    (["release", "sphere", "-o", "/dev/null"], "/dev/null"),
]


def run_measured(args: list[str], cwd: Path) -> tuple[int, str, int]:
    done = subprocess.run([sys.executable, "-c", MEASURED, sys.executable, "-m", "cs451", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=120)
    lines = done.stderr.strip().splitlines()
    return done.returncode, "\n".join(lines[:-1]), int(lines[-1].split()[1])


@pytest.mark.spawns
@pytest.mark.parametrize("scene, change, extra, field", CASES, ids=[c[3] for c in CASES])
def test_a_scene_asking_too_much_is_refused_at_once(scene, change, extra, field, tmp_path):
    path = variant(tmp_path, scene, change)
    code, err, peak = run_measured(["render", path, "-o", "out.png", *extra], tmp_path)
    assert code == 2 and len(err.splitlines()) == 1, err
    assert err.startswith(f"cs451: error: {path}: {field}:"), err
    assert peak < PEAK_KB, f"peak {peak} KB"
    assert not (tmp_path / "out.png").exists()


@pytest.mark.spawns
@pytest.mark.parametrize("args, names", COMMANDS, ids=[" ".join(c[0][:4]) for c in COMMANDS])
def test_a_bad_command_line_is_one_line(args, names, tmp_path):
    code, err, _ = run_measured(args, tmp_path)
    assert code == 2 and err.splitlines()[-1].startswith("cs451: error:") and names in err.splitlines()[-1], err
    assert err.count("error") == 1, err


def test_the_budget_follows_the_environment(monkeypatch):
    monkeypatch.setenv("CS451_MEMORY_BUDGET", "512M")
    assert memory_budget() == 512 * 2**20 and parse_bytes("2G") == 2 * 2**30
    refuse_over_budget("s.json", [Cost("a", 100 * 2**20, "a little")])
    with pytest.raises(InputError, match=r"s.json: b: asks for a lot: about 1 GB .* budget of 512 MB"):
        refuse_over_budget("s.json", [Cost("a", 1, "a little"), Cost("b", 2**30, "a lot")])
    monkeypatch.delenv("CS451_MEMORY_BUDGET")
    assert 2**28 < memory_budget()
