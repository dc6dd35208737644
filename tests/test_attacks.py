"""Hostile submissions in every grading path: none scores what it did not earn, reads what it must not, or
touches another student's grade.

Each attack is a copy of the reference's stage-1 package whose ``perspective`` (task S1) first does
something hostile, or an upload shaped to hurt the grader. It is graded through the local grader
(``grade``), a roster (``grade_roster``, beside an honest classmate) and the Gradescope zip in the
layout its own ``setup.sh`` makes, under bubblewrap and under the uid-only fallback. S2 is the
control: one hostile function never costs another task's points. Attacks that reach for something
print ``LEAKED`` when they get it and ``BLOCKED`` when they do not.
"""
from __future__ import annotations

import csv
import json
import os
import shutil
import stat
import subprocess
import uuid
from dataclasses import dataclass
from pathlib import Path

import pytest

from cs451 import ENGINE_DIR, KIT_ROOT
from cs451.grading import sandbox
from cs451.grading.roster import grade_roster
from cs451.stages import stage_names
from cs451.grading.runner import grade
from cs451.packaging.release import build_release

import adversaries
from conftest import world_readable_dir
from test_packaging import run_autograder

pytestmark = pytest.mark.skipif(not sandbox.is_root(), reason="the attacks are graded as a root grader grades them")

ORIGINAL = "    f = 1.0 / np.tan(np.radians(fovy) / 2.0)\n"
TASKS = ["S1", "S2"]


@dataclass
class Outcome:
    """What one grading path made of an attack, in the same form for every path."""
    points: dict[str, float]        # per task
    messages: dict[str, str]        # per task, joined
    printed: str                    # everything the submission printed, all tests
    summary: str                    # the run's own message (problems, or why nothing was graded)


def attack(root: Path, name: str, code: str = "", at_import: str = "", private: bool = False) -> Path:
    """The reference's sphere package with ``code`` run first in perspective() (and ``at_import`` at import)."""
    folder = root / name
    shutil.copytree(KIT_ROOT / "reference" / "sphere", folder / "sphere", ignore=shutil.ignore_patterns("__pycache__"))
    camera = folder / "sphere" / "camera.py"
    text = camera.read_text()
    assert ORIGINAL in text
    text = text.replace(ORIGINAL, code + ORIGINAL, 1)
    if at_import:
        text = text.replace("import numpy as np\n", "import numpy as np\n" + at_import, 1)
    camera.write_text(text)
    for path in [folder, *folder.rglob("*")]:
        os.chmod(path, (0o700 if path.is_dir() else 0o600) if private else (0o755 if path.is_dir() else 0o644))
    return folder


def reaches(paths: list[str], write: bool = False) -> str:
    """Code that tries to read (or write into) each path and says which it got."""
    action = ("open(os.path.join(p, 'cs451-pwned'), 'x').write('x')" if write else
              "(os.listdir(p) if os.path.isdir(p) else open(p, 'rb').read(64))")
    return (f"    import os\n    for p in {paths!r}:\n        try:\n            {action}\n"
            f"            print('LEAKED', p)\n        except OSError:\n            print('BLOCKED', p)\n")


# --- the three paths --------------------------------------------------------------------------

def outcome_of_results(data: dict) -> Outcome:
    points, messages, printed = {}, {}, []
    for t in data["tests"]:
        task = t["tags"][0]
        points[task] = points.get(task, 0.0) + t["score"]
        messages[task] = messages.get(task, "") + " | " + t["output"].split("\n\nYour code printed:")[0]
        printed.append(t["output"])
    return Outcome(points, messages, "\n".join(printed), data.get("output", ""))


def run_local(folder: Path) -> Outcome:
    try:
        result = grade("sphere", folder, show_progress=False, tasks=TASKS, test_timeout=20)
    except Exception as err:
        return Outcome({}, {}, "", str(err))
    points, messages = {}, {}
    for r in result.results:
        points[r.test.task] = points.get(r.test.task, 0.0) + r.score
        messages[r.test.task] = messages.get(r.test.task, "") + " | " + r.verdict.message
    return Outcome(points, messages, "\n".join(r.output for r in result.results), "; ".join(result.problems))


