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
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
from dataclasses import dataclass, field
from typing import Callable
from pathlib import Path

try:  # not on Windows: there the student copy runs without limits (nothing to protect)
    import resource
except ImportError:  # pragma: no cover
    resource = None  # type: ignore[assignment]

from .. import instructor_only
from . import cgroups
from . import preflight
from .processes import count_processes, drop_to, free_uid, kill_uid, processes_of, remove_ipc, wait_for
from .scratch import free_bytes, mount_tmpfs, read_log, remove_tree, world_writable_dirs
from .staging import StagedUpload, stage_upload
from .watches import DiskWatch, Watchdog
from .workers import SUBMISSION_MEMORY, Completed, Limits, set_limits, worker_env
# The sandbox's names as its callers know them (the grader, the roster, the tests), kept where they now live:
from .processes import UID_RANGE, IsolationError  # noqa: F401
from .scratch import is_root  # noqa: F401
from .workers import FILE_LIMIT, MEMORY_LIMIT, namespaces_work, run_trusted  # noqa: F401

JOB_DISK = 512 << 20           # bytes a test may keep in its job folder (its scratch, and its answer)
TMP_DISK = 256 << 20           # bytes in its /tmp under bubblewrap
SHM_DISK = 64 << 20            # bytes in its /dev/shm under bubblewrap
FULL_BELOW = 1 << 20           # a job folder with less free is full: its answer may not have fitted
MNT_DETACH = 2
PROCESS_ALLOWANCE = 64         # processes and threads a test may run (llvmpipe uses one per core)
CLONE_NEWNET = 0x40000000

#: How each mode is described in results and reports.
DESCRIPTIONS = {
    "bubblewrap": "bubblewrap (private mount, pid, network and IPC namespaces)",
    "uid": "a throwaway user per test, with the kit's files checked unreadable first",
    "none": "no isolation (a student copy of the kit: your own code runs as you)",
}


