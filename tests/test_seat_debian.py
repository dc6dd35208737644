"""Seat: a fresh minimal Debian 12, set up and used exactly as the README says (issue 33).

A throwaway minimal Debian (tests/seats/debian.py: debootstrap minbase with python3 only; this machine's apt
and pip configuration and certificates, so it reaches the same registries) gets a copy of this working tree,
as a clone would hold it. Then, inside, as root with a clean environment, only what a new user types: the
README's set-up command as written; the main job's image; every bundled scene rendered by every stage that
draws it, each first render of a stage in a fresh process (none may compile anything: the set-up warmed the
kernels); and every stage's reference, copied as a student's submission would be, graded through the console
script in the sandbox with full marks. Marked ``seat``: ``.venv/bin/python -m pytest -m seat`` (CI runs it).
"""
from __future__ import annotations

import json
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest

from cs451 import KIT_ROOT
from cs451.grading.results import total_score
from cs451.imageio import load_png
from cs451.scene import bundled_scenes, load_scene
from cs451.stages import get_stage, stage_names

from seats.debian import fresh_machine, missing_tools
from seats.measured import FOLDER, record
from test_containers import readme_commands

pytestmark = [pytest.mark.seat, pytest.mark.spawns, pytest.mark.skipif(missing_tools() is not None, reason=str(missing_tools()))]

KIT = "/root/cs451-kit"
#: What first use announces when it compiles (cs451/stages/whitted/accel/running.py): after set-up, nothing may.
COMPILING = "compiling the ray tracer's kernels"
#: The optional peers (pyproject's extra ``peers``): the README's set-up does not install them, so their checks skip.
OPTIONAL_PEERS = ("mitsuba", "embreex", "Embree, an optional peer")
#: Skips that say something of this harness, not of a user's machine: the root runs in a private mount namespace
#: with no cgroup file system mounted (a fresh VM has systemd's), so no CPU share can be made there.
HARNESS_ONLY = ("no cpu controller to make a share with here",)
#: Prints the file names (the real files: libOpenGL.so.0.0.0) of the libraries mapped once the kit has made its moderngl context and a pyrender
#: renderer: the versioned GLVND names, never libGL.so (a -dev name) or GLX (which loads X).
LOADED_LIBRARIES = ("from cs451.gl import create_context; create_context(); "
                    "from cs451.pyrender_shim import pyrender; pyrender.OffscreenRenderer(8, 8); "
                    "print(*sorted({l.split('/')[-1] for l in open('/proc/self/maps') if '.so' in l}))")


def kit_files() -> list[Path]:
    """The working tree as a clone of it holds it: its repository (``.git``), and the tracked and untracked files
    that git does not ignore."""
    out = subprocess.run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"], cwd=KIT_ROOT,
                         capture_output=True, text=True, check=True).stdout
    repository = [p.relative_to(KIT_ROOT) for p in (KIT_ROOT / ".git").rglob("*") if p.is_file() and not p.is_symlink()]
    return repository + [Path(p) for p in out.split("\0") if p and (KIT_ROOT / p).is_file()]


def drawable() -> list[tuple[str, str]]:
    """Every (bundled scene, stage) pair the stage draws (the rest are refused by design, naming the object)."""
    pairs = []
    for name in bundled_scenes():
        scene = load_scene(name)
        for stage in stage_names():
            try:
                get_stage(stage).check_scene(scene)
            except Exception:
                continue
            pairs.append((name, stage))
    return pairs


@pytest.fixture(scope="module")
def debian():
    """A fresh machine with the kit copied in and the README's set-up command run in its folder."""
    with fresh_machine() as machine:
        machine.put_tree(kit_files(), KIT_ROOT, KIT)
        setup = readme_commands()[0]
        start = time.perf_counter()
        done = machine.run(f"cd {KIT} && {setup}")
        machine.setup_seconds = time.perf_counter() - start
        machine.setup = done
        yield machine


def _said(done: subprocess.CompletedProcess) -> str:
    return (done.stdout + done.stderr)[-3000:]


def test01_the_readme_set_up_runs_the_main_job_through_the_versioned_gl_libraries(debian):
    assert debian.setup.returncode == 0, _said(debian.setup)
    loaded = debian.run(f"cd {KIT} && .venv/bin/python -c \"{LOADED_LIBRARIES}\"")
    assert loaded.returncode == 0, _said(loaded)
    names = set(loaded.stdout.split())
    assert all(any(n.startswith(lib) for n in names) for lib in ("libEGL.so.1", "libOpenGL.so.0")), names
    assert not {n for n in names if n.startswith(("libGL.so", "libGLX"))}, f"the kit loaded GLX: {sorted(names)}"
    mine = load_png(debian.path(f"{KIT}/sphere.png"))
    here = FOLDER / "sphere-here.png"   # beside the measurements
    subprocess.run([str(KIT_ROOT / ".venv" / "bin" / "cs451"), "render", "sphere", "-o", str(here)],
                   check=True, capture_output=True)
    assert mine.shape == (500, 500, 3)
    assert np.abs(mine - load_png(here)).max() <= 1 / 255 + 1e-9, "the fresh machine's main job differs from here"


