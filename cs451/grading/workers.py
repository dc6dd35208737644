"""One worker process: its limits, its environment, and how the kit's own reference runs (trusted, no sandbox).
"""
from __future__ import annotations

import os
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

try:  # not on Windows: there the student copy runs without limits (nothing to protect)
    import resource
except ImportError:  # pragma: no cover
    resource = None  # type: ignore[assignment]

MEMORY_LIMIT = 3 << 30         # bytes of address space per process (llvmpipe reserves generously)
SUBMISSION_MEMORY = 1 << 30    # bytes of memory for everything one test starts, together
FILE_LIMIT = 256 << 20         # largest file a worker may write



from .processes import (drop_to, free_uid, wait_for)
from .scratch import (is_root, read_log)


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


def set_limits(limits: Limits) -> None:
    """In the worker's child before exec: cap CPU time (about twice the wall limit), address space and file size, allow
    no core file, and make it the OOM killer's first choice (nothing where ``resource`` is missing)."""
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


#: Whether unprivileged namespaces work here (bubblewrap needs them), found once.
_NAMESPACES: bool | None = None


def namespaces_work() -> bool:
    """Whether bubblewrap can make its namespaces here, as the user tests would run as (cached)."""
    global _NAMESPACES
    if _NAMESPACES is None:
        if os.environ.get("CS451_SANDBOX") in ("uid", "none") or not shutil.which("bwrap"):
            _NAMESPACES = False
        else:
            uid = free_uid() if is_root() else None
            try:
                done = subprocess.run(["bwrap", "--unshare-all", "--ro-bind", "/", "/", "--proc", "/proc", "--dev", "/dev",
                                       "true"], stdin=subprocess.DEVNULL, capture_output=True, timeout=30,
                                      preexec_fn=(lambda: drop_to(uid)) if uid is not None else None)
                _NAMESPACES = done.returncode == 0
            except (OSError, subprocess.TimeoutExpired):
                _NAMESPACES = False
    return _NAMESPACES


def run_trusted(args: list[str], job: Path, limits: Limits, engine: Path) -> Completed:
    """The reference (literally ``reference``) in a plain subprocess with the limits, as the grader's user."""
    log_path = job.parent / f"{job.name}.log"
    with open(os.open(log_path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600), "wb") as log:
        proc = subprocess.Popen(args, cwd=job, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT,
                                env=worker_env(str(job), str(engine)), start_new_session=True,
                                preexec_fn=(lambda: set_limits(limits)) if resource else None)
        timed_out = wait_for(proc, limits.wall_seconds)
    text = read_log(log_path)
    log_path.unlink()
    return Completed(proc.returncode, text, timed_out)

