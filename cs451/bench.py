"""``cs451 bench STAGE``: runs ``bench/<stage>.py`` from the kit checkout (benchmarks are not tests)."""
from __future__ import annotations

import importlib
import sys
from pathlib import Path

from . import KIT_ROOT
from .errors import KitError


def run_bench(*, stage: str, output: str | Path = "bench-results", quick: bool = False) -> None:
    if not (KIT_ROOT / "bench" / f"{stage}.py").exists():
        raise KitError(f"no benchmark for stage {stage!r} (expected bench/{stage}.py in the kit checkout)")
    if str(KIT_ROOT) not in sys.path:
        sys.path.insert(0, str(KIT_ROOT))
    module = importlib.import_module(f"bench.{stage}")
    module.main(output=Path(output), quick=quick)
