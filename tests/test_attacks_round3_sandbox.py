"""Hostile submissions of the third round (issue 34) against the sandbox itself: other copies of the kit on the
host (item 5), what one test leaves for the next (item 3), and disk, CPU and processes (item 7).

Each attack is built here at run time in a temporary folder and graded through the paths of
``test_attacks.py``: locally, in a roster, and through the Gradescope zip in the layout its own ``setup.sh``
makes, under bubblewrap and under the uid-only fallback. The uid fallback's runs happen as on a server with no
other copy of the kit (``hidden_host.py``: this machine's checkout and ``/tmp`` hidden), so what they find is
only what the test puts there. Attacks print ``LEAKED`` when they get what they reach for, ``BLOCKED`` when not.
"""
from __future__ import annotations

import json
import os
import shutil
import stat
import subprocess
import sys
import threading
import time
import zipfile
from pathlib import Path

import pytest

from cs451 import KIT_ROOT
from cs451.grading import canary, sandbox
from cs451.packaging.gradescope import build_gradescope

from conftest import world_readable_dir
from test_attacks import TASKS, attack, graded, run_gradescope

pytestmark = pytest.mark.skipif(not sandbox.is_root(), reason="the attacks are graded as a root grader grades them")


@pytest.fixture(scope="module")
def corpus():
    root = world_readable_dir("cs451-round3-")
    yield root
    shutil.rmtree(root, ignore_errors=True)


# --- item 5: other copies of the kit on the host ---------------------------------------------------------

def borrower(root: Path, name: str, build: Path, kit_zip: Path) -> Path:
    """A starter that answers with the reference it finds in a wheel's build folder or an autograder zip."""
    folder = root / name
    shutil.copytree(KIT_ROOT / "starter" / "sphere", folder / "sphere", ignore=shutil.ignore_patterns("__pycache__"))
    (folder / "sphere" / "__init__.py").write_text(
        "import importlib.util, os, sys, tempfile, zipfile\n"
        f"BUILD, ZIP = {str(build / 'lib' / 'cs451_kit' / 'reference' / 'sphere')!r}, {str(kit_zip)!r}\n"
        "def _leak():\n"
        "    if os.access(BUILD, os.R_OK):\n"
        "        return BUILD\n"
        "    try:\n"
        "        out = tempfile.mkdtemp()\n"
        "        with zipfile.ZipFile(ZIP) as z:\n"
        "            z.extractall(out, [n for n in z.namelist() if n.startswith('reference/sphere/')])\n"
        "        return os.path.join(out, 'reference', 'sphere')\n"
        "    except OSError:\n"
        "        return None\n"
        "_where = _leak()\n"
        "print('LEAKED' if _where else 'BLOCKED', _where)\n"
        "if _where:\n"
        "    _spec = importlib.util.spec_from_file_location('_leaked', os.path.join(_where, '__init__.py'),\n"
        "                                                   submodule_search_locations=[_where])\n"
        "    _mod = importlib.util.module_from_spec(_spec)\n"
        "    sys.modules['_leaked'] = _mod\n"
        "    _spec.loader.exec_module(_mod)\n"
        "    globals().update({k: v for k, v in vars(_mod).items() if not k.startswith('__')})\n")
    for path in [folder, *folder.rglob("*")]:
        os.chmod(path, 0o755 if path.is_dir() else 0o644)
    return folder


@pytest.fixture
def stray_copies(gradescope):
    """What an instructor's machine may hold beside the grading: a wheel's build folder and an autograder zip left
    in a kit's folder, world-readable, as the kit's own builds once left them (in the layout's folder, which the
    uid fallback's runs keep visible)."""
    top = gradescope[0].parent
    build, kit = top / "cs451-kit-build", top / "instructor-kit"
    shutil.copytree(KIT_ROOT / "reference" / "sphere", build / "lib" / "cs451_kit" / "reference" / "sphere",
                    ignore=shutil.ignore_patterns("__pycache__"))
    kit_zip = build_gradescope("sphere", kit / "autograder.zip")
    for path in [build, kit, *build.rglob("*"), *kit.rglob("*")]:
        os.chmod(path, 0o755 if path.is_dir() else 0o644)
    yield build, kit_zip
    shutil.rmtree(build, ignore_errors=True)
    shutil.rmtree(kit, ignore_errors=True)