def run_roster(folder: Path) -> Outcome:
    """The attack in a class folder beside an honest classmate, who must keep full marks."""
    top = world_readable_dir("cs451-class-")
    try:
        (top / "class").mkdir()
        subprocess.run(["cp", "-a", str(folder), str(top / "class" / "mallory")], check=True)
        shutil.copytree(KIT_ROOT / "reference" / "sphere", top / "class" / "alice" / "sphere",
                        ignore=shutil.ignore_patterns("__pycache__"))
        grade_roster(stage="sphere", roster=top / "class", output=top / "grades", show_progress=False, only=TASKS)
        rows = {r["student"]: r for r in csv.DictReader(open(top / "grades" / "gradebook.csv"))}
        assert float(rows["alice"]["score"]) == 20, f"the honest classmate lost points: {rows['alice']}"
        return outcome_of_results(json.loads((top / "grades" / "mallory" / "results.json").read_text()))
    finally:
        shutil.rmtree(top, ignore_errors=True)


def run_gradescope(layout, folder: Path, mode: str) -> Outcome:
    root, env = layout
    env = {**env, "CS451_SANDBOX": mode}
    return outcome_of_results(run_autograder((root, env), folder, "--tasks", ",".join(TASKS)))


@pytest.fixture(scope="module")
def corpus():
    root = world_readable_dir("cs451-attacks-")
    home_secret = Path.home() / HOME_SECRET          # what the grader keeps in its home (keys, tokens)
    home_secret.write_text("the grader's own\n")
    home_secret.chmod(0o600)
    yield root
    home_secret.unlink(missing_ok=True)
    shutil.rmtree(root, ignore_errors=True)


#: A private file the module puts in the grader's home. Not the home folder itself: where the kit lives under it
#: (a clone in /root, as on a fresh machine), bubblewrap makes the path to the kit's environment inside the
#: sandbox, so a submission may list a /root that holds nothing but that path.
HOME_SECRET = ".cs451-attack-home-secret"


PATHS = ["local", "roster", "gradescope-bubblewrap", "gradescope-uid"]
#: The same paths, with the uid fallback's run in the slow suite (test01 and test07 run it in the fast one too).
FAST_PATHS = ["local", "roster", "gradescope-bubblewrap", pytest.param("gradescope-uid", marks=pytest.mark.slow)]


def graded(path: str, folder: Path, gradescope) -> Outcome:
    if path == "local":
        return run_local(folder)
    if path == "roster":
        return run_roster(folder)
    return run_gradescope(gradescope, folder, path.split("-", 1)[1])


def secrets(gradescope) -> list[str]:
    """What a submission must never read: the kit's reference, hidden tests, answers and history, in each layout."""
    kit = Path(gradescope[1]["CS451_HOME"])
    return [str(KIT_ROOT / "reference" / "sphere" / "camera.py"), str(KIT_ROOT / "autograder" / "sphere" / "hidden.py"),
            str(KIT_ROOT / ".git" / "HEAD"), str(KIT_ROOT / ".cs451-cache"),
            str(kit / "reference" / "sphere" / "camera.py"), str(kit / "autograder" / "sphere" / "truth.py"),
            str(kit / ".cs451-cache"), str(gradescope[0] / "source"), str(Path.home() / HOME_SECRET),
            "/etc/shadow", *instructors_parts(ENGINE_DIR), *instructors_parts(kit / "cs451")]


def instructors_parts(engine: Path) -> list[str]:
    """An engine's instructors-only files, by path (no listing needed): a benchmark whose loop solves R3 (a fourth
    round's attacker ran it under the uid fallback from a readable checkout), a deck figure, the speed layer."""
    stages = engine / "stages"
    return [str(stages / "radiosity" / "bench_substructuring.py"), str(stages / "radiosity" / "figures.py"),
            str(stages / "whitted" / "accel" / "kernels.py")]


def layout_secrets(gradescope) -> list[str]:
    """The secrets of the Gradescope layout alone (the uid-only fallback guards the kit it runs, not this checkout)."""
    kit = Path(gradescope[1]["CS451_HOME"])
    return [str(kit / "reference" / "sphere" / "camera.py"), str(kit / "autograder" / "sphere" / "hidden.py"),
            str(kit / ".cs451-cache"), str(gradescope[0] / "source"), "/etc/shadow", *instructors_parts(kit / "cs451")]


def assert_blocked(out: Outcome):
    assert "LEAKED" not in out.printed, out.printed
    assert "BLOCKED" in out.printed, (out.printed, out.summary, out.messages)
    assert out.points == {"S1": 10, "S2": 10}, out.messages


