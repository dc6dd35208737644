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
    """What one part of a job needs: the scene field that sets it, bytes, and what they are for."""
    field: str          # JSON path in the scene file: "options.radiosity.patch_size"
    bytes: float
    what: str           # "9.2e12 patches and their form factors"


def _cgroup_limit() -> float:
    """The memory cap of this process's cgroup (v2 or v1), or infinity (Gradescope runs in a 768 MB one)."""
    for path in ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"):
        try:
            text = Path(path).read_text().strip()
        except OSError:
            continue
        if text.isdigit() and int(text) < 1 << 60:
            return float(text)
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


def memory_budget() -> float:
    """Half of this machine's memory (or of its cgroup's cap), or ``CS451_MEMORY_BUDGET`` where set."""
    if os.environ.get("CS451_MEMORY_BUDGET"):
        return parse_bytes(os.environ["CS451_MEMORY_BUDGET"])
    return 0.5 * min(_physical_memory(), _cgroup_limit())


def size_text(n: float) -> str:
    for unit, scale in (("TB", 2**40), ("GB", 2**30), ("MB", 2**20)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{n / 2**10:.3g} KB"


def refuse_over_budget(file: str, costs: list[Cost], budget: float | None = None) -> None:
    """Raise an InputError naming the costliest field when the costs together exceed the budget."""
    budget = memory_budget() if budget is None else budget
    total = sum(c.bytes for c in costs)
    if not costs or total <= budget:
        return
    worst = max(costs, key=lambda c: c.bytes)
    raise InputError(file, worst.field, f"asks for {worst.what}: about {size_text(total)} of memory in all, over "
                     f"this machine's budget of {size_text(budget)} (half its memory; CS451_MEMORY_BUDGET sets it)")


def check_image_size(width: int, height: int, what: str) -> str | None:
    """Why an image of this size cannot be made, or None."""
    if width > MAX_SIDE or height > MAX_SIDE:
        return f"{what} {width}x{height}: each side must be at most {MAX_SIDE} pixels"
    if width * height > MAX_PIXELS:
        return f"{what} {width}x{height}: at most {MAX_PIXELS:,} pixels"
    return None
