"""Which tests a ``pytest`` command runs: a marker per stage, the fast suite by default, and the ``spawns`` marker kept
true by watching.

- **A marker per stage**, from the registry (``cs451.stages.stage_names``), never a list kept here: a test belongs to
  stage S when it sits in ``tests/S/`` or when it is parametrised on S (the contract, handout and seat tests run once
  per stage). ``pytest -m radiosity`` runs stage 4's tests, whichever file holds them.
- **The fast suite by default.** Tests marked ``slow`` or ``seat`` run only when the ``-m`` expression names them
  (``-m slow``, ``-m seat``, ``-m "radiosity and slow"``, or ``-m "slow or not slow"`` for everything), so that
  ``pytest -m radiosity`` stays a stage's fast tests.
- **``spawns``**: the test starts another process (a grading sandbox, a console script, a compiler, a browser), so
  ``pytest -m "not spawns"`` runs in one process. The mark is checked while the tests run: a test that starts a
  process from the kit's own code (``cs451/``, ``tests/``, ``autograder/``, ``bench/``, ``reference/``) without it
  fails, naming the mark. Two kinds of process do not count, since whether they start depends on the machine or on
  the tests before, not on the test: a library's own helper (a font cache, say), and the reference's answers
  computed into the grader's cache.
"""
from __future__ import annotations

import os
import re
import sys
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Iterator

import pytest

TESTS = Path(__file__).resolve().parent
#: Where a process started from counts as the kit's own (the folders of the kit's checkout).
OWN_CODE = tuple(str(TESTS.parent / top) + os.sep for top in ("cs451", "tests", "autograder", "bench", "reference"))
SPAWNS = "spawns"
#: Markers that keep a test out of the default run, unless the ``-m`` expression names them.
SLOW_KINDS = ("slow", "seat")


def stage_names() -> list[str]:
    from cs451.stages import stage_names as names
    return names()


def register_markers(config: pytest.Config) -> None:
    """One marker per registered stage, and ``spawns``."""
    from cs451.stages import get_stage
    for name in stage_names():
        config.addinivalue_line("markers", f"{name}: stage {get_stage(name).number}'s tests (tests/{name}/, and every "
                                           f"test parametrised on {name})")
    config.addinivalue_line("markers", f"{SPAWNS}: starts another process (sandbox, console script, browser, compiler)")


def stages_of(item: pytest.Item) -> set[str]:
    """The stages a collected test belongs to: its folder's, and any it is parametrised on."""
    names = set(stage_names())
    found = set()
    try:
        parts = Path(str(item.path)).resolve().relative_to(TESTS).parts
    except ValueError:
        parts = ()
    if len(parts) > 1 and parts[0] in names:
        found.add(parts[0])
    callspec = getattr(item, "callspec", None)
    for value in (callspec.params.values() if callspec else ()):
        if isinstance(value, str) and value in names:
            found.add(value)
    return found


def mark_and_select(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Add the stage markers, then leave out slow and seat tests unless the ``-m`` expression names them."""
    for item in items:
        for stage in sorted(stages_of(item)):
            item.add_marker(getattr(pytest.mark, stage))
    expression = config.getoption("markexpr") or ""
    if any(re.search(rf"\b{kind}\b", expression) for kind in SLOW_KINDS):
        return
    kept, left = [], []
    for item in items:
        (left if any(item.get_closest_marker(kind) for kind in SLOW_KINDS) else kept).append(item)
    if left:
        config.hook.pytest_deselected(items=left)
        items[:] = kept


#: Where a process started does not count: the reference's answers computed into the grader's cache (any test that
#: reads an answer may fill the cache the first time, so whether it does depends on the tests run before it).
CACHE_FILLS = (os.sep + os.path.join("cs451", "grading", "expected.py"),)


def _own_caller() -> str | None:
    """The first frame outside the process-starting machinery, if it is the kit's own code and no frame below it is
    filling the answer cache."""
    frame = sys._getframe(2)
    probe = frame
    while probe is not None:
        if probe.f_code.co_filename.endswith(CACHE_FILLS):
            return None
        probe = probe.f_back
    while frame is not None:
        name = frame.f_code.co_filename
        if not name.startswith(os.path.dirname(os.__file__)) and os.sep + "multiprocessing" + os.sep not in name:
            return name if name.startswith(OWN_CODE) else None
        frame = frame.f_back
    return None


#: What each test started, by node id (setup and call add to it; :func:`check_spawns` reads it).
STARTED: dict[str, list[str]] = {}


@contextmanager
def watching_spawns(item: pytest.Item) -> Iterator[list[str]]:
    """While a test sets up or runs, note every process the kit's own code starts (subprocess, multiprocessing,
    os.fork) under the test's node id."""
    import _posixsubprocess
    import multiprocessing.process
    import subprocess
    started = STARTED.setdefault(item.nodeid, [])
    originals: list[tuple[Any, str, Any]] = []

    def watch(owner: Any, name: str) -> None:
        original = getattr(owner, name)

        def watched(*args: Any, **kwargs: Any) -> Any:
            caller = _own_caller()
            if caller is not None:
                started.append(f"{name} from {Path(caller).relative_to(TESTS.parent)}")
            return original(*args, **kwargs)
        originals.append((owner, name, original))
        setattr(owner, name, watched)
    watch(subprocess, "_fork_exec")                 # subprocess binds it at import
    watch(_posixsubprocess, "fork_exec")            # multiprocessing's own starts
    watch(multiprocessing.process.BaseProcess, "start")
    for name in ("fork", "posix_spawn", "posix_spawnp", "system"):
        if hasattr(os, name):
            watch(os, name)
    try:
        yield started
    finally:
        for owner, name, original in reversed(originals):
            setattr(owner, name, original)


def check_spawns(item: pytest.Item) -> None:
    """Fail a test that started a process (in its set-up or its call) without the ``spawns`` marker."""
    started = STARTED.pop(item.nodeid, [])
    listing = os.environ.get("CS451_LIST_SPAWNS")      # a file to list them in instead (marking the tests in bulk)
    if started and listing and item.get_closest_marker(SPAWNS) is None:
        with open(listing, "a") as out:
            out.write(f"{item.nodeid}\t{started[0]}\n")
        return
    if started and item.get_closest_marker(SPAWNS) is None:
        pytest.fail(f"{item.nodeid} starts processes ({started[0]}) but is not marked "
                    f"@pytest.mark.{SPAWNS} (tests/selection.py)", pytrace=False)