def assert_s1_fails(out: Outcome, fragment: str):
    assert out.points.get("S1") == 0 and any(f in out.messages["S1"] for f in fragment.split("|")), out.messages
    assert out.points.get("S2") == 10, out.messages


# --- reading and writing what the grader keeps --------------------------------------------------

@pytest.mark.spawns
@pytest.mark.parametrize("path", PATHS)
def test01_the_kit_its_history_and_its_answers_are_out_of_reach(path, corpus, gradescope):
    targets = layout_secrets(gradescope) if path == "gradescope-uid" else secrets(gradescope)
    assert_blocked(graded(path, attack(corpus, f"reads-{path}", reaches(targets)), gradescope))


@pytest.mark.spawns
@pytest.mark.parametrize("path", FAST_PATHS)
def test02_nothing_the_grader_keeps_can_be_written(path, corpus, gradescope):
    kit = Path(gradescope[1]["CS451_HOME"])
    targets = [str(kit / ".cs451-cache"), str(kit / "reference" / "sphere"), str(gradescope[0] / "results"),
               str(KIT_ROOT / "reference" / "sphere"), "/usr/lib"]
    code = reaches(targets, write=True) + ("    try:\n        open(__file__, 'a').write('#')\n        print('LEAKED own file')\n"
                                          "    except OSError:\n        print('BLOCKED own file')\n")
    out = graded(path, attack(corpus, f"writes-{path}", code), gradescope)
    assert_blocked(out)
    assert not list((KIT_ROOT / "reference" / "sphere").glob("cs451-pwned"))


@pytest.mark.spawns
@pytest.mark.parametrize("path", FAST_PATHS)
def test03_a_private_submission_runs_as_the_sandbox_user_never_root(path, corpus, gradescope):
    code = "    import os\n    print('BLOCKED' if os.getuid() else 'LEAKED root')\n"
    assert_blocked(graded(path, attack(corpus, f"private-{path}", code, private=True), gradescope))


# --- uploads shaped to hurt ------------------------------------------------------------------------

@pytest.mark.spawns
@pytest.mark.parametrize("path", FAST_PATHS)
def test04_a_link_to_the_reference_is_not_followed(path, corpus, gradescope):
    folder = corpus / f"link-{path}"
    folder.mkdir()
    target = Path(gradescope[1]["CS451_HOME"]) / "reference" / "sphere" if path.startswith("gradescope") else \
        KIT_ROOT / "reference" / "sphere"
    (folder / "sphere").symlink_to(target)
    (folder / "relative").symlink_to("../source/reference/sphere")
    out = graded(path, folder, gradescope)
    assert sum(out.points.values()) == 0
    assert "no 'sphere' package" in out.summary + " ".join(out.messages.values()), (out.summary, out.messages)


@pytest.mark.spawns
@pytest.mark.parametrize("path", ["local", "gradescope-bubblewrap"])
def test05_links_fifos_and_devices_inside_the_upload_are_left_out_and_said(path, corpus, gradescope):
    folder = attack(corpus, f"oddfiles-{path}", reaches(["secret.txt", "zero", "dangling"]).replace(
        "for p in", "here = os.path.dirname(__file__)\n    for p in").replace("(p)", "(os.path.join(here, p))"))
    pkg = folder / "sphere"
    (pkg / "secret.txt").symlink_to("/etc/shadow")
    (pkg / "zero").symlink_to("/dev/zero")
    (pkg / "dangling").symlink_to("/nonexistent/cs451")
    os.mkfifo(pkg / "pipe")
    out = graded(path, folder, gradescope)
    assert_blocked(out)
    if path == "local":
        assert all(n in out.summary for n in ("secret.txt", "zero", "dangling", "pipe")), out.summary


@pytest.mark.spawns
@pytest.mark.parametrize("path", ["local", "gradescope-bubblewrap"])
def test06_a_deep_or_huge_upload_is_refused_with_the_reason(path, corpus, gradescope):
    deep = attack(corpus, f"deep-{path}")
    tower = deep / "tower"
    for _ in range(40):
        tower = tower / "d"
    tower.mkdir(parents=True)
    out = graded(path, deep, gradescope)
    assert sum(out.points.values()) == 0 and "nested more than" in out.summary + str(out.messages), out.summary
    huge = attack(corpus, f"huge-{path}")
    with open(huge / "sphere" / "data.bin", "wb") as f:
        f.truncate(80 << 20)          # sparse: 80 MiB of zeros, read at the copy's pace
    out = graded(path, huge, gradescope)
    assert sum(out.points.values()) == 0 and "larger than" in out.summary + str(out.messages), out.summary