def test02_every_bundled_scene_renders_and_no_first_render_compiles(debian):
    pairs = drawable()
    script, first = [], {}
    for scene, stage in pairs:
        first.setdefault(stage, scene)
        out = f"/root/renders/{scene}--{stage}.png"
        script.append(f"s=$(date +%s.%N); .venv/bin/cs451 render {scene} --stage {stage} -o {out} "
                      f"> /root/renders/{scene}--{stage}.log 2>&1; echo \"{scene} {stage} $? $s $(date +%s.%N)\"")
    done = debian.run(f"cd {KIT} && mkdir -p /root/renders && " + " && ".join(script))
    assert done.returncode == 0, _said(done)
    rows = [line.split() for line in done.stdout.splitlines() if line.strip()]
    failed = [f"{r[0]} --stage {r[1]}: {debian.path(f'/root/renders/{r[0]}--{r[1]}.log').read_text()[-400:]}"
              for r in rows if r[2] != "0"]
    assert not failed, failed
    compiled = [f"{r[0]} --stage {r[1]}" for r in rows
                if COMPILING in debian.path(f"/root/renders/{r[0]}--{r[1]}.log").read_text()]
    assert not compiled, f"a first render compiled kernels after set-up: {compiled}"
    seconds = {f"{r[0]} --stage {r[1]}": float(r[4]) - float(r[3]) for r in rows}
    firsts = {stage: seconds[f"{scene} --stage {stage}"] for stage, scene in first.items()}
    assert len(rows) == len(pairs) and set(firsts) == set(stage_names())
    _record({"setup_s": debian.setup_seconds, "renders_s": seconds, "first_render_s": firsts})
    for scene, stage in pairs:
        image = load_png(debian.path(f"/root/renders/{scene}--{stage}.png"))
        assert image.ndim == 3 and image.max() > 0, f"{scene} --stage {stage}: a black image"


def test03_every_reference_gets_full_marks_in_the_sandbox_through_the_console_script(debian):
    script = []
    for stage in stage_names():
        script.append(f"mkdir -p /root/submissions/{stage} && cp -r reference/{stage} /root/submissions/{stage}/ && "
                      f"rm -rf /root/submissions/{stage}/{stage}/__pycache__ && "
                      f".venv/bin/cs451 grade {stage} --submission /root/submissions/{stage} "
                      f"--results /root/results-{stage}.json > /root/grade-{stage}.log 2>&1; echo \"{stage} $?\"")
    done = debian.run(f"cd {KIT} && " + " ; ".join(script))
    scores = {}
    for stage in stage_names():
        log = debian.path(f"/root/grade-{stage}.log").read_text()
        results = json.loads(debian.path(f"/root/results-{stage}.json").read_text())
        points = sum(t["max_score"] for t in results["tests"])
        scores[stage] = (total_score(results), points)
        assert total_score(results) == pytest.approx(points) and points > 0, f"{stage}: {total_score(results)}/{points}\n{log[-1500:]}"
        assert "bubblewrap" in log, f"{stage}: not graded in the bubblewrap sandbox:\n{log[-800:]}"
    assert f"{stage} 0" in done.stdout
    _record({"grades": scores})


def _record(values: dict) -> None:
    record("debian", values)


def test04_the_readme_test_command_runs_there_and_nothing_skips(debian):
    """The README's test command as written; only the optional peers (Embree, Mitsuba 3), which the README's set-up
    leaves out on purpose, may skip (``PYTEST_ADDOPTS=-rfEs`` only makes pytest say why each skip happened)."""
    done = debian.run(f"cd {KIT} && PYTEST_ADDOPTS=-rfEs {readme_commands()[1]} 2>&1 | tail -n 300", timeout=5400)
    lines = done.stdout.strip().splitlines()
    summary = lines[-1] if lines else ""
    assert " passed" in summary and "failed" not in summary and "error" not in summary, done.stdout[-6000:]
    skips = [line for line in lines if line.startswith("SKIPPED")]
    not_peers = [line for line in skips if not any(why in line for why in OPTIONAL_PEERS + HARNESS_ONLY)]
    assert not not_peers, "tests skip on a machine set up by the README:\n" + "\n".join(not_peers)
    _record({"suite": summary})
