"""Running untrusted student code: a subprocess with limits, as an unprivileged user when we are root.

What it enforces, and where:
- always: its own process group (killed whole on time-out), a wall-clock limit, CPU time,
  address space, file size, no core dumps, a cap on processes (fork bombs), stdin closed,
  a scrubbed environment;
- when the grader runs as root (Gradescope, a Docker grader): the worker drops to the
  ``nobody`` user, so files the grader keeps at mode 0700 (the reference, hidden tests,
  cached reference answers, the results folder) cannot be read or written; and it gets a
  fresh network namespace with no interfaces where the kernel allows it.
Run locally as a normal user (a student's self-check), only the first list applies.
"""
from __future__ import annotations

import ctypes
import os
import pwd
import resource
import signal
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

MEMORY_LIMIT = 3 << 30       # bytes of address space (llvmpipe reserves generously; a numpy bomb stops here)
FILE_LIMIT = 256 << 20       # largest file a worker may write
PROCESS_ALLOWANCE = 64       # processes and threads beyond what the user already runs (llvmpipe uses one per core)
OUTPUT_LIMIT = 4000          # characters of printed output kept
CLONE_NEWNET = 0x40000000
UNPRIVILEGED_USER = "nobody"


def is_root() -> bool:
    return os.geteuid() == 0


def unprivileged_ids() -> tuple[int, int] | None:
    """The uid and gid the worker runs as when we are root (None when we are not root)."""
    if not is_root():
        return None
    try:
        entry = pwd.getpwnam(UNPRIVILEGED_USER)
        return entry.pw_uid, entry.pw_gid
    except KeyError:
        return 65534, 65534


def _reachable_by_others(path: Path) -> bool:
    """Whether a user who is neither owner nor in the group can read ``path`` (and traverse its parents)."""
    path = path.resolve()
    for folder in [*reversed(path.parents), path]:
        try:
            mode = folder.stat().st_mode
        except OSError:
            return False
        if folder.is_dir() and not mode & 0o001:
            return False
    return bool(path.stat().st_mode & 0o004)


def isolation_problem(impl_dir: Path) -> str | None:
    """Why the worker cannot run as the unprivileged user here (None when it can, or when we are not root)."""
    if not is_root():
        return None
    import cs451
    needed = [Path(sys.executable), Path(sys.base_prefix) / "lib", Path(cs451.__file__).parent, impl_dir]
    for path in needed:
        if not _reachable_by_others(path):
            return f"{UNPRIVILEGED_USER} cannot read {path}"
    return None


def _count_processes(uid: int) -> int:
    count = 0
    for status in Path("/proc").glob("[0-9]*/status"):
        try:
            for line in status.read_text().splitlines():
                if line.startswith("Uid:"):
                    count += int(line.split()[1]) == uid
                    break
        except OSError:
            continue
    return count


@dataclass(frozen=True)
class Limits:
    wall_seconds: float
    memory_bytes: int = MEMORY_LIMIT
    file_bytes: int = FILE_LIMIT


def _preexec(limits: Limits, ids: tuple[int, int] | None, nproc: int) -> None:  # runs in the child, before exec
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
    if ids is not None:
        try:  # no network: a new, empty network namespace (needs CAP_SYS_ADMIN; skipped where refused)
            ctypes.CDLL(None, use_errno=True).unshare(CLONE_NEWNET)
        except Exception:
            pass
        os.setgroups([])
        os.setgid(ids[1])
        os.setuid(ids[0])
    resource.setrlimit(resource.RLIMIT_NPROC, (nproc, nproc))


def worker_env(home: Path) -> dict[str, str]:
    """Only what GL and Python need; nothing of the grader's (tokens, paths to the reference)."""
    keep = ("PATH", "LANG", "LC_ALL", "DISPLAY", "LD_LIBRARY_PATH", "EGL_PLATFORM", "LIBGL_ALWAYS_SOFTWARE",
            "GALLIUM_DRIVER", "LP_NUM_THREADS", "__EGL_VENDOR_LIBRARY_FILENAMES", "MESA_SHADER_CACHE_DISABLE")
    env = {k: os.environ[k] for k in keep if k in os.environ}
    env.setdefault("EGL_PLATFORM", "surfaceless")
    from .. import KIT_ROOT
    env.update(HOME=str(home), TMPDIR=str(home), PYTHONDONTWRITEBYTECODE="1", PYTHONHASHSEED="0",
               PYTHONPATH=str(KIT_ROOT),  # the worker runs the same engine as the grader, wherever it is installed
               OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MESA_SHADER_CACHE_DISABLE="true",
               NUMBA_CACHE_DIR=str(home))
    return env


@dataclass
class Completed:
    returncode: int | None
    output: str
    timed_out: bool


def run_untrusted(args: list[str], job: Path, limits: Limits, trusted: bool = False,
                  drop_privileges: bool = True) -> Completed:
    """Run ``args`` in ``job`` with the limits; ``trusted`` (the reference) keeps the grader's user."""
    ids = None if trusted or not drop_privileges else unprivileged_ids()
    if ids is not None:
        os.chmod(job.parent, 0o711)  # the worker may pass through to its job folder, and see nothing else
        os.chown(job, ids[0], ids[1])
        for path in job.iterdir():
            os.chown(path, ids[0], ids[1])
    nproc = _count_processes(ids[0] if ids else os.getuid()) + PROCESS_ALLOWANCE
    log_path = job.parent / f"{job.name}.log"  # outside the job folder: the worker cannot replace it
    with open(os.open(log_path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600), "wb") as log:
        # a file, not a pipe: an output flood fills a capped file, not our memory
        proc = subprocess.Popen(args, cwd=job, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT,
                                env=worker_env(job), start_new_session=True,
                                preexec_fn=lambda: _preexec(limits, ids, nproc))
        timed_out = False
        try:
            proc.wait(timeout=limits.wall_seconds)
        except subprocess.TimeoutExpired:
            timed_out = True
        finally:
            try:
                os.killpg(proc.pid, signal.SIGKILL)  # the worker and anything it left behind
            except (ProcessLookupError, PermissionError):
                pass
            proc.wait()
    size = log_path.stat().st_size
    with open(log_path, "rb") as log:
        text = log.read(OUTPUT_LIMIT).decode("utf-8", "replace")
    log_path.unlink()
    if size > OUTPUT_LIMIT:
        text += f"\n… ({size - OUTPUT_LIMIT} more bytes of output cut)"
    return Completed(proc.returncode, text, timed_out)


def protect(*paths: Path) -> list[Path]:
    """Make grader-only files unreadable to the worker's user (root only; a no-op otherwise)."""
    if not is_root():
        return []
    done = []
    for path in paths:
        if path.exists():
            os.chmod(path, 0o700 if path.is_dir() else 0o600)
            done.append(path)
    return done