# --- what the worker leaves behind ------------------------------------------------------------------

WORKER_LEFTOVERS = {
    "status.json is a FIFO": ("    import os\n    os.mkfifo('status.json')\n    os._exit(0)\n", "not a regular file"),
    "status.json links to a root-only file": ("    import os\n    os.symlink('/etc/shadow', 'status.json')\n    os._exit(0)\n",
                                             "could not be opened"),
    "an npz bomb": ("    import io, os, zipfile\n"
                    "    with zipfile.ZipFile('output.npz', 'w', zipfile.ZIP_DEFLATED) as z:\n"
                    "        b = io.BytesIO()\n"
                    "        np.lib.format.write_array_header_1_0(b, {'descr': '<f8', 'fortran_order': False, 'shape': (20000, 20000)})\n"
                    "        z.writestr('matrix.npy', b.getvalue() + bytes(32 << 20))\n"
                    "    open('status.json', 'w').write('{\"ok\": true, \"error\": \"\"}')\n    os._exit(0)\n", "would take"),
    "a real-time signal": ("    import os\n    os.kill(os.getpid(), 40)\n", "signal 40"),
    "memory spread over four children": (
        "    import os\n    kids = []\n    for _ in range(4):\n        pid = os.fork()\n        if pid == 0:\n"
        "            x = bytearray(400 << 20)\n            x[::4096] = b'x' * len(x[::4096])\n            import time\n"
        "            time.sleep(3)\n            os._exit(0)\n        kids.append(pid)\n"
        "    for pid in kids:\n        os.waitpid(pid, 0)\n", "out of memory|killed"),
}


@pytest.mark.spawns
@pytest.mark.parametrize("name", list(WORKER_LEFTOVERS))
@pytest.mark.parametrize("path", ["local", "gradescope-bubblewrap", "gradescope-uid"])
def test07_what_the_worker_leaves_fails_its_test_and_never_the_grader(path, name, corpus, gradescope):
    code, fragment = WORKER_LEFTOVERS[name]
    assert_s1_fails(graded(path, attack(corpus, f"{name.replace(' ', '-')}-{path}", code), gradescope), fragment)


@pytest.mark.spawns
def test07b_without_cgroups_the_watchdog_caps_the_children_together(corpus, monkeypatch):
    monkeypatch.setenv("CS451_NO_CGROUP", "1")
    code, fragment = WORKER_LEFTOVERS["memory spread over four children"]
    out = run_local(attack(corpus, "memory-watchdog", code))
    assert_s1_fails(out, "out of memory")


@pytest.mark.spawns
@pytest.mark.parametrize("path", ["local", "gradescope-bubblewrap"])
def test08_a_forged_interface_answer_and_a_deep_job_tree_do_not_crash_grading(path, corpus, gradescope):
    forged = ("import json as _j, os as _o\n"
              "if _j.load(open('request.json'))['probe'] == '__interface__':\n"
              "    np.savez('output.npz', problems=np.array('=HYPERLINK(\"x\")'))\n"
              "    open('status.json', 'w').write('{\"ok\": true}')\n    _o._exit(0)\n")
    tree = ("    import os\n    here = os.open('.', os.O_RDONLY)\n    for _ in range(3000):\n        os.mkdir('d')\n"
            "        os.chdir('d')\n    os.fchdir(here)\n    print('BLOCKED')\n")
    out = graded(path, attack(corpus, f"forged-{path}", tree, at_import=forged), gradescope)
    assert out.points == {"S1": 10, "S2": 10}, out.messages
    assert "could not be read" in out.summary


# --- processes and files that outlive a test -------------------------------------------------------

def live_processes_with(marker: str) -> list[int]:
    found = []
    for cmdline in Path("/proc").glob("[0-9]*/cmdline"):
        try:
            if marker.encode() in cmdline.read_bytes():
                found.append(int(cmdline.parent.name))
        except OSError:
            continue
    return found


