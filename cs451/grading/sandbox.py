"""Running untrusted student code: one sandbox per grading run, one fresh worker per test.

A submission is hostile: it may read anything its user can (the kit's ``.git``,
the reference, the answer cache, a classmate's folder), leave daemons behind,
fork children that together hold gigabytes, or leave data in a shared temporary
folder for the next test. The sandbox therefore fails closed:

- it copies the engine (``cs451/`` only: no stage's reference, an earlier stage's
  results come in as trusted arrays) and the staged upload into a private run
  folder, fresh for each test; the worker sees only those (read-only), its own
  job folder and a private ``/tmp``;
- ``bubblewrap`` (private mount, pid, network, IPC and UTS namespaces) where it
  works, under a throwaway uid per test when the grader is root; else, as root,
  the throwaway uid alone, with the kit's secrets checked unreadable first;
  else (not root, no namespaces) it refuses, unless this is a student copy of
  the kit, which holds nothing the sandbox protects;
- before the first test a canary runs exactly as a test would and must find
  every protected path unreadable, or grading stops and says why;
- every test gets time, CPU, address-space, file-size and output limits, a
  cgroup capping the memory and processes of everything it starts (or, where
  cgroups cannot be made, a watchdog that sums them), a disk quota (its job
  folder a tmpfs of ``JOB_DISK`` bytes where the grader may mount one, ``/tmp``
  and ``/dev/shm`` capped tmpfs under bubblewrap, else a watch that sums what it
  keeps), and afterwards every process it left is killed and every file it
  left is removed;
- each test reads its own fresh copy of the engine and the upload, so nothing
  one test leaves (in the page cache of a file they share, say) reaches the next;
- each graded submission has a CPU share of the same weight as any other's
  (:func:`.cgroups.create_share`), however many processes or sessions it makes.

Only the literal word ``reference`` runs without the sandbox (``run_trusted``).
"""
from __future__ import annotations

import ctypes
import json
import os
import random
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from typing import Callable
from pathlib import Path

try:  # not on Windows: there the student copy runs without limits (nothing to protect)
    import resource
except ImportError:  # pragma: no cover
    resource = None  # type: ignore[assignment]

from .. import lecturer_only
from ..errors import KitError
from . import cgroups
from .staging import StagedUpload, stage_upload

MEMORY_LIMIT = 3 << 30         # bytes of address space per process (llvmpipe reserves generously)
SUBMISSION_MEMORY = 1 << 30    # bytes of memory for everything one test starts, together
FILE_LIMIT = 256 << 20         # largest file a worker may write
JOB_DISK = 512 << 20           # bytes a test may keep in its job folder (its scratch, and its answer)
TMP_DISK = 256 << 20           # bytes in its /tmp under bubblewrap
SHM_DISK = 64 << 20            # bytes in its /dev/shm under bubblewrap
FULL_BELOW = 1 << 20           # a job folder with less free is full: its answer may not have fitted
MS_NOSUID, MS_NODEV, MNT_DETACH = 2, 4, 2
PROCESS_ALLOWANCE = 64         # processes and threads a test may run (llvmpipe uses one per core)
OUTPUT_LIMIT = 4000            # characters of printed output kept
CLONE_NEWNET = 0x40000000
UID_RANGE = (2_000_000_000, 2_100_000_000)   # throwaway uids: far above any real account
CANARY_SECONDS = 90.0          # the canary's whole run
CANARY_SEARCH_SECONDS = 60.0   # its search of everything the sandbox user can read

#: How each mode is described in results and reports.
DESCRIPTIONS = {
    "bubblewrap": "bubblewrap (private mount, pid, network and IPC namespaces)",
    "uid": "a throwaway user per test, with the kit's files checked unreadable first",
    "none": "no isolation (a student copy of the kit: your own code runs as you)",
}


def _sandbox_litter(folder: str, names: list[str]) -> set[str]:
    """What a sandbox's copy of the engine leaves out: byte code, and the lecturers' folders (no test imports them)."""
    left = set(shutil.ignore_patterns("*.pyc", "__pycache__")(folder, names))
    return left | {name for name in names if lecturer_only(Path(folder) / name)}


class IsolationError(KitError):
    """The sandbox cannot be set up as required here: grading must not go on (the message says why)."""


def private_folder_above(path: Path) -> Path | None:
    """The first folder on the way to ``path`` (as written, and with its links resolved) that users who are neither
    its owner nor in its group may not pass through (no ``o+x``), or None."""
    seen: set[Path] = set()
    for route in (Path(os.path.abspath(path)), Path(path).resolve()):
        for folder in [*reversed(route.parents), route]:
            if folder in seen:
                continue
            seen.add(folder)
            try:
                mode = os.stat(folder).st_mode
            except OSError:
                continue
            if stat.S_ISDIR(mode) and not mode & stat.S_IXOTH:
                return folder
    return None