def _sandbox_litter(folder: str, names: list[str]) -> set[str]:
    """What a sandbox's copy of the engine leaves out: byte code, and the lecturers' folders (no test imports them)."""
    left = set(shutil.ignore_patterns("*.pyc", "__pycache__")(folder, names))
    return left | {name for name in names if instructor_only(Path(folder) / name)}


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
        (self.run_dir / "nothing").touch(mode=0o000)   # bound over a protected file in a bound folder: no one opens it
        self.share = cgroups.create_share()
        if self.share is not None:
            self.share.enter()   # the grading of this submission, checks included, shares its CPU with its tests
        self.mode = preflight.choose_mode(self)

    @staticmethod
    def _tree(root: Path) -> list[Path]:
        return [Path(d) / n for d, dirs, files in os.walk(root) for n in dirs + files]

    def close(self) -> None:
        """Unmount and remove every job folder and the run folder, and remove the CPU share; safe to call twice."""
        for job in list(self._job_mounts):
            self._finish_job(job)
        if self.run_dir is not None:
            remove_tree(self.run_dir.parent)
            self.run_dir = None
        if self.share is not None:
            self.share.remove()
            self.share = None

    # -- paths as the worker sees them --
    @property
    def visible_engine(self) -> str:
        """Where the worker finds the engine: ``/kit`` under bubblewrap, else the path of the copy it reads."""
        return "/kit" if self.mode == "bubblewrap" else str(self._copies(None)[0])

    @property
    def visible_upload(self) -> str:
        """Where the worker finds the staged upload: ``/submission`` under bubblewrap, else the copy it reads."""
        return "/submission" if self.mode == "bubblewrap" else str(self._copies(None)[1])

    def visible_job(self, job: Path) -> str:
        """Where the worker finds a job folder: ``/job`` under bubblewrap, else the folder itself."""
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
        """How this run isolates the submission, in one line for the results and the report (mode, caps, CPU share)."""
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
        if mount_tmpfs(job, JOB_DISK):   # a disk quota; where no mount can be made, run() watches the folder
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
                for pid in processes_of(uid):
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
        """Unmount and remove a test's job folder once its answer is read (the grader calls it after each probe)."""
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
        """The Python arguments that run the sandboxed worker on a job, naming its folder as the worker sees it."""
        return ["-m", "cs451.grading.worker", self.visible_job(job)]

    def run(self, python_args: list[str], job: Path, limits: Limits) -> Completed:
        """Run ``python python_args`` on ``job`` in the sandbox; everything it started is gone afterwards."""
        uid = free_uid() if self.uid_for_tests else None
        if uid is not None:
            os.chown(job, uid, uid)
            for path in job.iterdir():
                os.chown(path, uid, uid)
        group = cgroups.create(min(limits.submission_memory, self.submission_memory), PROCESS_ALLOWANCE, self.share)
        self.job_tmpfs = job in self._job_mounts
        self.cgroups_used = group is not None
        nproc = PROCESS_ALLOWANCE if uid is not None else count_processes(os.getuid()) + PROCESS_ALLOWANCE
        engine, upload = self.fresh_copies(job)
        command = self._command(python_args, job, engine, upload)
        env = worker_env(self.visible_job(job), self.visible_engine)
        if self.mode == "bubblewrap":
            env = {"PATH": "/usr/bin:/bin"}  # bwrap itself; the worker's environment is set inside
        log_path = self.run_dir / "logs" / f"{job.name}.log"

        def preexec() -> None:  # in the child, before exec
            set_limits(limits)
            if group is not None:
                cgroups.join(group.procs_files)
            if self.mode == "uid":
                try:  # no network: a new, empty network namespace (needs CAP_SYS_ADMIN; skipped where refused)
                    ctypes.CDLL(None, use_errno=True).unshare(CLONE_NEWNET)
                except Exception:
                    pass
            if uid is not None:
                drop_to(uid)
            if resource is not None:
                resource.setrlimit(resource.RLIMIT_NPROC, (nproc, nproc))

        watchdog = disk = None
        try:
            with open(os.open(log_path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600), "wb") as log:
                proc = subprocess.Popen(command, cwd=job, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT,
                                        env=env, start_new_session=True, preexec_fn=preexec if resource else None)
                if group is None:
                    watchdog = Watchdog(proc.pid, uid, self.submission_memory)
                if self.mode != "none" and (job not in self._job_mounts or self.mode == "uid"):
                    disk = DiskWatch(job, uid if self.mode == "uid" else None, JOB_DISK + TMP_DISK, self._kill_test(proc, group, uid))
                timed_out = wait_for(proc, limits.wall_seconds)
            out_of_memory = (group.out_of_memory() if group else False) or bool(watchdog and watchdog.tripped)
            peak = group.peak_memory() if group else (watchdog.peak if watchdog else 0)
            full = bool(disk and disk.tripped) or (self.job_tmpfs and free_bytes(job) < FULL_BELOW)
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
        text = read_log(log_path)
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
            if not any(Path(path).is_relative_to(b) for b in bound) or os.path.islink(path):
                continue
            if os.path.isdir(path):
                args += ["--perms", "0000", "--tmpfs", str(path), "--remount-ro", str(path)]   # empty, no one may open
            elif os.path.isfile(path):      # an instructors-only file of an engine installed there
                args += ["--ro-bind", str(self.run_dir / "nothing"), str(path)]
        args += ["--ro-bind", str(engine), "/kit", "--ro-bind", str(upload), "/submission",
                 "--bind", str(job), "/job", "--remount-ro", "/dev", "--remount-ro", "/",   # nothing else writable
                 "--chdir", "/job", "--clearenv"]
        for key, value in worker_env("/job", "/kit").items():
            args += ["--setenv", key, value]
        return args + ["--"] + python + python_args

    def _sweep(self, uid: int) -> None:
        """After a test in the uid mode: what the uid left in shared places goes too."""
        for folder in world_writable_dirs():
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
        remove_ipc(uid)