@pytest.mark.spawns
@pytest.mark.parametrize("path", FAST_PATHS)
def test09_no_daemon_outlives_grading(path, corpus, gradescope):
    marker = f"cs451-daemon-{uuid.uuid4().hex[:8]}"
    code = ("    import subprocess, sys\n"
            f"    subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(600)', {marker!r}], start_new_session=True,"
            " stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)\n    print('BLOCKED')\n")
    out = graded(path, attack(corpus, f"daemon-{path}", code), gradescope)
    assert out.points == {"S1": 10, "S2": 10}, out.messages
    assert live_processes_with(marker) == []


@pytest.mark.spawns
@pytest.mark.parametrize("path", FAST_PATHS)
def test10_nothing_one_test_leaves_in_shared_places_reaches_the_next(path, corpus, gradescope):
    code = ("    import glob, os\n"
            "    seen = [open(p).read() for d in ('/tmp', '/var/tmp', '/dev/shm') for p in glob.glob(d + '/cs451-leak-*')]\n"
            "    print('LEAKED', seen) if seen else print('BLOCKED')\n"
            "    for d in ('/tmp', '/var/tmp', '/dev/shm'):\n"
            "        try:\n            open(f'{d}/cs451-leak-{os.getpid()}', 'w').write(repr((fovy, aspect, near, far)))\n"
            "        except OSError:\n            pass\n")
    out = graded(path, attack(corpus, f"leak-{path}", code), gradescope)
    assert_blocked(out)
    assert not [p for d in ("/tmp", "/var/tmp", "/dev/shm") for p in Path(d).glob("cs451-leak-*")]


@pytest.mark.spawns
def test11_a_classmate_can_neither_read_nor_break_another(corpus):
    top = world_readable_dir("cs451-class-")
    honest = top / "class" / "alice" / "sphere"
    shutil.copytree(KIT_ROOT / "reference" / "sphere", honest, ignore=shutil.ignore_patterns("__pycache__"))
    targets = [str(honest / "camera.py"), str(top / "grades" / "alice"), str(top / "class")]
    code = reaches(targets) + reaches([str(top / "grades" / "alice"), str(honest)], write=True) + \
        "    import glob\n    print('LEAKED', glob.glob('/tmp/cs451-run-*/*')) if glob.glob('/tmp/cs451-run-*/*') else None\n"
    shutil.copytree(attack(corpus, "mallory", code), top / "class" / "mallory")
    try:
        grade_roster(stage="sphere", roster=top / "class", output=top / "grades", show_progress=False)
        rows = {r["student"]: r for r in csv.DictReader(open(top / "grades" / "gradebook.csv"))}
        assert float(rows["alice"]["score"]) == 100 and float(rows["mallory"]["score"]) == 100
        printed = (top / "grades" / "mallory" / "results.json").read_text()
        assert "LEAKED" not in printed and "BLOCKED" in printed
    finally:
        shutil.rmtree(top, ignore_errors=True)


@pytest.mark.spawns
def test12_gradebook_cells_that_look_like_formulas_are_quoted(corpus, tmp_path):
    klass = world_readable_dir("cs451-class-")
    try:
        shutil.copytree(KIT_ROOT / "reference" / "sphere", klass / "=2+3" / "sphere", ignore=shutil.ignore_patterns("__pycache__"))
        grade_roster(stage="sphere", roster=klass, output=tmp_path / "grades", show_progress=False, only=["S1"])
        cells = [r["student"] for r in csv.DictReader(open(tmp_path / "grades" / "gradebook.csv"))]
        assert cells == ["'=2+3"]
    finally:
        shutil.rmtree(klass, ignore_errors=True)


# --- points from nothing, and from what a release ships --------------------------------------------

@pytest.mark.spawns
@pytest.mark.parametrize("stage", stage_names())
def test13_a_submission_that_does_nothing_scores_zero(stage):
    root = world_readable_dir("cs451-vacuous-")
    try:
        result = grade(stage, adversaries.vacuous(stage, root), show_progress=False)
        assert result.score == 0, [(r.test.number, r.score, r.verdict.message) for r in result.results if r.score]
    finally:
        shutil.rmtree(root, ignore_errors=True)


@pytest.mark.spawns
@pytest.mark.parametrize("stage", ["sphere", pytest.param("whitted", marks=pytest.mark.slow),
                                   pytest.param("hemicube", marks=pytest.mark.slow), "radiosity"])
def test14_a_submission_made_of_what_the_release_ships_scores_zero(stage):
    top = world_readable_dir("cs451-scavenger-")
    try:
        release = build_release(stage, top / "release")
        assert adversaries.task_answer_definitions(release, stage) == []
        result = grade(stage, adversaries.scavenger(stage, release, top / "sub"), show_progress=False)
        assert result.score == 0, [(r.test.number, r.score, r.verdict.message) for r in result.results if r.score]
    finally:
        shutil.rmtree(top, ignore_errors=True)


@pytest.mark.spawns
def test15_a_huge_hierarchy_fails_at_once_by_its_size():
    """A million nodes for a thousand boxes: refused from the parameters, before any walk of the tree."""
    root = world_readable_dir("cs451-bvh-")
    try:
        shutil.copytree(KIT_ROOT / "reference" / "whitted", root / "whitted", ignore=shutil.ignore_patterns("__pycache__"))
        init = root / "whitted" / "__init__.py"
        init.write_text(init.read_text() + (
            "\n\ndef build_bvh(lo, hi):\n    import numpy as np\n    m = 1_000_000\n"
            "    return {'lo': np.zeros((m, 3)), 'hi': np.ones((m, 3)), 'child': np.full(m, -1), 'start': np.zeros(m, int),"
            " 'count': np.ones(m, int), 'order': np.arange(len(lo))}\n"))
        result = grade("whitted", root, show_progress=False, tasks=["W4"], test_timeout=60)
        w4 = [r for r in result.results if not r.test.hidden]
        assert all(r.score == 0 and "1000000 nodes for" in r.verdict.message for r in w4), \
            [r.verdict.message for r in w4]
    finally:
        shutil.rmtree(root, ignore_errors=True)


@pytest.mark.spawns
def test16_without_isolation_a_kit_refuses_to_run_a_submission(corpus, monkeypatch):
    """The uid-only fallback on this checkout: its .git and reference are world-readable, so it must refuse."""
    monkeypatch.setenv("CS451_SANDBOX", "uid")
    modes = {p: stat.S_IMODE(p.stat().st_mode) for p in (KIT_ROOT, KIT_ROOT / ".git")}
    if all(m & 0o005 == 0 for m in modes.values()):
        pytest.skip("this checkout is private already")
    with pytest.raises(sandbox.IsolationError, match="cannot be isolated"):
        grade("sphere", attack(corpus, "refused"), show_progress=False, tasks=["S1"])


@pytest.mark.spawns
def test17_a_grading_run_leaves_no_folder_behind(corpus, monkeypatch):
    """The run folder (staged upload, engine, job folders) goes when grading ends, even after a hostile test."""
    seen = []
    opened = sandbox.Sandbox._open

    def remember(self):
        opened(self)
        seen.append(self.run_dir.parent)
    monkeypatch.setattr(sandbox.Sandbox, "_open", remember)
    code, _ = WORKER_LEFTOVERS["status.json is a FIFO"]
    run_local(attack(corpus, "leaves-nothing", code))
    assert seen and not [p for p in seen if p.exists()]


@pytest.mark.spawns
def test18_a_direct_solve_posing_as_progressive_refinement_earns_nothing_for_r3():
    """B from (I − ρF)B = E is the converged answer; the furnace and scene tests also ask for the shots that get there."""
    root = world_readable_dir("cs451-direct-")
    try:
        shutil.copytree(KIT_ROOT / "reference" / "radiosity", root / "radiosity", ignore=shutil.ignore_patterns("__pycache__"))
        init = root / "radiosity" / "__init__.py"
        init.write_text(init.read_text() + (
            "\n\ndef progressive_refinement(row, areas, reflectance, emission, tolerance, max_shots, overshoot, on_shot):\n"
            "    import numpy as np\n    n = len(areas)\n    F = np.array([row(i) for i in range(n)])\n"
            "    E = np.asarray(emission, float)\n    rho = np.asarray(reflectance, float)\n"
            "    B = np.column_stack([np.linalg.solve(np.eye(n) - rho[:, c:c + 1] * F, E[:, c]) for c in range(3)])\n"
            "    return B, np.zeros_like(B), list(range(n))\n"))
        result = grade("radiosity", root, show_progress=False, tasks=["R3"])
        earned = [(r.test.number, r.score, r.verdict.message) for r in result.results if r.score]
        assert result.score == 0, earned
    finally:
        shutil.rmtree(root, ignore_errors=True)
