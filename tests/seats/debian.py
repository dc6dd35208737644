"""A fresh minimal Debian 12, as a new user's machine: ``debootstrap --variant=minbase`` with python3 and nothing
else, this machine's apt and pip configuration and certificates copied in (so it reaches the same registries),
and the local package folders that configuration names bound read-only.

The pristine root is built once and cached under /var/tmp (its name carries a digest of the recipe and of the
configuration copied in); every seat runs in a throwaway overlay on it. A command runs inside through a private
mount and pid namespace and ``pivot_root``, as a container does: a plain chroot is not enough, because
bubblewrap (the grader's sandbox) refuses to run in one ("Failed to make / slave"). Needs root, debootstrap,
util-linux's unshare and the kernel's overlayfs.
"""
from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

CACHE = Path(os.environ.get("CS451_SEAT_CACHE", "/var/tmp/cs451-seats"))
SUITE, MIRROR = "bookworm", "http://deb.debian.org/debian"
#: This machine's configuration a new machine of the same workplace would have, copied in as it is.
CONFIG_FILES = ("/etc/apt/sources.list.d/debian.sources", "/etc/apt/apt.conf.d/99artifact-registry",
                "/etc/apt/apt.conf.d/99farm-no-dep11", "/etc/pip.conf", "/etc/xdg/pip/pip.conf",
                "/etc/xdg/pip/constraints.txt", "/root/.config/pip/pip.conf", "/etc/ssl/certs/ca-certificates.crt")
#: Local package folders the pip configuration points at, bound read-only inside.
PACKAGE_DIRS = ("/opt/wheels", "/opt/pypi", "/opt/pypi-more")
#: What a new machine downloads again on every run, kept between runs (host folder under CACHE, where inside): apt's
#: archive of .deb files and pip's of wheels. Only downloads are kept: every package is still installed by the
#: README's set-up, in a fresh root, as on a new machine; a warm cache changes how long that takes, not what it does.
DOWNLOAD_CACHES = (("apt-archives", "/var/cache/apt/archives"), ("pip", "/root/.cache/pip"))
ENTER = Path(__file__).with_name("enter-root.sh")


def missing_tools() -> str | None:
    """Why a Debian root cannot be made or entered here, or None."""
    if os.geteuid() != 0:
        return "needs root (namespaces, debootstrap)"
    for tool in ("debootstrap", "unshare", "pivot_root", "mount"):
        if not shutil.which(tool):
            return f"needs {tool}"
    if "overlay" not in Path("/proc/filesystems").read_text():
        return "needs the kernel's overlayfs"
    return None


def _config() -> list[Path]:
    return [Path(p) for p in CONFIG_FILES if Path(p).is_file()]


def _recipe_digest() -> str:
    h = hashlib.sha256(f"{SUITE} {MIRROR} minbase python3".encode())
    for path in _config():
        h.update(str(path).encode() + b"\0" + path.read_bytes())
    return h.hexdigest()[:12]


def pristine_root() -> Path:
    """The cached minimal root (built on first use, about a minute); never written to afterwards."""
    root = CACHE / f"{SUITE}-minbase-{_recipe_digest()}"
    if (root / "etc" / "debian_version").is_file():
        return root
    CACHE.mkdir(parents=True, exist_ok=True)
    building = Path(tempfile.mkdtemp(prefix="building-", dir=CACHE))
    done = subprocess.run(["debootstrap", "--variant=minbase", "--include=python3", SUITE, str(building), MIRROR],
                          capture_output=True, text=True, timeout=1800)
    if done.returncode != 0:
        shutil.rmtree(building, ignore_errors=True)
        raise RuntimeError(f"debootstrap failed: {done.stdout[-1500:]}{done.stderr[-1500:]}")
    (building / "etc" / "apt" / "sources.list").unlink(missing_ok=True)   # this machine's sources replace it
    for path in _config():
        target = building / path.relative_to("/")
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(path, target)
    bundle = Path("/etc/ssl/certs/ca-certificates.crt")
    if bundle.is_file():   # kept when the root's own ca-certificates package rebuilds the bundle
        local = building / "usr" / "local" / "share" / "ca-certificates"
        local.mkdir(parents=True, exist_ok=True)
        shutil.copy2(bundle, local / "this-machine.crt")
    shutil.rmtree(root, ignore_errors=True)
    building.rename(root)
    return root


@contextmanager
def fresh_machine() -> Iterator["Machine"]:
    """A throwaway copy of the pristine root (an overlay; its changes are dropped afterwards)."""
    lower = pristine_root()
    top = Path(tempfile.mkdtemp(prefix="seat-", dir=CACHE))
    try:
        for part in ("upper", "work", "merged"):
            (top / part).mkdir()
        yield Machine(lower, top)
    finally:
        subprocess.run(["umount", "-l", str(top / "merged")], capture_output=True)
        shutil.rmtree(top, ignore_errors=True)


class Machine:
    """A fresh Debian: files go in through :meth:`put` (written to the overlay's upper layer), commands run as root
    inside with a clean environment (:meth:`run`)."""

    def __init__(self, lower: Path, top: Path):
        self.lower, self.top = lower, top

    def path(self, inside: str) -> Path:
        """Where a path inside the machine is written from outside (its upper layer)."""
        return self.top / "upper" / inside.lstrip("/")

    def put_tree(self, files: list[Path], source: Path, inside: str) -> None:
        """Copy these files of ``source`` (relative paths) to ``inside``, as regular files (no link followed)."""
        dest = self.path(inside)
        for rel in files:
            src = source / rel
            if src.is_symlink() or not src.is_file():
                continue
            (dest / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dest / rel, follow_symlinks=False)

    def run(self, script: str, timeout: float = 3600) -> subprocess.CompletedProcess:
        """``bash -c script`` inside, as root, with only HOME, PATH, LANG and TERM set; output captured."""
        binds = " ".join(d for d in PACKAGE_DIRS if Path(d).is_dir())
        caches = []
        for name, inside in DOWNLOAD_CACHES:
            host = CACHE / "downloads" / f"{SUITE}-{_recipe_digest()}" / name
            (host / "partial" if name == "apt-archives" else host).mkdir(parents=True, exist_ok=True)
            caches.append(f"{host}={inside}")
        return subprocess.run(["unshare", "--mount", "--pid", "--fork", "--propagation", "private",
                               "sh", str(ENTER), str(self.lower), str(self.top), binds, " ".join(caches), script],
                              capture_output=True, text=True, timeout=timeout)
