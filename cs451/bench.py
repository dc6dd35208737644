"""``cs451 bench NAME``: the kit's benchmarks, found where they live (benchmarks are not tests).

A stage's benchmarks sit in its own package, beside the code they measure: ``cs451/stages/<stage>/bench.py`` is
``cs451 bench <stage>``, and a ``bench_<name>.py`` beside it that defines ``main(output, quick)`` is ``cs451 bench
<name>`` (``walkthrough``, ``formfactors``); a ``bench_*.py`` without one is a part the others import. Benchmarks
that measure every stage at once (grading's cost, the image tolerance, planted mistakes) are the kit's own, in
``bench/<name>.py`` of the checkout. All of them are instructors' only (:func:`cs451.instructor_only`): their
solvers would answer tasks, so no release or sandbox holds them. The list below is read from the files, so a new
benchmark needs no list kept by hand: the command's choices and help come from it.
"""
from __future__ import annotations

import importlib
import re
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

from . import ENGINE_DIR, KIT_ROOT, import_from_kit
from .errors import KitError

#: The extra of pyproject.toml that installs what the benchmarks' plots need.
PLOTS_EXTRA = "bench"
#: A stage's benchmark modules: ``bench.py`` (the stage's own command) and ``bench_<name>.py``.
STAGE_BENCH, PART_PREFIX = "bench", "bench_"


@dataclass(frozen=True)
class Bench:
    """One ``cs451 bench`` command: its name, the module that runs it, its source and the stage it belongs to
    (None for the kit's own, in ``bench/``)."""
    name: str
    module: str
    path: Path
    stage: str | None

    @property
    def summary(self) -> str:
        """The first sentence of the module's docstring, without its ``cs451 bench NAME``: prefix (the help text)."""
        doc = re.match(r'\s*(?:"""|\'\'\')(.*?)(?:"""|\'\'\')', self.path.read_text(), re.S)
        first = " ".join((doc.group(1) if doc else "").split("\n\n")[0].split())
        first = re.sub(r"^``cs451 bench \w+``:\s*", "", first)
        return first.split(". ")[0].rstrip(".")


def _runs(path: Path) -> bool:
    """Whether a module is a command: it defines ``main`` taking ``output`` and ``quick`` at its top level (read
    from the text, not imported: the command's help lists them at every start)."""
    signature = re.search(r"^def main\(([^)]*)\)", path.read_text(), re.M)
    return signature is not None and {"output", "quick"} <= set(re.findall(r"\b(\w+)\s*[:=,)]", signature.group(1) + ")"))


def benches() -> dict[str, Bench]:
    """Every benchmark command, by name: each stage's (in stage order), then the kit's own."""
    from .stages import stage_names
    found: dict[str, Bench] = {}

    def add(bench: Bench) -> None:
        if bench.name in found:
            raise KitError(f"two benchmarks are called {bench.name!r}: {found[bench.name].path} and {bench.path}")
        found[bench.name] = bench
    for stage in stage_names():
        folder = ENGINE_DIR / "stages" / stage
        own = folder / f"{STAGE_BENCH}.py"
        if own.is_file() and _runs(own):
            add(Bench(stage, f"cs451.stages.{stage}.{STAGE_BENCH}", own, stage))
        for path in sorted(folder.glob(f"{PART_PREFIX}*.py")):
            if _runs(path):
                add(Bench(path.stem.removeprefix(PART_PREFIX), f"cs451.stages.{stage}.{path.stem}", path, stage))
    for path in sorted((KIT_ROOT / "bench").glob("*.py")):
        if not path.name.startswith("_") and _runs(path):
            add(Bench(path.stem, f"bench.{path.stem}", path, None))
    return found


def _bench(name: str) -> Bench:
    found = benches()
    if name not in found:
        raise KitError(f"no benchmark {name!r} (benchmarks: {', '.join(found) or 'none in this copy'})")
    return found[name]


def bench_module(name: str) -> ModuleType:
    """Benchmark ``name`` imported. The kit's folder goes on ``sys.path`` first: benchmarks import ``bench.meshes``
    and ``autograder`` from it, wherever the command was typed."""
    import_from_kit("bench")
    return importlib.import_module(_bench(name).module)


def check_bench(name: str) -> None:
    """Refuse, before anything runs, a benchmark whose plots need matplotlib where it is not installed: the plot
    comes last, and a run of minutes should not end in an ImportError. Which benchmarks plot is read from their
    source (``import matplotlib``), so a new one needs no list kept here."""
    if not re.search(r"^\s*import matplotlib\b", _bench(name).path.read_text(), re.M):
        return
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise KitError(f"bench {name}: its plots need matplotlib, which is not installed: "
                       f"pip install 'cs451-kit[{PLOTS_EXTRA}]' (or pip install -e '.[{PLOTS_EXTRA}]' in the kit)") from None


def run_bench(*, stage: str, output: str | Path = "bench-results", quick: bool = False) -> None:
    """Run benchmark ``stage`` (a stage's name, or another benchmark's) into ``output`` (a folder), once
    :func:`check_bench` has found what it needs."""
    check_bench(stage)
    bench_module(stage).main(output=Path(output), quick=quick)
