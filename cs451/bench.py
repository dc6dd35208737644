"""``cs451 bench STAGE``: runs ``bench/<stage>.py`` from the kit checkout (benchmarks are not tests)."""
from __future__ import annotations

import re
from pathlib import Path
from types import ModuleType

from . import KIT_ROOT, import_from_kit
from .errors import KitError

#: the extra of pyproject.toml that installs what the benchmarks' plots need
PLOTS_EXTRA = "bench"


def _source(name: str) -> Path:
    path = KIT_ROOT / "bench" / f"{name}.py"
    if not path.exists():
        raise KitError(f"no benchmark {name!r} (expected bench/{name}.py in the kit checkout)")
    return path


def bench_module(name: str) -> ModuleType:
    """``bench/<name>.py`` of the kit checkout, imported (the benchmarks import ``bench`` and ``autograder``)."""
    _source(name)
    return import_from_kit(f"bench.{name}")


def check_bench(name: str) -> None:
    """Refuse, before anything runs, a benchmark whose plots need matplotlib where it is not installed: the plot
    comes last, and a run of minutes should not end in an ImportError. Which benchmarks plot is read from their
    source (``import matplotlib``), so a new one needs no list kept here."""
    if not re.search(r"^\s*import matplotlib\b", _source(name).read_text(), re.M):
        return
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise KitError(f"bench {name}: its plots need matplotlib, which is not installed: "
                       f"pip install 'cs451-kit[{PLOTS_EXTRA}]' (or pip install -e '.[{PLOTS_EXTRA}]' in the kit)") from None


def run_bench(*, stage: str, output: str | Path = "bench-results", quick: bool = False) -> None:
    """Run one benchmark into ``output`` (a folder), once :func:`check_bench` has found what it needs."""
    check_bench(stage)
    bench_module(stage).main(output=Path(output), quick=quick)
