"""Round 3 (issue 34, item 2): no code that solves a task is in reach of any stage's sandbox.

Stage 4 draws with stage 3's form factors, and its sandbox once held the hemicube reference: a
radiosity submission printed it, and the printed code scored 100 on stage 3. The *looter* here is
the reference radiosity package (so it earns its own points) that, in every test, walks what the
worker can read (its upload, the engine it imports, the kit that engine names, ``/``), packs every
hemicube package it finds (a folder whose files define ``delta_form_factors`` or ``form_factor_row``)
and prints it in base64 chunks, one chunk per task function. The harness puts the chunks back
together from what the grader reports (the local grader's results, Gradescope's ``results.json``)
and grades what came out as a stage-3 submission. Beside the looter in the upload lies a decoy, the
starter's stage-3 stubs: the looter must find that (its search works in the sandbox) and nothing
else, and score 0. The engine copy each stage's worker imports is checked for references, tests,
truths, answers and any function named after a task.
"""
from __future__ import annotations

import base64
import json
import re
import shutil
import sys
import zlib
from pathlib import Path

import numpy as np
import pytest

from cs451 import KIT_ROOT
from cs451.grading import sandbox
from cs451.grading.roster import grade_roster
from cs451.grading.runner import engine_sources, grade, protected_paths
from cs451.stages import get_stage, stage_names

from conftest import world_readable_dir
from test_packaging import run_autograder

pytestmark = pytest.mark.skipif(not sandbox.is_root(), reason="the attacks are graded as a root grader grades them")

#: Characters of loot per printed line: one line per test, under the 4,000 characters of output kept.
CHUNK = 3600
#: The task functions that print a chunk: the n-th prints chunk n, once per worker.
LEAKERS = ("subdivide", "shoot", "progressive_refinement", "ambient_term", "vertex_colors")
#: A folder of the upload holding the starter's stage-3 stubs: the looter must find it (its search works) and
#: they score 0 on stage 3.
DECOY = "decoy"

LOOTER = '''"""Walks what this worker can read for hemicube packages and prints them, in base64 chunks."""
import base64, json, os, sys, time, zlib

MARKS = ("def delta_form_factors(", "def form_factor_row(")
SYSTEM = {"/proc", "/sys", "/dev", "/usr", "/etc", "/bin", "/sbin", "/lib", "/lib32", "/lib64", "/libx32", "/run",
          "/boot", "/snap"}
LIBRARIES = ("site-packages", "dist-packages")
MINE = os.path.dirname(os.path.abspath(__file__))
_loot, _printed = None, set()


def _hemicube_folder(folder, names):
    """A folder holding a hemicube package's files (this package excepted, wherever a copy of it lies)."""
    if os.path.abspath(folder).startswith(MINE) or "_looter.py" in names:
        return False
    for name in names:
        if name.endswith(".py"):
            try:
                with open(os.path.join(folder, name), "rb") as f:
                    text = f.read(200_000).decode("utf-8", "replace")
            except OSError:
                continue
            if any(m in text for m in MARKS):
                return True
    return False


def _walk(root, found, deadline, skip=()):
    """Add the hemicube folders below ``root``; False when the deadline cut the walk short."""
    for folder, dirs, files in os.walk(root):
        if time.monotonic() > deadline:
            return False
        if folder in SYSTEM or any(folder == s or folder.startswith(s.rstrip("/") + "/") for s in skip):
            dirs[:] = []
            continue
        if os.path.basename(folder) in LIBRARIES:   # third-party code: only what a kit could put there
            dirs[:] = [d for d in dirs if d.startswith(("cs451", "reference", "hemicube", "autograder"))]
        if _hemicube_folder(folder, files):
            found.add(os.path.abspath(folder))
    return True


def _search():
    found, roots = set(), [os.path.dirname(MINE)]      # the upload, beside this package
    try:                  # the engine's folder, the kit it names, and the kit's own finder of stage-3 code
        import cs451
        roots += [os.path.dirname(os.path.dirname(os.path.abspath(cs451.__file__))), str(cs451.KIT_ROOT)]
        from cs451.impl import earlier_stage_impl
        roots.append(str(earlier_stage_impl("hemicube")))
    except Exception:
        pass
    roots += @EXTRA@
    for root in roots:
        _walk(root, found, float("inf"))
    complete = _walk("/", found, time.monotonic() + @BUDGET@, skip=@SKIP@)
    loot = {}
    for folder in sorted(found):
        files = {}
        for name in sorted(os.listdir(folder)):
            try:
                with open(os.path.join(folder, name), "rb") as f:
                    files[name] = f.read(200_000).decode("utf-8", "replace")
            except OSError:
                pass
        loot[folder] = {n: t for n, t in files.items() if n.endswith(".py")}
    return {"found": loot, "roots": roots, "complete": complete}


def leak(k):
    """Print chunk ``k`` of everything found (found once per worker)."""
    global _loot
    if k in _printed:
        return
    _printed.add(k)
    if _loot is None:
        blob = base64.b64encode(zlib.compress(json.dumps(_search()).encode(), 9)).decode()
        _loot = [blob[i:i + @CHUNK@] for i in range(0, len(blob), @CHUNK@)]
    if k < len(_loot):
        print(f"LOOT {k}/{len(_loot)} {_loot[k]}", flush=True)
'''