def is_root() -> bool:
    return hasattr(os, "geteuid") and os.geteuid() == 0


@dataclass(frozen=True)
class Limits:
    wall_seconds: float
    memory_bytes: int = MEMORY_LIMIT
    file_bytes: int = FILE_LIMIT
    submission_memory: int = SUBMISSION_MEMORY


@dataclass
class Completed:
    returncode: int | None
    output: str
    timed_out: bool
    out_of_memory: bool = False
    peak_memory: int = 0          # bytes, where a cgroup or the watchdog measured it
    disk_full: bool = False       # it filled its job folder's tmpfs, or the disk watch ended it


def worker_env(home: str, engine: str) -> dict[str, str]:
    """Only what GL and Python need; nothing of the grader's (tokens, paths to the reference)."""
    keep = ("PATH", "LANG", "LC_ALL", "DISPLAY", "LD_LIBRARY_PATH", "EGL_PLATFORM", "LIBGL_ALWAYS_SOFTWARE",
            "GALLIUM_DRIVER", "LP_NUM_THREADS", "__EGL_VENDOR_LIBRARY_FILENAMES", "MESA_SHADER_CACHE_DISABLE")
    env = {k: os.environ[k] for k in keep if k in os.environ}
    env.setdefault("PATH", "/usr/bin:/bin")
    env.setdefault("EGL_PLATFORM", "surfaceless")
    env.setdefault("LP_NUM_THREADS", "2")   # llvmpipe starts one thread per core otherwise: past the process cap on big hosts
    env.update(HOME=home, TMPDIR=home, PYTHONDONTWRITEBYTECODE="1", PYTHONHASHSEED="0", PYTHONNOUSERSITE="1",
               PYTHONPATH=engine, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MESA_SHADER_CACHE_DISABLE="true",
               NUMBA_CACHE_DIR=home)
    return env


# --- the pieces a child runs before exec ------------------------------------------------

def _set_limits(limits: Limits) -> None:
    if resource is None:
        return
    cpu = int(limits.wall_seconds * 2) + 5
    resource.setrlimit(resource.RLIMIT_CPU, (cpu, cpu + 5))
    resource.setrlimit(resource.RLIMIT_AS, (limits.memory_bytes, limits.memory_bytes))
    resource.setrlimit(resource.RLIMIT_FSIZE, (limits.file_bytes, limits.file_bytes))
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
    try:  # under a container's memory cap (Gradescope: 768 MB) the kernel's OOM killer takes the worker first
        with open("/proc/self/oom_score_adj", "w") as f:
            f.write("1000")
    except OSError:
        pass


def _drop_to(uid: int) -> None:
    os.setgroups([])
    os.setgid(uid)
    os.setuid(uid)
    if os.getuid() != uid or os.geteuid() != uid:  # never go on as anyone else
        os._exit(111)


def _count_processes(uid: int) -> int:
    return len(_processes_of(uid))


def _processes_of(uid: int) -> list[int]:
    """Live processes of ``uid`` (zombies are dead already: they wait only for a parent to reap them)."""
    found = []
    for status in Path("/proc").glob("[0-9]*/status"):
        try:
            fields = dict(line.split(":", 1) for line in status.read_text().splitlines() if ":" in line)
            if int(fields["Uid"].split()[0]) == uid and not fields["State"].strip().startswith(("Z", "X")):
                found.append(int(status.parent.name))
        except (OSError, ValueError, KeyError):
            continue
    return found


def _descendants(root: int) -> list[int]:
    children: dict[int, list[int]] = {}
    for stat_file in Path("/proc").glob("[0-9]*/stat"):
        try:
            text = stat_file.read_text()
            ppid = int(text[text.rindex(")") + 2:].split()[1])
        except (OSError, ValueError):
            continue
        children.setdefault(ppid, []).append(int(stat_file.parent.name))
    out, todo = [], [root]
    while todo:
        pid = todo.pop()
        out.append(pid)
        todo.extend(children.get(pid, []))
    return out


def _rss(pid: int) -> int:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    except (OSError, ValueError):
        pass
    return 0


def kill_uid(uid: int) -> None:
    """Kill every process of ``uid``: a child drops to it and signals everyone it may (``kill(-1)``)."""
    for _ in range(100):
        if not _processes_of(uid):
            return
        pid = os.fork()
        if pid == 0:
            try:
                _drop_to(uid)
                os.kill(-1, signal.SIGKILL)
            finally:
                os._exit(0)
        os.waitpid(pid, 0)
        time.sleep(0.01)


