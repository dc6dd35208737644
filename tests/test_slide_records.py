"""The benchmark figures' records (cs451/slides/records.py, issue 37): measured once by ``cs451 slides record``, never
while a deck is built.

A record round-trips; a missing or broken one is refused in one line naming its file and the command that makes it;
the benchmark figures draw from the record alone (every timing function made to fail, they still draw), keyed by
its text; every committed record names its machine, date and command, and is a full run. Nothing here asserts a
timing.
"""
from __future__ import annotations

import datetime
import importlib
import json
from pathlib import Path

import pytest

from cs451 import bench as kit_bench
from cs451.errors import KitError
from cs451.slides import figures, records

#: Each benchmark figure and the record it draws from, as the stages declare them (``records=`` of their figures).
BENCH_FIGURES = {name: figures.spec_of(name).records[0] for name in figures.FIGURES if figures.spec_of(name).records}


def measured(rows: int = 3) -> dict:
    return {"rows": [{"size": k, "seconds": 0.1 * (k + 1)} for k in range(rows)],
            "columns": {"size": "what was varied", "seconds": "median seconds"},
            "params": {"scene": "a test"}, "gl_renderer": "a test renderer"}


@pytest.mark.spawns
def test01_a_record_round_trips(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(records, "RECORDS", tmp_path)
    path = records.write_record("whitted", measured(), command="cs451 slides record whitted", repeats=3, quick=False)
    assert path == tmp_path / "whitted.json"
    back = records.load_record("whitted")
    assert back["rows"] == measured()["rows"] and back["columns"] == measured()["columns"]
    assert back["params"] == {"scene": "a test"} and back["repeats"] == 3 and back["quick"] is False
    assert back["command"] == "cs451 slides record whitted"
    assert back["machine"]["gl_renderer"] == "a test renderer"
    assert all(back["machine"][k] for k in records.MACHINE)
    when = datetime.datetime.fromisoformat(back["date"].replace("Z", "+00:00"))
    assert when.tzinfo is not None and abs((datetime.datetime.now(datetime.timezone.utc) - when).total_seconds()) < 600


@pytest.mark.parametrize("name", list(records.recorders()))
def test02_a_missing_record_is_refused_in_one_line_naming_the_file_and_the_command(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, name: str) -> None:
    monkeypatch.setattr(records, "RECORDS", tmp_path)
    with pytest.raises(KitError) as caught:
        records.load_record(name)
    message = str(caught.value)
    assert "\n" not in message
    assert f"{name}.json" in message and f"cs451 slides record {name}" in message


@pytest.mark.parametrize("text, problem", [
    ("{not json", "JSONDecodeError"),
    ('{"name": "whitted"}', "no description"),
    ("[1, 2]", "not a JSON object"),
])
def test03_a_broken_record_is_refused_in_one_line(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, text: str,
                                                 problem: str) -> None:
    monkeypatch.setattr(records, "RECORDS", tmp_path)
    (tmp_path / "whitted.json").write_text(text)
    with pytest.raises(KitError) as caught:
        records.load_record("whitted")
    message = str(caught.value)
    assert "\n" not in message and problem in message
    assert "whitted.json" in message and "cs451 slides record whitted" in message


def test04_a_record_must_name_its_machine_date_and_command(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(records, "RECORDS", tmp_path)
    good = json.loads(records.write_record("hemicube", measured(), command="cs451 slides record hemicube",
                                           repeats=3, quick=False).read_text())
    for field, value, problem in (("machine", {"cpu": "x"}, "machine must name"), ("date", "yesterday", "ISO 8601"),
                                  ("command", "python bench.py", "command"), ("repeats", 1, "repeats"),
                                  ("rows", [{"unexplained": 1}], "columns do not say")):
        (tmp_path / "hemicube.json").write_text(json.dumps({**good, field: value}))
        with pytest.raises(KitError, match=problem):
            records.load_record("hemicube")


def test05_the_bench_figures_draw_from_the_record_alone(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Every way to measure is made to fail: the benchmarks, the reference, GL, the stages. The figures still draw,
    from the committed records, and say where those came from."""
    def boom(*args: object, **kwargs: object) -> None:
        raise AssertionError("a benchmark figure measured something while the deck was built")
    import cs451.gl
    monkeypatch.setattr(kit_bench, "bench_module", boom)
    monkeypatch.setattr(records, "measure", boom)
    monkeypatch.setattr(cs451.gl, "create_context", boom)
    drawers = {figures.spec_of(figure).draw.__module__ for figure in BENCH_FIGURES}
    for module in [importlib.import_module(m) for m in drawers | {m.rsplit(".", 1)[0] + ".figures" for m in drawers}]:
        for name in ("reference_impl", "get_stage", "scene_data", "parse_scene"):
            if hasattr(module, name):
                monkeypatch.setattr(module, name, boom)
    for figure, record in BENCH_FIGURES.items():
        path = figures.render_figure(figure, tmp_path)
        facts = figures.figure_facts(path)
        data = records.load_record(record)
        assert facts["record"]["date"] == data["date"] and facts["record"]["command"] == data["command"]
        assert facts["record"]["machine"]["cpu"] == data["machine"]["cpu"]


def test06_a_bench_figure_is_keyed_by_its_record(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    before = {name: figures.figure_key(name) for name in figures.FIGURES}
    for record in BENCH_FIGURES.values():
        (tmp_path / f"{record}.json").write_bytes(records.record_path(record).read_bytes())
    monkeypatch.setattr(records, "RECORDS", tmp_path)
    assert {name: figures.figure_key(name) for name in figures.FIGURES} == before     # the same text, the same key
    data = json.loads((tmp_path / "radiosity.json").read_text())
    data["date"] = "2000-01-01T00:00:00Z"
    (tmp_path / "radiosity.json").write_text(json.dumps(data))
    after = {name: figures.figure_key(name) for name in figures.FIGURES}
    assert {name for name in before if after[name] != before[name]} == {"bench-radiosity"}
    (tmp_path / "radiosity.json").unlink()
    with pytest.raises(KitError, match="cs451 slides record radiosity"):
        figures.figure_key("bench-radiosity")


@pytest.mark.parametrize("name", list(records.recorders()))
def test07_every_committed_record_names_its_machine_date_and_command_and_is_a_full_run(name: str) -> None:
    data = records.load_record(name)
    assert all(data["machine"][k] for k in records.MACHINE)
    assert data["command"].startswith("cs451 slides record") and "--quick" not in data["command"]
    assert data["quick"] is False and data["repeats"] >= records.MIN_REPEATS
    assert set(data["columns"]) >= {k for row in data["rows"] for k in row}
    assert records.provenance(data).count(data["command"]) == 1


def test08_the_command_records_quick_runs_into_a_folder(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    from cs451.cli import main
    names = sorted(records.recorders())                 # every record a stage's figure declares
    assert set(names) == set(BENCH_FIGURES.values()) and len(names) >= 3
    asked, left = names[:-1], names[-1]
    assert main(["slides", "record", *asked, "--quick", "-o", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    for name in asked:
        data = records.check_record(json.loads((tmp_path / f"{name}.json").read_text()), tmp_path, name)
        assert data["quick"] is True and data["command"] == f"cs451 slides record {' '.join(asked)} --quick -o {tmp_path}"
        assert f"{name}.json" in out
    assert not (tmp_path / f"{left}.json").exists()          # only the records asked for
    assert main(["slides", "record", left, "--quick", "-o", str(tmp_path)]) == 0
    records.check_record(json.loads((tmp_path / f"{left}.json").read_text()), tmp_path, left)
    radiosity = json.loads((tmp_path / "radiosity.json").read_text())
    assert radiosity["machine"].get("gl_renderer")                   # GL drew its form factors: it names the renderer


def test09_the_command_refuses_an_unknown_record_and_too_few_repeats(tmp_path: Path,
                                                                     capsys: pytest.CaptureFixture) -> None:
    from cs451.cli import main
    assert main(["slides", "record", "whited", "-o", str(tmp_path)]) != 0
    assert "unknown record 'whited'" in capsys.readouterr().err
    assert main(["slides", "record", "whitted", "--repeats", "2", "-o", str(tmp_path)]) != 0
    assert "at least 3" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []
