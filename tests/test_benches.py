"""Every benchmark runs, so that none rots unseen: ``cs451 bench NAME --quick`` for every benchmark the command lists
(each stage's, in its package, and the kit's own in bench/), through the console script, on its small size.

Each must exit 0 and write ``NAME.json`` holding the keys its module promises (``KEYS``: what the decks, the docs and
the records read of it). Nothing here asserts a time: the benches measure, the tests only run them.
"""
from __future__ import annotations

import importlib.util
import json

import pytest

from cs451 import KIT_ROOT
from cs451.bench import benches, bench_module



def _cases() -> list:
    return [pytest.param(name, marks=[getattr(pytest.mark, b.stage)] if b.stage else [], id=name)
            for name, b in benches().items()]


@pytest.mark.spawns
@pytest.mark.parametrize("name", _cases())
def test_every_benchmark_runs_quick_and_writes_what_is_read(name: str, bench_run) -> None:
    module = bench_module(name)
    keys = getattr(module, "KEYS", None)
    assert keys, f"{benches()[name].path}: no KEYS (the keys of {name}.json that docs and decks read)"
    for peer in getattr(module, "NEEDS", ()):
        if importlib.util.find_spec(peer) is None:
            pytest.skip(f"bench {name} needs {peer}, an optional peer (pip install -e '.[peers]')")
    folder, done = bench_run(name)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-3000:]
    written = folder / f"{name}.json"
    assert written.is_file(), sorted(p.name for p in folder.iterdir())
    data = json.loads(written.read_text())
    for row in data if isinstance(data, list) else [data]:          # a list: each row holds the keys
        assert isinstance(row, dict) and set(keys) <= set(row), f"{name}.json lacks {sorted(set(keys) - set(row))}"
    assert data, f"{name}.json is empty"
    assert "Traceback" not in done.stderr, done.stderr[-3000:]


def test_a_benchmark_without_its_plotting_library_is_refused_before_it_runs(monkeypatch: pytest.MonkeyPatch) -> None:
    """Where matplotlib is missing, a benchmark that plots is refused in one line, naming the extra, and one that
    does not plot is not (read from their source: nothing runs)."""
    import builtins

    from cs451.bench import check_bench
    from cs451.errors import KitError
    real = builtins.__import__

    def no_matplotlib(name: str, *args, **kwargs):
        if name == "matplotlib" or name.startswith("matplotlib."):
            raise ImportError("no matplotlib here")
        return real(name, *args, **kwargs)
    monkeypatch.setattr(builtins, "__import__", no_matplotlib)
    plotting = [n for n, b in benches().items() if "import matplotlib" in b.path.read_text()]
    assert plotting, "no benchmark plots: the refusal is not exercised"
    with pytest.raises(KitError, match=r"pip install 'cs451-kit\[bench\]'"):
        check_bench(plotting[0])
    for name, b in benches().items():
        if "import matplotlib" not in b.path.read_text():
            check_bench(name)


def test_the_kit_s_benchmarks_are_found_where_they_live() -> None:
    """Each stage's ``bench.py`` is ``cs451 bench <stage>``; the kit's own are bench/*.py; a part is not a command."""
    from cs451.stages import stage_names
    found = benches()
    for stage in stage_names():
        if (KIT_ROOT / "cs451" / "stages" / stage / "bench.py").is_file():
            assert found[stage].module == f"cs451.stages.{stage}.bench"
    assert {"walkthrough", "formfactors", "autograder", "tolerance"} <= set(found)
    assert not {"kernels", "peer", "meshes", "record"} & set(found), sorted(found)