def _free_uid() -> int:
    for _ in range(1000):
        uid = random.randrange(*UID_RANGE)
        if not _processes_of(uid):
            return uid
    raise IsolationError("no free uid for the sandbox")


def _world_writable_dirs() -> list[Path]:
    """Where any user may create files: the places a uid-only sandbox must sweep after a test."""
    found = []
    for top in (Path("/tmp"), Path("/var/tmp"), Path("/dev/shm"), Path("/dev/mqueue"), Path("/run/lock"),
                Path("/var/lock")):
        try:
            if top.is_dir() and not top.is_symlink() and top.stat().st_mode & 0o002:
                found.append(top)
                found += [c for c in top.iterdir() if c.is_dir() and not c.is_symlink() and c.stat().st_mode & 0o002]
        except OSError:
            continue
    return found


def _mount_tmpfs(folder: Path, size: int) -> bool:
    """Mount a tmpfs of ``size`` bytes on ``folder`` (as root, where this machine lets us: not in most containers,
    or not with ``CS451_NO_MOUNT``, which the kit's tests use to run the watch that stands in for it)."""
    if not is_root() or os.environ.get("CS451_NO_MOUNT") or sys.platform != "linux":
        return False
    libc = ctypes.CDLL(None, use_errno=True)
    return libc.mount(b"tmpfs", str(folder).encode(), b"tmpfs", MS_NOSUID | MS_NODEV,
                      f"size={size},mode=0700".encode()) == 0


def _free_bytes(folder: Path) -> int:
    st = os.statvfs(folder)
    return st.f_bavail * st.f_frsize


def remove_tree(path: Path) -> None:
    """Remove a folder the sandbox wrote, however deep or strange (never following links)."""
    if not os.path.lexists(path):
        return
    if shutil.which("rm"):
        subprocess.run(["rm", "-rf", "--", str(path)], stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL, check=False)
    if os.path.lexists(path):
        shutil.rmtree(path, ignore_errors=True)


def _remove_ipc(uid: int) -> None:
    """System V shared memory, queues and semaphores the uid made (they outlive processes)."""
    for kind, flag in (("shm", "-m"), ("msg", "-q"), ("sem", "-s")):
        try:
            lines = Path(f"/proc/sysvipc/{kind}").read_text().splitlines()[1:]
        except OSError:
            continue
        header = Path(f"/proc/sysvipc/{kind}").read_text().splitlines()[0].split()
        for line in lines:
            cols = dict(zip(header, line.split()))
            if cols.get("uid") == str(uid) or cols.get("cuid") == str(uid):
                subprocess.run(["ipcrm", flag, cols.get("shmid") or cols.get("msqid") or cols.get("semid", "")],
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)


_NAMESPACES: bool | None = None


def namespaces_work() -> bool:
    """Whether bubblewrap can make its namespaces here, as the user tests would run as (cached)."""
    global _NAMESPACES
    if _NAMESPACES is None:
        if os.environ.get("CS451_SANDBOX") in ("uid", "none") or not shutil.which("bwrap"):
            _NAMESPACES = False
        else:
            uid = _free_uid() if is_root() else None
            try:
                done = subprocess.run(["bwrap", "--unshare-all", "--ro-bind", "/", "/", "--proc", "/proc", "--dev", "/dev",
                                       "true"], stdin=subprocess.DEVNULL, capture_output=True, timeout=30,
                                      preexec_fn=(lambda: _drop_to(uid)) if uid is not None else None)
                _NAMESPACES = done.returncode == 0
            except (OSError, subprocess.TimeoutExpired):
                _NAMESPACES = False
    return _NAMESPACES


# --- trusted runs ----------------------------------------------------------------------

def _read_log(log_path: Path) -> str:
    size = log_path.stat().st_size
    with open(log_path, "rb") as log:
        text = log.read(OUTPUT_LIMIT).decode("utf-8", "replace")
    if size > OUTPUT_LIMIT:
        text += f"\n… ({size - OUTPUT_LIMIT} more bytes of output cut)"
    return text


def run_trusted(args: list[str], job: Path, limits: Limits, engine: Path) -> Completed:
    """The reference (literally ``reference``) in a plain subprocess with the limits, as the grader's user."""
    log_path = job.parent / f"{job.name}.log"
    with open(os.open(log_path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600), "wb") as log:
        proc = subprocess.Popen(args, cwd=job, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT,
                                env=worker_env(str(job), str(engine)), start_new_session=True,
                                preexec_fn=(lambda: _set_limits(limits)) if resource else None)
        timed_out = _wait(proc, limits.wall_seconds)
    text = _read_log(log_path)
    log_path.unlink()
    return Completed(proc.returncode, text, timed_out)


