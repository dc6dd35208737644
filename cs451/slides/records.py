"""Recorded measurements the decks' benchmark figures are drawn from, never timed while a deck is built.

A record is ``slides/records/<name>.json``: the measured ``rows``, what each column means (``columns``), the
``machine`` it was measured on (CPU model, cores, OS, Python, numpy, and the GL renderer where GL draws), the
``date`` (UTC, ISO 8601), the exact ``command`` that made it, how many ``repeats`` each timing is the median of,
and the measurement's ``params``. ``cs451 slides record [NAME ...]`` measures and writes them (:func:`record`),
one after another, through each benchmark's own ``slide_record`` function (:data:`RECORDERS`); a figure reads
one with :func:`load_record`, and its cache key holds the record's text (``records=`` in
:func:`cs451.slides.registry.slide_figure`), so a new record draws the figure again and nothing else does.
"""
from __future__ import annotations

import datetime
import json
import os
import platform
import re
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .. import KIT_ROOT
from ..errors import KitError

#: Where records live (tests point it at a folder of their own).
RECORDS = KIT_ROOT / "slides" / "records"
#: Each timing is the median of at least this many runs.
MIN_REPEATS = 3
#: What every record holds, and what its ``machine`` names.
FIELDS = ("name", "description", "machine", "date", "command", "repeats", "quick", "columns", "rows", "params")
MACHINE = ("cpu", "cores", "os", "python", "numpy")


@dataclass(frozen=True)
class Recorder:
    """One record: what it measures, and the benchmark function that measures it
    (``<module>::<function>(quick, repeats)``, a stage's benchmark module, returning ``rows``, ``columns``, ``params`` and, where GL
    drew, ``gl_renderer``)."""
    name: str
    description: str
    module: str
    function: str = "slide_record"


#: Every record, declared by the stage whose benchmark figure draws from it (:func:`declare_record`, in the
#: stage's ``figures.py``); :func:`recorders` loads those declarations.
RECORDERS: dict[str, Recorder] = {}


def declare_record(name: str, description: str, module: str, function: str = "slide_record") -> None:
    """A record a stage's benchmark figure draws from, measured by ``<module>::<function>`` (``module`` a
    benchmark module of the stage's package, named in full: ``f"{__package__}.bench"``)."""
    RECORDERS[name] = Recorder(name, description, module, function)


def recorders() -> dict[str, Recorder]:
    """Every declared record (the stages' figure modules declare them; importing the figures loads them all)."""
    import importlib.util
    from ..stages import stage_names
    from ..stages.base import part
    for stage in stage_names():             # each stage's figures.py declares the records its figures read
        if importlib.util.find_spec(f"cs451.stages.{stage}.figures") is not None:
            part(f"cs451.stages.{stage}", "figures")
    return RECORDERS


def command_for(names: list[str] | None = None, quick: bool = False, repeats: int = MIN_REPEATS) -> str:
    """The command line that makes these records (as a record names it, and as a refusal tells it)."""
    words = ["cs451", "slides", "record", *(names or [])]
    if quick:
        words.append("--quick")
    if repeats != MIN_REPEATS:
        words += ["--repeats", str(repeats)]
    return " ".join(words)


def record_path(name: str, must_exist: bool = False) -> Path:
    """``slides/records/<name>.json``; with ``must_exist``, a missing file is refused in one line naming it and the
    command that makes it."""
    if name not in recorders():
        raise KitError(f"unknown record {name!r} (the records: {', '.join(recorders())})")
    path = Path(RECORDS) / f"{name}.json"
    if must_exist and not path.is_file():
        raise KitError(f"{_shown(path)}: no such record; make it with `{command_for([name])}` "
                       "(the benchmark figures draw only from recorded measurements)")
    return path


def _shown(path: Path) -> str:
    try:
        return path.resolve().relative_to(KIT_ROOT.resolve()).as_posix()
    except ValueError:
        return str(path)


def _cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.lower().startswith("model name"):
                return re.sub(r"\s+", " ", line.split(":", 1)[1]).strip()
    except OSError:
        pass
    return platform.processor() or platform.machine() or "unknown CPU"


def machine(gl_renderer: str | None = None) -> dict[str, Any]:
    """What a measurement ran on: the CPU model, the cores this process may use (and the machine's), the OS,
    Python, numpy, the load average when it began, and the GL renderer where GL drew."""
    import numpy
    usable = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    out: dict[str, Any] = {"cpu": _cpu_model(), "cores": usable, "cores_on_machine": os.cpu_count(),
                           "os": platform.platform(), "python": platform.python_version(), "numpy": numpy.__version__}
    if hasattr(os, "getloadavg"):
        out["load_average"] = [round(x, 2) for x in os.getloadavg()]
    if gl_renderer:
        out["gl_renderer"] = gl_renderer
    return out


