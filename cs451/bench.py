"""``cs451 bench STAGE``: runs ``bench/<stage>.py`` from the kit checkout (benchmarks are not tests)."""
from __future__ import annotations

import importlib
import sys
from pathlib import Path
from types import ModuleType

from . import KIT_ROOT
from .errors import KitError


def bench_module(name: str) -> ModuleType:
    """``bench/<name>.py`` of the kit checkout, imported (the benchmarks import ``bench`` and ``autograder``)."""
    if not (KIT_ROOT / "bench" / f"{name}.py").exists():
        raise KitError(f"no benchmark {name!r} (expected bench/{name}.py in the kit checkout)")
    if str(KIT_ROOT) not in sys.path:
        sys.path.insert(0, str(KIT_ROOT))
    return importlib.import_module(f"bench.{name}")


def run_bench(*, stage: str, output: str | Path = "bench-results", quick: bool = False) -> None:
    bench_module(stage).main(output=Path(output), quick=quick)
