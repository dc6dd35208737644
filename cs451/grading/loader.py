"""Finding a stage's tests: the spec modules in the instructor's kit, the manifest in a student copy.

The kit declares tests in ``autograder/<stage>/public.py`` and ``hidden.py``; every
test of ``hidden.py`` is hidden, whatever it says. A student copy has neither
(they import the truths): it has ``public.json``, the public tests as data,
written by :func:`write_manifest` when the copy is built.

Given the kit's secret (:func:`variant_secret`), :func:`load_tests` replaces every public
test's case by its variant's fresh case (``autograder/<stage>/variants.py``), the same for
every submission graded with that secret and unknown to students.
"""
from __future__ import annotations

import copy
import hashlib
import json
import os
import secrets
import threading
from dataclasses import replace
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from .. import KIT_ROOT, import_from_kit
from ..errors import KitError
from ..stages import get_stage
from .spec import VARIANT_MODULES, Case, Test, jsonable

MANIFEST = "public.json"


def spec_dir(stage: str) -> Path:
    """A stage's autograder folder, ``autograder/<stage>/``: its spec modules or manifest, and hidden.json."""
    return KIT_ROOT / "autograder" / stage


def _load_spec_module(stage: str, name: str) -> ModuleType | None:
    """Import autograder/<stage>/<name>.py in the grader's process (specs import each other as ``autograder.*``)."""
    if not (spec_dir(stage) / f"{name}.py").exists():
        return None
    return import_from_kit(f"autograder.{stage}.{name}")


def _declared(stage: str, include_hidden: bool) -> list[Test]:
    public = _load_spec_module(stage, "public")
    if public is not None:
        tests = [replace(t, hidden=False) for t in public.TESTS]
        hidden = _load_spec_module(stage, "hidden") if include_hidden else None
        if hidden is not None:
            tests += [replace(t, hidden=True) for t in hidden.TESTS]
        return tests
    manifest = spec_dir(stage) / MANIFEST
    if manifest.exists():
        return [Test.from_json(t) for t in json.loads(manifest.read_text())["tests"]]
    raise KitError(f"no autograder tests for stage {stage!r} (expected autograder/{stage}/public.py or {MANIFEST})")


#: The file in the answer cache holding the kit's secret for fresh cases (private to the grader's user).
SECRET_FILE = "variant-secret"


def variant_secret(cache_dir: Path | None = None) -> str:
    """The kit's secret for fresh cases: made once, at random, in the answer cache (mode 0600), which no
    submission can read; ``setup.sh`` of a Gradescope zip makes a new one for every image it builds."""
    from .expected import cache_root
    path = cache_root(cache_dir) / SECRET_FILE
    if not path.exists():   # written whole, then linked into place: a roster's graders may all start at once
        tmp = path.with_name(f"{SECRET_FILE}.{os.getpid()}.{threading.get_ident()}.tmp")
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
        with os.fdopen(fd, "w") as f:
            f.write(secrets.token_hex(32) + "\n")
        try:
            os.link(tmp, path)
        except FileExistsError:
            pass
        finally:
            tmp.unlink()
    text = path.read_text().strip()
    if len(text) < 32:
        raise KitError(f"{path}: not a secret this kit made (delete it to make a new one)")
    return text


def fresh_case(stage: str, test: Test, secret: str) -> Test:
    """``test`` on its variant's fresh case, drawn from ``secret``, the stage and the test's name (stable per secret)."""
    seed = hashlib.sha256(f"{secret}\0{stage}\0{test.task}\0{test.name}".encode()).digest()
    fn = test.vary.resolve(VARIANT_MODULES)
    case = fn(copy.deepcopy(test.params), np.random.default_rng(int.from_bytes(seed[:8], "little")), **test.vary.kwargs)
    if not isinstance(case, Case):
        raise KitError(f"{test.vary.module}.{test.vary.name}: returned {type(case).__name__}, not a Case")
    params = json.loads(json.dumps(jsonable(case.params)))   # as the worker will read them back
    if params == test.params:
        raise KitError(f"{test.name}: its variant {test.vary.name} made the shipped case again")
    return replace(test, params=params, check=case.check or test.check,
                   name=f"{test.name}; graded on a fresh case of this kind: {case.describe}")


def load_tests(stage: str, include_hidden: bool = True, secret: str | None = None) -> list[Test]:
    """The stage's tests in rubric order, numbered per task (S1.1, S1.2, …).

    ``secret``: grade the public tests on their fresh cases (:func:`fresh_case`) instead of the shipped ones.
    """
    tests = _declared(stage, include_hidden)
    if secret is not None:
        tests = [fresh_case(stage, t, secret) if not t.hidden and t.vary is not None else t for t in tests]
    order = [t.id for t in get_stage(stage).tasks]
    unknown = sorted({t.task for t in tests} - set(order))
    if unknown:
        raise KitError(f"autograder/{stage}: tests name unknown tasks {unknown}")
    tests.sort(key=lambda t: (order.index(t.task), t.hidden))
    optional = {t.id for t in get_stage(stage).tasks if t.optional}
    counts: dict[str, int] = {}
    numbered = []
    for t in tests:
        counts[t.task] = counts.get(t.task, 0) + 1
        numbered.append(replace(t, number=f"{t.task}.{counts[t.task]}", extension=t.task in optional))
    return numbered


def hidden_summary(stage: str) -> dict[str, Any]:
    """How many hidden tests there are and what they are worth, without what they check.

    From hidden.py where it exists (the instructor's copy), else from the summary
    a student copy ships (``autograder/<stage>/hidden.json``, written by ``cs451 release``).
    """
    hidden = _load_spec_module(stage, "hidden")
    if hidden is not None:
        by_task: dict[str, float] = {}
        for t in hidden.TESTS:
            by_task[t.task] = by_task.get(t.task, 0.0) + t.points
        return {"count": len(hidden.TESTS), "points": sum(by_task.values()), "by_task": by_task}
    path = spec_dir(stage) / "hidden.json"
    if path.exists():
        return json.loads(path.read_text())
    return {"count": 0, "points": 0.0, "by_task": {}}


def write_manifest(stage: str, tests: list[Test], dest: Path) -> Path:
    """The public tests as data, for a student copy (checks by name, truths only as keys)."""
    path = dest / MANIFEST
    path.write_text(json.dumps({"stage": stage, "tests": [t.to_json() for t in tests if not t.hidden]}, indent=1) + "\n")
    return path