@pytest.mark.spawns
def test01_a_readable_copy_of_the_kit_stops_the_uid_fallback_before_any_code_runs(corpus, gradescope, stray_copies):
    """Before: the borrower printed LEAKED and scored 20/20 (S1, S2) through the build folder. After: the canary finds
    the copy and nothing is run."""
    out = run_gradescope(gradescope, borrower(corpus, "borrower-uid", *stray_copies), "uid")
    assert sum(out.points.values()) == 0 and "LEAKED" not in out.printed, (out.points, out.printed)
    assert "can read a copy of the kit's reference or answers" in out.summary, out.summary
    assert str(stray_copies[0]) in out.summary


@pytest.mark.spawns
def test02_under_bubblewrap_the_host_copies_are_not_there(corpus, gradescope, stray_copies):
    """Bubblewrap shows an allow-list (system folders, the Python environment, the engine, the upload, the job):
    no host /tmp, so the same copies are out of sight, the borrower gets nothing and the reference keeps full marks."""
    out = run_gradescope(gradescope, borrower(corpus, "borrower-bwrap", *stray_copies), "bubblewrap")
    assert "LEAKED" not in out.printed and "BLOCKED" in out.printed, (out.printed, out.summary)
    assert sum(out.points.values()) == 0
    honest = run_gradescope(gradescope, KIT_ROOT / "reference", "bubblewrap")
    assert honest.points == {"S1": 10, "S2": 10}, honest.messages


