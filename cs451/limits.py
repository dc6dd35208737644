"""What a job may cost, judged from its parameters before any work starts.

A scene file can ask for more than a machine has (a patch size of 1e-4 makes 10¹³ patches; 10,000 samples
per pixel need hundreds of gigabytes of rays). Each stage estimates the memory its render needs from the
scene (:attr:`cs451.stages.base.Stage.estimate`, bytes per patch, ray or mesh cell measured on the
reference), and a job over the budget is refused with the field that asked for it, never started.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from .errors import InputError, KitError

#: the largest image side: GL_MAX_RENDERBUFFER_SIZE on llvmpipe and on most GPUs
MAX_SIDE = 16384
#: the most pixels in one image (a 8000 × 8000 render), for --size and for scene files alike
MAX_PIXELS = 64_000_000


@dataclass(frozen=True)
class Cost:
    """What one part of a job needs: the scene field that sets it, bytes, what they are for, and seconds at the
    reference's speed on a 2-core laptop where the part's time can run away (shadow rays, paths)."""
    field: str          # JSON path in the scene file: "options.radiosity.patch_size"
    bytes: float
    what: str           # "9.2e12 patches and their form factors"
    seconds: float = 0.0


def _cgroup_limit() -> tuple[float, str]:
    """The tightest memory cap on this process's own cgroup and the cgroups above it (v2 ``memory.max``, v1
    ``memory.limit_in_bytes``), and the file that sets it; infinity where none is set. Gradescope runs a
    submission in a 768 MB one, and a container's own cap is not the root cgroup's."""
    try:
        lines = Path("/proc/self/cgroup").read_text().splitlines()
    except OSError:
        lines = []
    found = [(float("inf"), "")]
    for line in lines:
        _, controllers, rel = (line.split(":", 2) + ["", ""])[:3]
        if controllers == "":
            base, name = Path("/sys/fs/cgroup"), "memory.max"
        elif "memory" in controllers.split(","):
            base, name = Path("/sys/fs/cgroup/memory"), "memory.limit_in_bytes"
        else:
            continue
        parts = [p for p in rel.strip().split("/") if p and p != ".."]
        for depth in range(len(parts), -1, -1):     # its own, then each parent's (a namespace may hide some)
            path = base.joinpath(*parts[:depth], name)
            try:
                text = path.read_text().strip()
            except OSError:
                continue
            if text.isdigit() and int(text) < 1 << 60:
                found.append((float(text), str(path)))
    return min(found)


def _address_space_left() -> float:
    """What RLIMIT_AS (``ulimit -v``) leaves this process beyond what it has mapped already; infinity if unset."""
    try:
        import resource
        soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    except (ImportError, ValueError, OSError):   # Windows has no resource module
        return float("inf")
    if soft == resource.RLIM_INFINITY or soft < 0:
        return float("inf")
    mapped = 0.0
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmSize:"):
                mapped = float(line.split()[1]) * 1024
    except OSError:
        pass
    return max(float(soft) - mapped, 0.0)


def _available_memory() -> float:
    """MemAvailable: what the machine can give without swapping; infinity where /proc does not say."""
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return float(line.split()[1]) * 1024
    except OSError:
        pass
    return float("inf")


def _physical_memory() -> float:
    try:
        return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):   # Windows has no sysconf
        return 8.0 * 2**30


def parse_bytes(text: str) -> float:
    """'2G', '512M', '1.5e9' to bytes."""
    units = {"K": 2**10, "M": 2**20, "G": 2**30, "T": 2**40}
    text = text.strip().upper().removesuffix("B")
    try:
        return float(text[:-1]) * units[text[-1]] if text and text[-1] in units else float(text)
    except ValueError:
        raise KitError(f"CS451_MEMORY_BUDGET: expected a size such as 2G or 512M, got {text!r}") from None


def memory_limits() -> list[tuple[float, str]]:
    """Each budget this process must keep under, with what sets it: half its cgroup's cap, half of what
    RLIMIT_AS leaves, most of the memory free now, half the machine's; ``CS451_MEMORY_BUDGET`` replaces them."""
    if os.environ.get("CS451_MEMORY_BUDGET"):
        return [(parse_bytes(os.environ["CS451_MEMORY_BUDGET"]), "CS451_MEMORY_BUDGET")]
    cap, where = _cgroup_limit()
    limits = [(0.5 * _physical_memory(), "half this machine's memory"),
              (0.5 * cap, f"half the cap of this process's cgroup ({where})"),
              (0.5 * _address_space_left(), "half of what this process's RLIMIT_AS (ulimit -v) leaves"),
              (0.8 * _available_memory(), "80% of the memory free now")]
    return [(b, why) for b, why in limits if b != float("inf")]


def memory_budget() -> float:
    """The tightest of :func:`memory_limits`."""
    return min(memory_limits())[0]


def size_text(n: float) -> str:
    for unit, scale in (("TB", 2**40), ("GB", 2**30), ("MB", 2**20)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{n / 2**10:.3g} KB"


def refuse_over_budget(file: str, costs: list[Cost], budget: float | None = None) -> None:
    """Raise an InputError naming the costliest field when the costs together exceed the memory budget, then
    the time budget (:func:`refuse_over_time`)."""
    budget, why = min(memory_limits()) if budget is None else (budget, "given")
    total = sum(c.bytes for c in costs)
    if costs and total > budget:
        worst = max(costs, key=lambda c: c.bytes)
        source = "set by CS451_MEMORY_BUDGET" if why == "CS451_MEMORY_BUDGET" else f"{why}; CS451_MEMORY_BUDGET sets it"
        raise InputError(file, worst.field, f"asks for {worst.what}: about {size_text(total)} of memory in all, over "
                                            f"this process's budget of {size_text(budget)} ({source})")
    refuse_over_time(file, costs)


#: the longest job a scene may ask for without CS451_TIME_BUDGET saying more is meant: 30 minutes
TIME_BUDGET = 1800.0


def refuse_over_time(file: str, costs: list[Cost]) -> None:
    """Refuse a job whose parts together would run past the time budget, naming the slowest part's field: a 10⁶
    in the wrong field should not keep a machine busy for a day before anyone hears of it."""
    try:
        budget = float(os.environ.get("CS451_TIME_BUDGET") or TIME_BUDGET)
    except ValueError:
        raise KitError(f"CS451_TIME_BUDGET: expected seconds, such as 3600, got "
                       f"{os.environ['CS451_TIME_BUDGET']!r}") from None
    seconds = sum(c.seconds for c in costs)
    if seconds > budget:
        worst = max(costs, key=lambda c: c.seconds)
        raise InputError(file, worst.field, f"asks for {worst.what}: about {_duration(seconds)} at the reference's "
                                            f"speed, over the budget of {_duration(budget)} (CS451_TIME_BUDGET, in "
                                            f"seconds, sets it)")


def _duration(seconds: float) -> str:
    for unit, scale in (("days", 86400), ("hours", 3600), ("minutes", 60)):
        if seconds >= 2 * scale:
            return f"{seconds / scale:.3g} {unit}"
    return f"{seconds:.3g} s"


def check_image_size(width: int, height: int, what: str) -> str | None:
    """Why an image of this size cannot be made, or None."""
    if width > MAX_SIDE or height > MAX_SIDE:
        return f"{what} {width}x{height}: each side must be at most {MAX_SIDE} pixels"
    if width * height > MAX_PIXELS:
        return f"{what} {width}x{height}: at most {MAX_PIXELS:,} pixels"
    return None