def _wait(proc: subprocess.Popen, seconds: float) -> bool:
    timed_out = False
    try:
        proc.wait(timeout=seconds)
    except subprocess.TimeoutExpired:
        timed_out = True
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError, AttributeError):
            pass
        proc.wait()
    return timed_out


# --- the sandbox --------------------------------------------------------------------------

@dataclass
class Sandbox:
    """One grading run's isolation: a private run folder, the mode in force, and a runner per test.

    Use as a context manager; ``run(request, timeout)`` runs one worker on one job.
    """
    stage: str
    upload: Path
    engine_sources: list[tuple[Path, str]]   # (source folder, path below the engine root) to copy in
    protected: list[Path]                    # must be unreadable from inside (checked by the canary)
    unwritable: list[Path] = field(default_factory=list)   # folders it must not create files in (results)
    student_copy: bool = False               # no reference or hidden tests here: "none" is allowed
    mode: str = "auto"                       # auto, bubblewrap, uid, none
    submission_memory: int = SUBMISSION_MEMORY
    staged: StagedUpload | None = None
    run_dir: Path | None = None
    uid_for_tests: bool = False
    cgroups_used: bool = False
    share: cgroups.ShareGroup | None = None   # this submission's CPU share, the same weight as any other's
    job_tmpfs: bool = False                   # the job folders are tmpfs mounts of their own (JOB_DISK)
    _jobs: int = 0
    _lock: threading.Lock = field(default_factory=threading.Lock)
    _job_mounts: set[Path] = field(default_factory=set)   # job folders on a tmpfs of their own (JOB_DISK)

    # -- setup and teardown --
    def __enter__(self) -> "Sandbox":
        try:
            self._open()
        except BaseException:
            self.close()
            raise
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _open(self) -> None:
        self.run_dir = Path(tempfile.mkdtemp(prefix="cs451-run-")) / f"{random.getrandbits(64):016x}"
        self.run_dir.mkdir(mode=0o700)   # its parent (0711 below) lists nothing, so the name is the key
        self.staged = stage_upload(self.upload, self.run_dir / "upload")
        engine = self.run_dir / "engine"
        for source, below in self.engine_sources:
            shutil.copytree(source, engine / below, ignore=_sandbox_litter)
        self.engine = engine
        (self.run_dir / "jobs").mkdir()
        (self.run_dir / "logs").mkdir(mode=0o700)
        for path in [self.run_dir, self.run_dir / "upload", engine, self.run_dir / "jobs", *self._tree(engine),
                     *self._tree(self.run_dir / "upload")]:
            os.chmod(path, 0o755 if path.is_dir() else 0o644)
        os.chmod(self.run_dir, 0o711)   # the sandbox user may pass through to what it is given, and list nothing
        os.chmod(self.run_dir.parent, 0o711)
        os.chmod(self.run_dir / "jobs", 0o711)
        subprocess.run([sys.executable, "-m", "compileall", "-q", str(engine)], check=False,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # bytecode once, read-only after
        for path in self._tree(engine):
            os.chmod(path, 0o755 if path.is_dir() else 0o644)
        for pristine in (engine, self.run_dir / "upload"):   # copied afresh for each test (fresh_copies), never shown
            os.chmod(pristine, 0o700)
        (self.run_dir / "copies").mkdir(mode=0o711)
        self.share = cgroups.create_share()
        if self.share is not None:
            self.share.enter()   # the grading of this submission, checks included, shares its CPU with its tests
        self.mode = self._choose_mode()

    @staticmethod
    def _tree(root: Path) -> list[Path]:
        return [Path(d) / n for d, dirs, files in os.walk(root) for n in dirs + files]

    def close(self) -> None:
        for job in list(self._job_mounts):
            self._finish_job(job)
        if self.run_dir is not None:
            remove_tree(self.run_dir.parent)
            self.run_dir = None
        if self.share is not None:
            self.share.remove()
            self.share = None

    # -- choosing the isolation --
    def _choose_mode(self) -> str:
        wanted = os.environ.get("CS451_SANDBOX", self.mode)
        if wanted not in ("auto", "bubblewrap", "uid", "none"):
            raise IsolationError(f"CS451_SANDBOX={wanted!r}: expected auto, bubblewrap, uid or none")
        reasons = []
        candidates = ["bubblewrap", "uid", "none"] if wanted == "auto" else [wanted]
        for mode in candidates:
            problem = self._usable(mode)
            if problem is None:
                return mode
            reasons.append(f"{mode}: {problem}")
        tried = " (" + "; ".join(reasons) + ")"
        blocked = self._unreachable() if is_root() else None
        if blocked is not None:
            what, needed, private = blocked
            raise IsolationError(
                f"the submission cannot be isolated here, so it is not run: its tests run as a throwaway user, never "
                f"as root, and that user cannot reach {what} {needed}: {private} lets no other user pass through "
                f"(mode {stat.S_IMODE(os.stat(private).st_mode):04o}). Let others pass through it (chmod o+x "
                f"{private}: they may then open what is inside by name, not list it), move the repository to a "
                f"folder they may pass through and run its ./setup.sh again there, or grade as an ordinary user"
                + tried)
        fixes = [f for f, needed in (("install bubblewrap (apt-get install bubblewrap)", not shutil.which("bwrap")),
                                     ("grade as root", not is_root())) if needed]
        raise IsolationError("the submission cannot be isolated here, so it is not run" + tried +
                             (". " + " or ".join(fixes)[:1].upper() + " or ".join(fixes)[1:] + "." if fixes else "."))

    def _needed_outside(self) -> list[tuple[str, str]]:
        """What the sandbox's user must reach by path before any namespace exists: (what it is, path)."""
        needed = [("the Python interpreter", sys.executable)]
        needed += [("the Python environment", prefix) for prefix in
                   sorted({sys.prefix, sys.base_prefix, sys.exec_prefix, sys.base_exec_prefix})]
        needed += [("the library folder", lib) for lib in os.environ.get("LD_LIBRARY_PATH", "").split(":")
                   if lib and os.path.isdir(lib)]
        if self.run_dir is not None:
            needed.append(("the grading folder", str(self.run_dir)))
        return needed

    def _unreachable(self) -> tuple[str, str, Path] | None:
        """The first needed path behind a folder that users other than its owner may not pass through (mode bits
        only: the usual cause of a refusal as root, e.g. a repository in /root or under a private folder)."""
        for what, path in self._needed_outside():
            private = private_folder_above(Path(path))
            if private is not None:
                return what, path, private
        return None

    def _usable(self, mode: str) -> str | None:
        if mode == "none":
            if is_root():
                return "never as root"
            if not self.student_copy:
                return "this kit holds the reference or hidden tests, which a submission must not read"
            return None
        if mode == "bubblewrap" and not shutil.which("bwrap"):
            return "bwrap is not installed"
        if mode == "uid" and not is_root():
            return "needs root"
        self.mode = mode
        self.uid_for_tests = is_root()
        return self._canary()

    def _canary(self) -> str | None:
        """Run :mod:`.canary` exactly as a test would: it must see no protected path and no copy of the kit's
        reference or answers anywhere it can read, and change nothing it is given."""
        from ..stages import stage_names
        job = self._new_job()
        given = [f"{self.visible_engine}/{below}" for _, below in self.engine_sources if below != "cs451"]
        spec = {"protected": [str(p) for p in self.protected if os.path.lexists(p)],
                "unwritable": [self.visible_upload] + [str(p) for p in self.unwritable if os.path.isdir(p)],
                "exempt": [self.visible_upload, self.visible_job(job), str(Path(self.upload).absolute()), *given],
                "stages": stage_names(),
                "student_copy": self.student_copy, "seconds": CANARY_SEARCH_SECONDS}
        try:
            done = self.run(["-m", "cs451.grading.canary", json.dumps(spec)], job, Limits(wall_seconds=CANARY_SECONDS))
        except OSError as err:
            return f"could not start ({err})"
        finally:
            self._finish_job(job)
        try:
            answer = json.loads(done.output.strip().splitlines()[-1])
        except (ValueError, IndexError):
            return f"the canary did not run ({done.output.strip()[-300:] or f'exit {done.returncode}'})"
        if answer["seen"]:
            return (f"the sandbox user can read {', '.join(answer['seen'][:3])}; make those folders private "
                    f"(mode 0700) or install bubblewrap")
        if answer["wrote"]:
            for folder in answer["wrote"][1:]:
                (Path(folder) / "cs451-canary").unlink(missing_ok=True)
            return f"the sandbox user can write in {answer['wrote'][0]}"
        if answer["found"]:
            return (f"the sandbox user can read a copy of the kit's reference or answers: "
                    f"{'; '.join(answer['found'][:3])}{' and more' if len(answer['found']) > 3 else ''}; remove it or "
                    f"make it private (mode 0700){'' if self.mode == 'bubblewrap' else ', or install bubblewrap'}")
        if not answer["complete"]:
            return (f"the canary could not search everything the sandbox user can read in {CANARY_SEARCH_SECONDS:g} s "
                    f"({answer['entries']} entries); install bubblewrap, which shows it far less")
        if is_root() and answer["uid"] == 0:
            return "the worker would run as root"
        return None

    # -- paths as the worker sees them --
    @property
    def visible_engine(self) -> str:
        return "/kit" if self.mode == "bubblewrap" else str(self._copies(None)[0])

    @property
    def visible_upload(self) -> str:
        return "/submission" if self.mode == "bubblewrap" else str(self._copies(None)[1])

    def visible_job(self, job: Path) -> str:
        return "/job" if self.mode == "bubblewrap" else str(job)

    def visible(self, staged_path: Path) -> str:
        """Where a path inside the staged upload appears to the worker."""
        rel = staged_path.relative_to(self.run_dir / "upload")
        return str(Path(self.visible_upload) / rel)

    @property
    def parallel(self) -> bool:
        """Tests may overlap only where each has its own namespaces (the uid mode shares /tmp and the rest)."""
        return self.mode in ("bubblewrap", "none")

    def describe(self) -> str:
        text = DESCRIPTIONS[self.mode]
        if self.uid_for_tests and self.mode == "bubblewrap":
            text += ", as a throwaway user per test"
        if self.mode != "none":
            text += "; memory and processes capped " + ("by a cgroup" if self.cgroups_used else "by a watchdog")
            text += ", disk " + ("by a tmpfs of fixed size per folder" if self.job_tmpfs and self.mode == "bubblewrap"
                                 else "by a watch on what it writes")
            if self.share is not None:
                text += "; a CPU share equal to any other submission's"
        return text

    # -- one test --
    def _new_job(self) -> Path:
        with self._lock:
            self._jobs += 1
            job = self.run_dir / "jobs" / str(self._jobs)
        job.mkdir(mode=0o700)
        if _mount_tmpfs(job, JOB_DISK):   # a disk quota; where no mount can be made, run() watches the folder
            self._job_mounts.add(job)
        return job

    def new_job(self) -> Path:
        """A fresh job folder for one test's request and inputs (given to the sandbox user when it runs)."""
        return self._new_job()

    def _finish_job(self, job: Path) -> None:
        if job in self._job_mounts:
            self._job_mounts.discard(job)
            ctypes.CDLL(None, use_errno=True).umount2(str(job).encode(), MNT_DETACH)
        remove_tree(job)

    @staticmethod
    def _kill_test(proc: subprocess.Popen, group: cgroups.TestGroup | None, uid: int | None) -> Callable[[], None]:
        """Ends a test at once: its cgroup, or its uid's processes, or its process group."""
        def kill() -> None:
            if group is not None:
                group.kill_all()
            elif uid is not None:
                for pid in _processes_of(uid):
                    try:
                        os.kill(pid, signal.SIGKILL)
                    except (ProcessLookupError, PermissionError):
                        pass
            else:
                try:
                    os.killpg(proc.pid, signal.SIGKILL)
                except (ProcessLookupError, PermissionError):
                    pass
        return kill

    def finish_job(self, job: Path) -> None:
        self._finish_job(job)

    def _copies(self, job: Path | None) -> tuple[Path, Path]:
        """Where a test's own copies of the engine and the upload lie (job None: as the uid mode's worker sees them).

        Under bubblewrap each test has its own folder (tests may overlap); in the uid mode, which runs one test at
        a time, every test's copies take the same place, so the request's paths hold for all; with no isolation
        (a student copy) the worker reads the staged originals."""
        if self.mode == "bubblewrap" and job is not None:
            folder = self.run_dir / "copies" / job.name
        elif self.mode == "uid":
            folder = self.run_dir / "copies" / "live"
        else:
            return self.engine, self.run_dir / "upload"
        return folder / "engine", folder / "upload"

    def fresh_copies(self, job: Path) -> tuple[Path, Path]:
        """This test's own copies of the engine and the upload, made now from the private originals.

        Every file a test can read that the kit made for this grading is a new file, so nothing one test leaves in
        it (its pages dropped from or read into the page cache, say: a channel ``fsync``, ``posix_fadvise`` and
        ``preadv2(RWF_NOWAIT)`` open on any readable file) reaches the next."""
        engine, upload = self._copies(job)
        if engine == self.engine:
            return engine, upload
        remove_tree(engine.parent)
        engine.parent.mkdir(mode=0o711)
        for source, copy in ((self.engine, engine), (self.run_dir / "upload", upload)):
            shutil.copytree(source, copy)
            os.chmod(copy, 0o755)
        return engine, upload

    def worker_args(self, job: Path) -> list[str]:
        return ["-m", "cs451.grading.worker", self.visible_job(job)]

    def run(self, python_args: list[str], job: Path, limits: Limits) -> Completed:
        """Run ``python python_args`` on ``job`` in the sandbox; everything it started is gone afterwards."""
        uid = _free_uid() if self.uid_for_tests else None
        if uid is not None:
            os.chown(job, uid, uid)
            for path in job.iterdir():
                os.chown(path, uid, uid)
        group = cgroups.create(min(limits.submission_memory, self.submission_memory), PROCESS_ALLOWANCE, self.share)
        self.job_tmpfs = job in self._job_mounts
        self.cgroups_used = group is not None
        nproc = PROCESS_ALLOWANCE if uid is not None else _count_processes(os.getuid()) + PROCESS_ALLOWANCE
        engine, upload = self.fresh_copies(job)
        command = self._command(python_args, job, engine, upload)
        env = worker_env(self.visible_job(job), self.visible_engine)
        if self.mode == "bubblewrap":
            env = {"PATH": "/usr/bin:/bin"}  # bwrap itself; the worker's environment is set inside
        log_path = self.run_dir / "logs" / f"{job.name}.log"

        def preexec() -> None:  # in the child, before exec
            _set_limits(limits)
            if group is not None:
                cgroups.join(group.procs_files)
            if self.mode == "uid":
                try:  # no network: a new, empty network namespace (needs CAP_SYS_ADMIN; skipped where refused)
                    ctypes.CDLL(None, use_errno=True).unshare(CLONE_NEWNET)
                except Exception:
                    pass
            if uid is not None:
                _drop_to(uid)
            if resource is not None:
                resource.setrlimit(resource.RLIMIT_NPROC, (nproc, nproc))

        watchdog = disk = None
        try:
            with open(os.open(log_path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600), "wb") as log:
                proc = subprocess.Popen(command, cwd=job, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT,
                                        env=env, start_new_session=True, preexec_fn=preexec if resource else None)
                if group is None:
                    watchdog = _Watchdog(proc.pid, uid, self.submission_memory)
                if self.mode != "none" and (job not in self._job_mounts or self.mode == "uid"):
                    disk = _DiskWatch(job, uid if self.mode == "uid" else None, JOB_DISK + TMP_DISK, self._kill_test(proc, group, uid))
                timed_out = _wait(proc, limits.wall_seconds)
            out_of_memory = (group.out_of_memory() if group else False) or bool(watchdog and watchdog.tripped)
            peak = group.peak_memory() if group else (watchdog.peak if watchdog else 0)
            full = bool(disk and disk.tripped) or (self.job_tmpfs and _free_bytes(job) < FULL_BELOW)
        finally:
            if watchdog:
                watchdog.stop()
            if disk:
                disk.stop()
            if group is not None:
                group.remove()
            if uid is not None:
                kill_uid(uid)
            if self.mode == "bubblewrap":
                remove_tree(engine.parent)
        text = _read_log(log_path)
        log_path.unlink()
        if uid is not None and self.mode == "uid":
            self._sweep(uid)
        code = proc.returncode
        if self.mode == "bubblewrap" and code is not None and 128 < code <= 128 + 64:
            code = 128 - code   # bwrap exits with 128 + the signal that ended the worker: give it back as a signal
        return Completed(code, text, timed_out, out_of_memory, peak, full)

    def _command(self, python_args: list[str], job: Path, engine: Path, upload: Path) -> list[str]:
        python = [sys.executable, "-B", "-s"]
        if self.mode != "bubblewrap":
            return python + python_args
        args = ["bwrap", "--die-with-parent", "--new-session", "--unshare-all", "--cap-drop", "ALL",
                "--size", str(TMP_DISK), "--tmpfs", "/tmp",   # first: binds below /tmp go on top
                "--proc", "/proc", "--dev", "/dev", "--size", str(SHM_DISK), "--tmpfs", "/dev/shm"]
        for top in ("bin", "sbin", "lib", "lib32", "lib64", "libx32"):
            path = Path("/") / top
            if path.is_symlink():
                args += ["--symlink", os.readlink(path), str(path)]
            elif path.is_dir():
                args += ["--ro-bind", str(path), str(path)]
        args += ["--ro-bind", "/usr", "/usr", "--ro-bind", "/etc", "/etc"]
        venv = os.path.dirname(os.path.dirname(sys.executable))   # as invoked: it may be a link to the prefix
        bound = ["/usr", "/etc"]
        for prefix in sorted({sys.prefix, sys.base_prefix, sys.exec_prefix, sys.base_exec_prefix, venv}):
            if not prefix.startswith("/usr/") and prefix != "/usr":
                args += ["--ro-bind", prefix, prefix]
                bound.append(prefix)
        for lib in os.environ.get("LD_LIBRARY_PATH", "").split(":"):
            if lib and os.path.isdir(lib) and not lib.startswith("/usr/"):
                args += ["--ro-bind", lib, lib]
                bound.append(lib)
        for path in self.protected:   # a kit installed in the venv (a wheel) lies inside a bound prefix: cover it
            if any(Path(path).is_relative_to(b) for b in bound) and os.path.isdir(path) and not os.path.islink(path):
                args += ["--perms", "0000", "--tmpfs", str(path), "--remount-ro", str(path)]   # empty, no one may open
        args += ["--ro-bind", str(engine), "/kit", "--ro-bind", str(upload), "/submission",
                 "--bind", str(job), "/job", "--remount-ro", "/dev", "--remount-ro", "/",   # nothing else writable
                 "--chdir", "/job", "--clearenv"]
        for key, value in worker_env("/job", "/kit").items():
            args += ["--setenv", key, value]
        return args + ["--"] + python + python_args

    def _sweep(self, uid: int) -> None:
        """After a test in the uid mode: what the uid left in shared places goes too."""
        for folder in _world_writable_dirs():
            try:
                entries = list(folder.iterdir())
            except OSError:
                continue
            for entry in entries:
                try:
                    if entry.lstat().st_uid == uid:
                        remove_tree(entry) if entry.is_dir() and not entry.is_symlink() else entry.unlink()
                except OSError:
                    continue
        _remove_ipc(uid)


def _bytes_below(path: Path, limit_entries: int = 200_000) -> tuple[int, int]:
    """Bytes held on disk by ``path`` and everything below it (no link followed), and the entries counted."""
    total, entries, todo = 0, 0, [str(path)]
    while todo and entries < limit_entries:
        here = todo.pop()
        try:
            st = os.lstat(here)
        except OSError:
            continue
        entries += 1
        total += st.st_blocks * 512
        if stat.S_ISDIR(st.st_mode):
            try:
                todo += [e.path for e in os.scandir(here)]
            except OSError:
                continue
    return total, entries


class _DiskWatch:
    """A disk quota where the job folder has no tmpfs of its own (no mount allowed) or the test may write in shared
    places (the uid mode): sum what the test keeps in its job folder and, for ``uid``, in ``/tmp``, ``/var/tmp``,
    ``/dev/shm``…, and end the test past ``cap`` bytes."""

    def __init__(self, job: Path, uid: int | None, cap: int, kill: Callable[[], None], every: float = 0.1):
        self.job, self.uid, self.cap, self.kill, self.every = job, uid, cap, kill, every
        self.tripped = False
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._watch, daemon=True)
        self._thread.start()

    def used(self) -> int:
        total = _bytes_below(self.job)[0]
        for folder in _world_writable_dirs() if self.uid is not None else []:
            try:
                entries = list(os.scandir(folder))
            except OSError:
                continue
            for entry in entries:
                try:
                    if entry.stat(follow_symlinks=False).st_uid == self.uid:
                        total += _bytes_below(Path(entry.path))[0]
                except OSError:
                    continue
        return total

    def _watch(self) -> None:
        while not self._stop.wait(self.every):
            if self.used() > self.cap:
                self.tripped = True
                self.kill()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join()


class _Watchdog:
    """Where no cgroup can be made: sum the memory of the test's processes and kill them all past the cap."""

    def __init__(self, pid: int, uid: int | None, cap: int, every: float = 0.05):
        self.pid, self.uid, self.cap, self.every = pid, uid, cap, every
        self.peak, self.tripped = 0, False
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._watch, daemon=True)
        self._thread.start()

    def _members(self) -> list[int]:
        return _processes_of(self.uid) if self.uid is not None else _descendants(self.pid)

    def _watch(self) -> None:
        while not self._stop.wait(self.every):
            members = self._members()
            total = sum(_rss(p) for p in members)
            self.peak = max(self.peak, total)
            if total > self.cap:
                self.tripped = True
                for p in members:
                    try:
                        os.kill(p, signal.SIGKILL)
                    except (ProcessLookupError, PermissionError):
                        pass

    def stop(self) -> None:
        self._stop.set()
        self._thread.join()