@pytest.mark.spawns
def test03_the_kit_s_own_builds_leave_nothing_readable(tmp_path):
    """The autograder zip is private to its maker (even over an older, readable file, under umask 0); building the
    wheel's folders (setup.py) happens in a private temporary folder that is gone afterwards."""
    old = tmp_path / "autograder.zip"
    old.write_text("an older zip")
    old.chmod(0o644)
    mask = os.umask(0)
    try:
        build_gradescope("sphere", old)
    finally:
        os.umask(mask)
    assert stat.S_IMODE(old.stat().st_mode) == 0o600 and zipfile.ZipFile(old).namelist()
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    env = {**os.environ, "TMPDIR": str(scratch)}
    done = subprocess.run([sys.executable, "setup.py", "-q", "build"], cwd=KIT_ROOT, env=env, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert list(scratch.iterdir()) == []


def test04_the_canary_finds_every_kind_of_copy_and_nothing_else(tmp_path):
    """What counts as a copy of the kit's reference or answers (canary.search), and what does not: the starter's
    docstring example of a region, a student's own package, a folder the grader gives on purpose."""
    stages = {"sphere", "whitted"}
    (tmp_path / "a" / "reference" / "sphere").mkdir(parents=True)
    (tmp_path / "a" / "reference" / "sphere" / "__init__.py").write_text("")
    (tmp_path / "b" / "autograder" / "whitted").mkdir(parents=True)
    (tmp_path / "b" / "autograder" / "whitted" / "hidden.py").write_text("TESTS = []\n")
    (tmp_path / "c" / ".cs451-cache" / "truth").mkdir(parents=True)
    with zipfile.ZipFile(tmp_path / "kit.whl", "w") as z:
        z.writestr("cs451_kit/reference/sphere/camera.py", "")
    (tmp_path / "renamed.py").write_text("def f():\n    # BEGIN SOLUTION S1: hint\n    return 1\n    # END SOLUTION\n")
    (tmp_path / "example.py").write_text('"""\n    # BEGIN SOLUTION S1: hint\n    ...solution...\n    # END SOLUTION\n"""\n')
    (tmp_path / "student" / "sphere").mkdir(parents=True)
    (tmp_path / "student" / "sphere" / "camera.py").write_text("def perspective():\n    return 1\n")
    (tmp_path / "given" / "reference" / "whitted").mkdir(parents=True)
    (tmp_path / "given" / "reference" / "whitted" / "__init__.py").write_text("")
    found, complete, _ = canary.search(str(tmp_path), stages, [str(tmp_path / "given")], time.monotonic() + 60)
    where = sorted(f.split(":")[0].removeprefix(str(tmp_path)) for f in found)
    assert complete and where == ["/a/reference/sphere", "/b/autograder/whitted/hidden.py", "/c/.cs451-cache/truth",
                                  "/kit.whl", "/renamed.py"], found
    _, complete, _ = canary.search(str(tmp_path), stages, [], time.monotonic() - 1)
    assert not complete


# --- item 3: what one test leaves for the next ----------------------------------------------------------------

#: A channel through the page cache of a file every test can read (the submission's own 4 MiB blob, as staged):
#: a test sends a message by dropping the blob's pages from the cache (fsync, then POSIX_FADV_DONTNEED: both allowed
#: on a read-only file) and reading back one page per set bit; the next test reads the bits without touching the
#: pages (preadv2 with RWF_NOWAIT fails on a page that is not cached). Every import prints what it finds, and
#: when; perspective() sends its parameters.
PAGE_CHANNEL = '''import os as _os, time as _time
_BLOB, _PAGES = _os.path.join(_os.path.dirname(__file__), "blob.bin"), 1024


def _receive():
    fd = _os.open(_BLOB, _os.O_RDONLY)
    bits = []
    for page in range(_PAGES):
        try:
            _os.preadv(fd, [bytearray(1)], page * 4096, _os.RWF_NOWAIT)
            bits.append("1")
        except BlockingIOError:
            bits.append("0")
        except OSError:                     # no such reads on this file system (tmpfs): no channel
            return None
    _os.close(fd)
    data = bytes(int("".join(bits[i:i + 8]), 2) for i in range(0, _PAGES, 8))
    return data[1:1 + data[0]].decode("ascii", "replace") if 0 < data[0] < 100 else None


def _send(text):
    data = bytes([len(text)]) + text.encode()
    fd = _os.open(_BLOB, _os.O_RDONLY)
    _os.fsync(fd)
    _os.posix_fadvise(fd, 0, 0, _os.POSIX_FADV_RANDOM)
    _os.posix_fadvise(fd, 0, 0, _os.POSIX_FADV_DONTNEED)
    for i, byte in enumerate(data):
        for b in range(8):
            if byte >> (7 - b) & 1:
                _os.pread(fd, 1, (i * 8 + b) * 4096)
    _os.close(fd)


print("CHANNEL at", repr(_time.time()), "received", repr(_receive()))
'''


def page_channel(root: Path, name: str) -> Path:
    folder = attack(root, name, "    _send(repr((fovy, aspect, near, far)))\n", at_import=PAGE_CHANNEL)
    with open(folder / "sphere" / "blob.bin", "wb") as f:
        f.write(os.urandom(4 << 20))
    os.chmod(folder / "sphere" / "blob.bin", 0o644)
    return folder


def channel_reports(data: dict) -> list[tuple[float, bool, str]]:
    """(when the test's worker started, whether the test is hidden, what it received), in the order they ran."""
    found = []
    for t in data["tests"]:
        for line in t["output"].splitlines():
            if line.startswith("CHANNEL at "):
                when, received = line.removeprefix("CHANNEL at ").split(" received ", 1)
                found.append((float(when), t["visibility"] == "after_published", received))
    return sorted(found)


@pytest.mark.spawns
@pytest.mark.parametrize("mode", ["bubblewrap", pytest.param("uid", marks=pytest.mark.slow)])
def test05_a_hidden_test_s_parameters_never_reach_a_visible_test(mode, corpus, gradescope):
    """Before (Gradescope layout, bubblewrap): S1.2 received S1.1's parameters, and the visible S2.1, run right after
    the hidden S1.3, printed the hidden one's, (12.5, 0.4, 0.01, 10000.0), through the staged blob's page cache.
    After: every visible test runs before any hidden one, and each test reads its own fresh copy of the submission
    and the engine, so no test receives anything."""
    from test_packaging import run_autograder
    root, env = gradescope
    data = run_autograder((root, {**env, "CS451_SANDBOX": mode}), page_channel(corpus, f"pages-{mode}"),
                          "--tasks", ",".join(TASKS))
    reports = channel_reports(data)
    assert len(reports) == len(data["tests"]), data["output"]          # every test's worker printed
    hidden_from = min(i for i, (_, hidden, _) in enumerate(reports) if hidden)
    assert not [r for r in reports[hidden_from:] if not r[1]], reports        # no visible test after a hidden one
    visible = " ".join(received for _, hidden, received in reports if not hidden)
    assert "(12.5, 0.4, 0.01, 10000.0)" not in visible, reports
    assert {received for _, _, received in reports} == {"None"}, reports    # no test receives another's message
    assert sum(t["score"] for t in data["tests"]) == 20, (reports, data["output"])   # S1 and S2, all earned


# --- item 7: disk, CPU and processes ------------------------------------------------------------------------

#: Five files of 255 MiB (under the 256 MiB per-file limit) into each place a test may write, saying after each file
#: how much it holds there; then the right answer, so the attack costs nothing unless it is stopped.
DISK_FILLER = '''    import os
    for place in (".", "/tmp", "/dev/shm"):
        total = 0
        try:
            for i in range(5):
                with open(os.path.join(place, f"fill-{os.getpid()}-{i}"), "wb") as f:
                    for _ in range(255):
                        f.write(b"x" * (1 << 20))
                total += 255 << 20
                print("WROTE", place, total, flush=True)
        except OSError as err:
            print("STOPPED", place, total, type(err).__name__, flush=True)
'''


def written(printed: str) -> dict[str, int]:
    """The most the filler held in each place, by its own reports."""
    held: dict[str, int] = {}
    for line in printed.splitlines():
        if line.startswith(("WROTE ", "STOPPED ")):
            place, total = line.split()[1:3]
            held[place] = max(held.get(place, 0), int(total))
    return held


@pytest.mark.spawns
@pytest.mark.parametrize("path", ["local", "local-watch", "gradescope-bubblewrap",
                                  pytest.param("gradescope-uid", marks=pytest.mark.slow)])
def test06_a_test_cannot_fill_the_grader_s_disk(path, corpus, gradescope, monkeypatch):
    """Before: each S1 test wrote 5 × 255 MiB into its job folder (1.25 GiB in the grader's temp folder) and 1.25 GiB
    into /tmp, and passed. After: the job folder is a 512 MiB tmpfs of its own (where the grader may mount one; else
    a watch ends the test past 768 MiB, as it does in the uid mode, counting what the uid keeps in shared places),
    /tmp under bubblewrap 256 MiB and /dev/shm 64 MiB; nothing past that is kept and S2 keeps its points."""
    if path == "local-watch":
        monkeypatch.setenv("CS451_NO_MOUNT", "1")
    out = graded("local" if path == "local-watch" else path, attack(corpus, f"filler-{path}", DISK_FILLER), gradescope)
    held = written(out.printed)
    assert held, (out.printed[-2000:], out.summary)
    mib = 1 << 20
    if path == "gradescope-uid" or path == "local-watch":   # a watch: ended within a file or so of its cap
        assert sum(held.values()) <= sandbox.JOB_DISK + sandbox.TMP_DISK + 255 * mib, held
    else:
        assert held.get(".", 0) <= sandbox.JOB_DISK and held.get("/tmp", 0) <= sandbox.TMP_DISK, held
        assert held.get("/dev/shm", 0) <= sandbox.SHM_DISK, held
    assert out.points.get("S2") == 10, out.messages


@pytest.mark.spawns
def test07_each_submission_s_tests_share_the_cpu_with_the_same_weight(corpus):
    """Two submissions graded at once each get a CPU share of their own with the same weight, and every process a
    test starts is in its submission's share, whatever sessions it makes (cs451 bench fair_share measures what it
    does for an honest student beside one that burns the CPU)."""
    from cs451.grading import cgroups
    from cs451.grading.runner import engine_sources, protected_paths
    boxes = [sandbox.Sandbox("sphere", attack(corpus, f"share-{i}"), engine_sources("sphere"), protected_paths())
             for i in range(2)]
    with boxes[0] as first, boxes[1] as second:
        if first.share is None:
            pytest.skip("no cpu controller to make a share with here")
        assert first.share.folder != second.share.folder and "CPU share" in first.describe()
        weight = "cpu.weight" if first.share.version == 2 else "cpu.shares"
        assert (first.share.folder / weight).read_text() == (second.share.folder / weight).read_text()
        folders = [first.share.folder, second.share.folder]
        marker = "cs451-share-child"
        script = f"import os, subprocess, sys\nos.setsid()\nsubprocess.run([sys.executable, '-c', 'import time; time.sleep(4)', {marker!r}])\n"
        job = first.new_job()
        found: list[int] = []
        runner = threading.Thread(target=first.run, args=(["-c", script], job, sandbox.Limits(30)))
        runner.start()
        while runner.is_alive() and not found:
            for procs in [first.share.folder / "cgroup.procs", *first.share.folder.glob("*/cgroup.procs")]:
                try:
                    pids = procs.read_text().split()
                except OSError:
                    continue
                found += [int(p) for p in pids if marker.encode() in _cmdline(int(p))]
            time.sleep(0.05)
        runner.join()
        first.finish_job(job)
        assert found   # the worker's child, in a session of its own, is in its submission's share
    assert not [f for f in folders if f.exists()]


def _cmdline(pid: int) -> bytes:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:
        return b""


@pytest.mark.spawns
def test08_a_roster_under_the_uid_fallback_refuses_beside_a_readable_copy(corpus, gradescope):
    """The roster's path, from a kit kept private (the Gradescope layout's, as ``setup.sh`` left it) with the class
    and grades private too, as the uid fallback needs. Before: the borrower scored 10/10 on S1 through a
    world-readable build folder. After: with that folder on the host no submission runs and every row says why;
    without it, the honest student gets full marks."""
    from hidden_host import hiding_host
    root, env = gradescope
    top = world_readable_dir("cs451-r3-roster-")
    try:
        klass, grades = top / "class", top / "grades"
        shutil.copytree(KIT_ROOT / "reference" / "sphere", klass / "alice" / "sphere", ignore=shutil.ignore_patterns("__pycache__"))
        build = top / "cs451-kit-build"
        shutil.copytree(KIT_ROOT / "reference" / "sphere", build / "lib" / "cs451_kit" / "reference" / "sphere",
                        ignore=shutil.ignore_patterns("__pycache__"))
        shutil.copytree(borrower(corpus, "borrower-roster", build, top / "none.zip"), klass / "mallory")
        for path in [build, *build.rglob("*")]:
            os.chmod(path, 0o755 if path.is_dir() else 0o644)
        os.chmod(klass, 0o700)
        grade = ("import csv, json, sys\nfrom cs451.grading.roster import grade_roster\n"
                 f"grade_roster(stage='sphere', roster={str(klass)!r}, output={str(grades)!r}, show_progress=False, only=['S1'])\n"
                 f"print(json.dumps(list(csv.DictReader(open({str(grades / 'gradebook.csv')!r})))))\n")

        def rows() -> dict[str, dict]:
            grades.mkdir(mode=0o700)
            done = subprocess.run(hiding_host([env["CS451_PYTHON"], "-c", grade], [Path(env["CS451_HOME"]).parent, top]),
                                  capture_output=True, text=True, timeout=600, cwd=env["CS451_HOME"],
                                  env={**env, "CS451_SANDBOX": "uid"})
            assert done.returncode == 0, done.stderr[-3000:]
            return {r["student"]: r for r in json.loads(done.stdout.strip().splitlines()[-1])}
        refused = rows()
        assert all(float(r["score"]) == 0 and "can read a copy of the kit's reference" in r["problems"]
                   for r in refused.values()), [r["problems"] for r in refused.values()]
        shutil.rmtree(build)
        shutil.rmtree(klass / "mallory")
        shutil.rmtree(grades)
        alone = rows()["alice"]
        assert float(alone["score"]) == 10, alone
    finally:
        shutil.rmtree(top, ignore_errors=True)