def looter(root: Path, extra: tuple[str, ...] = (), skip: tuple[str, ...] = (), budget: float = 4.0) -> Path:
    """The reference's radiosity package, whose every task function first prints its chunk of the loot, beside
    the decoy.

    ``extra``: folders to search before ``/``; ``skip``: folders of this test machine that the layout under test
    would not have (a checkout beside the grader), left out of the walk of ``/``."""
    pkg = root / "radiosity"
    shutil.copytree(KIT_ROOT / "reference" / "radiosity", pkg, ignore=shutil.ignore_patterns("__pycache__"))
    code = LOOTER
    for name, value in (("BUDGET", budget), ("EXTRA", list(extra)), ("SKIP", sorted(skip)), ("CHUNK", CHUNK)):
        code = code.replace(f"@{name}@", repr(value))
    (pkg / "_looter.py").write_text(code)
    init = pkg / "__init__.py"
    wrapped = "".join(
        f"\n\n_honest_{name} = {name}\n\n\ndef {name}(*args):\n    _looter.leak({k})\n    return _honest_{name}(*args)\n"
        for k, name in enumerate(LEAKERS))
    init.write_text(init.read_text() + "\nfrom . import _looter\n" + wrapped)
    shutil.copytree(KIT_ROOT / "starter" / "hemicube", root / DECOY / "hemicube", ignore=shutil.ignore_patterns("__pycache__"))
    for path in [root, *root.rglob("*")]:
        path.chmod(0o755 if path.is_dir() else 0o644)
    return root


def loot_in(printed: str) -> dict | None:
    """The looter's report (``found``: folder → its files; ``roots``; ``complete``: the walk of ``/`` finished),
    put back together from its printed chunks; None when some chunk did not come back."""
    chunks: dict[int, str] = {}
    total = None
    for k, n, data in re.findall(r"LOOT (\d+)/(\d+) ([A-Za-z0-9+/=]+)", printed):
        chunks[int(k)], total = data, int(n)
    if total is None or sorted(chunks) != list(range(total)):
        return None
    return json.loads(zlib.decompress(base64.b64decode("".join(chunks[k] for k in range(total)))))


def stage3_score(found: dict[str, dict[str, str]], root: Path) -> float:
    """The best stage-3 grade of the packages the looter found, each graded as a hemicube submission."""
    best = 0.0
    for k, files in enumerate(found.values()):
        pkg = root / f"stolen-{k}" / "hemicube"
        pkg.mkdir(parents=True)
        for name, text in files.items():
            (pkg / name).write_text(text)
        for path in [pkg.parent, pkg, *pkg.iterdir()]:
            path.chmod(0o755 if path.is_dir() else 0o644)
        best = max(best, grade("hemicube", pkg.parent, show_progress=False).score)
    return best