def check_record(data: Any, path: Path, name: str) -> dict[str, Any]:
    """``data`` as a record, or a one-line refusal naming the file, what is wrong and the command that makes it."""
    def refuse(problem: str) -> KitError:
        return KitError(f"{_shown(path)}: not a valid record ({problem}); make it again with "
                        f"`{command_for([name])}`")
    if not isinstance(data, dict):
        raise refuse("not a JSON object")
    missing = [f for f in FIELDS if f not in data]
    if missing:
        raise refuse(f"no {', '.join(missing)}")
    if data["name"] != name:
        raise refuse(f"it is the record of {data['name']!r}")
    if not isinstance(data["machine"], dict) or any(not data["machine"].get(k) for k in MACHINE):
        raise refuse(f"its machine must name {', '.join(MACHINE)}")
    if not isinstance(data["command"], str) or not data["command"].startswith("cs451 slides record"):
        raise refuse("its command must be the `cs451 slides record` line that made it")
    try:
        datetime.datetime.fromisoformat(str(data["date"]).replace("Z", "+00:00"))
    except ValueError:
        raise refuse(f"date {data['date']!r} is not an ISO 8601 time") from None
    if not isinstance(data["repeats"], int) or data["repeats"] < MIN_REPEATS:
        raise refuse(f"repeats must be at least {MIN_REPEATS}")
    rows, columns = data["rows"], data["columns"]
    if not isinstance(columns, dict) or not columns:
        raise refuse("columns must say what each column means")
    if not isinstance(rows, list) or not rows or not all(isinstance(r, dict) for r in rows):
        raise refuse("rows must be a non-empty list of objects")
    unexplained = sorted({k for r in rows for k in r} - set(columns))
    if unexplained:
        raise refuse(f"columns do not say what {', '.join(unexplained)} mean")
    return data


def load_record(name: str) -> dict[str, Any]:
    """The record ``name``, checked; a missing or invalid one is refused in one line naming the file and the command
    that makes it."""
    path = record_path(name, must_exist=True)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
        raise KitError(f"{_shown(path)}: not a valid record ({type(err).__name__}: {err}); make it again with "
                       f"`{command_for([name])}`") from None
    return check_record(data, path, name)


def write_record(name: str, measured: dict[str, Any], *, command: str, repeats: int, quick: bool,
                 folder: Path | None = None, began: datetime.datetime | None = None,
                 machine_info: dict[str, Any] | None = None) -> Path:
    """Write a benchmark's measurement as record ``name`` (through a temporary file: a reader never sees half of
    one), checked as :func:`load_record` checks it."""
    path = Path(folder) / f"{name}.json" if folder is not None else record_path(name)
    began = began or datetime.datetime.now(datetime.timezone.utc)
    data = {"name": name, "description": recorders()[name].description,
            "machine": machine_info or machine(measured.get("gl_renderer")),
            "date": began.replace(microsecond=0).isoformat().replace("+00:00", "Z"), "command": command,
            "repeats": int(repeats), "quick": bool(quick), "columns": measured["columns"], "rows": measured["rows"],
            "params": measured.get("params", {})}
    check_record(json.loads(json.dumps(data, default=float)), path, name)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{name}-", suffix=".json", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as out:
            json.dump(data, out, indent=1, default=float, ensure_ascii=False)
            out.write("\n")
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def measure(name: str, quick: bool = False, repeats: int = MIN_REPEATS) -> dict[str, Any]:
    """Run record ``name``'s benchmark function (in its stage's benchmark module), as ``cs451 slides record`` does."""
    import importlib
    from .. import import_from_kit
    recorder = recorders()[name]
    import_from_kit("bench")                # benchmarks import the kit's bench/ and autograder/ from its folder
    return getattr(importlib.import_module(recorder.module), recorder.function)(quick=quick, repeats=repeats)


def record(names: list[str] | None = None, quick: bool = False, repeats: int = MIN_REPEATS,
           folder: Path | None = None, out: Any = None) -> list[Path]:
    """Measure and write the records named (all by default), one after another; each line of progress and each
    file written is printed to ``out`` (stdout)."""
    out = out or sys.stdout
    chosen = list(names or recorders())
    for name in chosen:
        record_path(name)                                    # an unknown name fails before anything is measured
    if repeats < MIN_REPEATS:
        raise KitError(f"--repeats {repeats}: each timing is the median of at least {MIN_REPEATS} runs")
    command = command_for(list(names or []), quick, repeats) + (f" -o {folder}" if folder is not None else "")
    written = []
    for name in chosen:
        print(f"recording {name}: {recorders()[name].description}", file=out, flush=True)
        began = datetime.datetime.now(datetime.timezone.utc)
        info = machine()                                      # the load average as the measurement begins
        start = time.perf_counter()
        measured = measure(name, quick, repeats)
        if measured.get("gl_renderer"):
            info["gl_renderer"] = measured["gl_renderer"]
        path = write_record(name, measured, command=command, repeats=repeats, quick=quick, folder=folder,
                            began=began, machine_info=info)
        print(f"wrote {_shown(path)} ({len(measured['rows'])} rows, {time.perf_counter() - start:.0f} s)",
              file=out, flush=True)
        written.append(path)
    return written


def provenance(data: dict[str, Any]) -> str:
    """One sentence for a figure: when, on what and by which command its record was measured."""
    m = data["machine"]
    date = str(data["date"]).replace("T", " ").replace("Z", "")[:16] + " UTC"
    system = re.split(r"[-_]", m["os"])[0]
    parts = [f"{m['cpu']} ({m['cores']} core{'s' * (m['cores'] != 1)})", system, f"Python {m['python']}",
             f"numpy {m['numpy']}"]
    if m.get("gl_renderer"):
        parts.append(f"GL {m['gl_renderer'].split(' (')[0].split(' /')[0]}")
    load = f", load {m['load_average'][0]:.1f}" if m.get("load_average") else ""
    quick = " (a quick run: small sizes, not for a lecture)" if data.get("quick") else ""
    return (f"Measured {date} on {', '.join(parts)}{load}; median of {data['repeats']} runs: "
            f"`{data['command']}`{quick}")


def facts(data: dict[str, Any]) -> dict[str, Any]:
    """What a benchmark figure returns about its record, for the deck to quote: machine, date, command, repeats."""
    return {"record": {k: data[k] for k in ("machine", "date", "command", "repeats", "quick")}}
