"""``cs451 bench STAGE``: runs ``bench/<stage>.py`` from the kit checkout (benchmarks are not tests)."""
from __future__ import annotations

from pathlib import Path
from types import ModuleType

from . import KIT_ROOT, import_from_kit
from .errors import KitError


def bench_module(name: str) -> ModuleType:
    """``bench/<name>.py`` of the kit checkout, imported (the benchmarks import ``bench`` and ``autograder``)."""
    if not (KIT_ROOT / "bench" / f"{name}.py").exists():
        raise KitError(f"no benchmark {name!r} (expected bench/{name}.py in the kit checkout)")
    return import_from_kit(f"bench.{name}")


def run_bench(*, stage: str, output: str | Path = "bench-results", quick: bool = False) -> None:
    bench_module(stage).main(output=Path(output), quick=quick)