def assert_nothing_stolen(printed: str, radiosity_score: float, root: Path, whole_disk: bool = True) -> None:
    """The looter earned its radiosity points, searched (its decoy, the starter's stubs in its own upload, was
    found), found no other stage-3 code, and what it found scores 0 on stage 3. ``whole_disk``: the walk of ``/``
    must have finished in its time."""
    report = loot_in(printed)
    assert report is not None, f"the looter's chunks did not all come back: {printed[:2000]}"
    assert radiosity_score == pytest.approx(100), radiosity_score
    assert report["roots"], "the looter could not import the engine it runs on"
    assert report["complete"] or not whole_disk, "the walk of / did not finish in its time"
    found = report["found"]
    decoys = [f for f in found if f.endswith(f"/{DECOY}/hemicube")]   # the staged copy, and the upload where readable
    assert decoys, f"the looter missed its own decoy: {list(found)}"
    assert [f for f in found if f not in decoys] == [], f"stage-3 code in reach of the radiosity worker: {list(found)}"
    assert stage3_score(found, root) == 0


# --- the layouts ------------------------------------------------------------------------------------

@pytest.mark.spawns
@pytest.mark.parametrize("path", ["local", pytest.param("roster", marks=pytest.mark.slow)])
def test01_locally_and_in_a_roster_the_radiosity_worker_finds_no_hemicube_code(path):
    root = world_readable_dir("cs451-looter-")
    try:
        if path == "local":
            result = grade("radiosity", looter(root / "upload"), show_progress=False)
            assert result.isolation.startswith("bubblewrap") or "throwaway" in result.isolation
            printed, score = "\n".join(r.output for r in result.results), result.score
        else:
            looter(root / "class" / "mallory")
            grade_roster(stage="radiosity", roster=root / "class", output=root / "grades", show_progress=False)
            results = json.loads((root / "grades" / "mallory" / "results.json").read_text())
            printed = "\n".join(t["output"] for t in results["tests"])
            score = sum(t["score"] for t in results["tests"])
        assert_nothing_stolen(printed, score, root)
    finally:
        shutil.rmtree(root, ignore_errors=True)


@pytest.fixture(scope="module")
def radiosity_gradescope(request) -> tuple[Path, dict]:
    """Stage 4's autograder zip in Gradescope's layout, after its own setup.sh ran."""
    from cs451.packaging.gradescope import build_gradescope, setup_like_gradescope
    top = world_readable_dir("cs451-gs4-")
    request.addfinalizer(lambda: shutil.rmtree(top, ignore_errors=True))
    return setup_like_gradescope(build_gradescope("radiosity", top / "autograder.zip"), top, sys.prefix)


@pytest.mark.spawns
@pytest.mark.slow
@pytest.mark.parametrize("mode", ["bubblewrap", "uid"])
def test02_on_gradescope_the_radiosity_worker_finds_no_hemicube_code(mode, radiosity_gradescope):
    """Both sandboxes of the zip. Under the uid fallback the worker sees this machine's whole disk: its walk of ``/``
    leaves out this checkout and the host's temporary folders (Gradescope has neither), not the kit the zip set up."""
    root, env = radiosity_gradescope
    kit = env["CS451_HOME"]
    skip = (str(KIT_ROOT.parent), "/tmp", "/var/tmp") if mode == "uid" else ()
    work = world_readable_dir("cs451-looter-")
    try:
        results = run_autograder((root, {**env, "CS451_SANDBOX": mode}),
                                 looter(work / "upload", extra=(kit, str(root)), skip=skip))
        printed = "\n".join(t["output"] for t in results["tests"])
        score = sum(t["score"] for t in results["tests"])    # no top-level score while hidden tests are in it
        assert_nothing_stolen(printed, score, work, whole_disk=mode == "bubblewrap")
    finally:
        shutil.rmtree(work, ignore_errors=True)


# --- what every stage's worker imports ------------------------------------------------------------

#: What a kit keeps for grading and never ships in the engine: tests, truths, answers, solutions.
ANSWER_FILES = ("truth.py", "hidden.py", "public.py")
KIT_FOLDERS = {"reference", "autograder", "starter", "answers", "tests", "bench"}


@pytest.mark.spawns
@pytest.mark.parametrize("stage", stage_names())
def test03_the_engine_a_worker_imports_holds_no_reference_no_tests_and_no_answers(stage):
    """The sandbox's copy of the engine (``/kit`` under bubblewrap), as built for a grading run of each stage."""
    upload = world_readable_dir("cs451-engine-")
    try:
        (upload / stage).mkdir()
        (upload / stage / "__init__.py").write_text("")
        with sandbox.Sandbox(stage, upload, engine_sources(stage), protected_paths()) as box:
            texts = {p.relative_to(box.engine): (p.read_text() if p.suffix == ".py" else "")
                     for p in box.engine.rglob("*") if p.is_file() and "__pycache__" not in p.parts}
        assert texts, "the engine copy is empty"
        assert {f.parts[0] for f in texts} == {"cs451"}, sorted({f.parts[0] for f in texts})
        assert not [f for f in texts if f.name in ANSWER_FILES or f.suffix in (".npz", ".npy")
                    or KIT_FOLDERS & set(f.parts)]
        from cs451 import ENGINE_DIR, instructor_only       # every stage's benchmarks, figures and speed layer
        assert not [f for f in texts if instructor_only(ENGINE_DIR.parent / f)]
        assert any(instructor_only(p) for p in ENGINE_DIR.glob("stages/*/bench*.py")), "no benchmark to leave out"
        tasks = {t.function for s in stage_names() for t in get_stage(s).tasks}
        defined = [f"{f}: {line.strip()}" for f, text in texts.items() for line in text.splitlines()
                   if line.strip().startswith("def ") and line.strip()[4:].split("(")[0] in tasks]
        assert defined == []
    finally:
        shutil.rmtree(upload, ignore_errors=True)


def test04_a_radiosity_probe_without_the_trusted_arrays_refuses_rather_than_compute_form_factors():
    """A worker has no stage-3 code: a scene test must bring the reference's system, and says so when it does not."""
    from cs451.errors import KitError
    from cs451.stages import radiosity
    from cs451.scene import BUNDLED_DIR
    scene = json.loads((BUNDLED_DIR / "furnace.json").read_text())
    ref = None      # no implementation at all: the probes must refuse before they call one
    with pytest.raises(KitError, match="gives no form factors"):
        radiosity.probe_progressive(ref, tolerance=1e-3, max_shots=10, scene=scene)
    with pytest.raises(KitError, match="gives no trusted system"):
        radiosity.probe_render(ref, scene=scene, size=[16, 16])
    with pytest.raises(KitError, match="gives no trusted system"):
        radiosity.probe_render(ref, scene=scene, size=[16, 16], quads=np.zeros((1, 4, 3)))


def test05_the_canary_names_an_engine_copy_holding_instructors_parts():
    """A readable copy of the engine with a stage's benchmarks, deck figures or speed layer in it is a copy of code
    that answers tasks: the canary names it (and the uid fallback then refuses to grade beside it)."""
    from cs451.grading.canary import secret_in_parts
    stages = set(stage_names())
    for name in ("bench.py", "bench_substructuring.py", "figures.py", "figure_bench.py", "accel"):
        assert secret_in_parts(("/", "tmp", "copy", "cs451", "stages", "radiosity", name), stages), name
    for name in ("display.py", "solvers.py", "__init__.py", "bench.txt"):
        assert secret_in_parts(("/", "tmp", "copy", "cs451", "stages", "radiosity", name), stages) is None, name


def test06_every_instructors_part_of_the_engine_is_protected():
    """Every benchmark, deck figure and speed layer of the engine is among what no sandbox may read: the uid fallback
    refuses to grade where one is readable, and bubblewrap covers one inside a bound environment (a wheel)."""
    from cs451 import ENGINE_DIR, instructor_only
    parts = [p for p in ENGINE_DIR.rglob("*") if instructor_only(p) and not instructor_only(p.parent)
             and "__pycache__" not in p.parts]
    assert len([p for p in parts if p.name.startswith("bench")]) >= 5
    assert set(parts) <= set(protected_paths())
