"""What a test's answer is compared with: the reference's answers and the truths' arrays, each cached on disk.

In the instructor's kit, the reference answers a probe in a trusted worker and a
truth function is evaluated in the grader; both are kept in ``.cs451-cache/``,
keyed by what produced them, so a class of hundreds renders each reference image
once. In a student copy neither the reference nor the truths exist: their answers
to the public tests ship as arrays in ``autograder/<stage>/answers/`` (written by
``cs451 release``), under the same file names.
"""
from __future__ import annotations

import hashlib
import json
import os
import threading
from pathlib import Path
from typing import Any

import numpy as np

from .. import ENGINE_DIR, KIT_ROOT, instructor_only
from ..caches import cache_home
from ..errors import KitError
from .probes import run_trusted_probe
from .spec import TRUTH_MODULES, Outputs, Ref, Test


def tree_hash(*folders: Path) -> str:
    """A version of the code that produces answers; independent of where the tree lives, so answers
    computed when an autograder is built stay valid where it is unpacked."""
    h = hashlib.sha256()
    for folder in folders:
        for path in sorted(folder.rglob("*.py")):      # no answer comes from the slides or a deck's figures
            if "__pycache__" not in path.parts and not instructor_only(path):
                h.update(path.relative_to(folder).as_posix().encode())
                h.update(path.read_bytes())
    return h.hexdigest()[:16]


def answer_key(probe: str, params: dict[str, Any], inputs: Outputs | None = None) -> str:
    """The file name of the reference's answer to a probe: the same in the cache and in a student copy."""
    key = hashlib.sha256(json.dumps([probe, params, sorted(inputs or {})], sort_keys=True).encode()).hexdigest()[:20]
    return f"{probe}-{key}.npz"


def truth_key(ref: Ref, params: dict[str, Any]) -> str:
    """The file name of a truth's arrays for these parameters."""
    key = hashlib.sha256(json.dumps([ref.module, ref.name, ref.kwargs, params], sort_keys=True).encode()).hexdigest()[:20]
    return f"truth-{ref.name}-{key}.npz"


def packaged_answers_dir(stage: str) -> Path:
    """Where a student copy (without reference/) keeps the answers to the public tests."""
    return KIT_ROOT / "autograder" / stage / "answers"


def is_student_copy(stage: str) -> bool:
    """A copy made by ``cs451 release``: no reference of this stage, no hidden tests, packaged answers."""
    return not (KIT_ROOT / "reference" / stage).is_dir() and packaged_answers_dir(stage).is_dir()


def cache_root(cache_dir: Path | None = None) -> Path:
    """The answer cache, private to the grader's user (no submission may read or replace an answer): the kit's
    ``.cs451-cache``, or the user's cache folder where the kit cannot be written (a read-only install), which
    the sandbox then hides too (:func:`.runner.protected_paths`)."""
    if cache_dir is not None:
        cache_dir.mkdir(mode=0o700, exist_ok=True)
        return cache_dir
    root = cache_home()
    root.mkdir(mode=0o700, parents=True, exist_ok=True)
    if root != KIT_ROOT / ".cs451-cache" and root.stat().st_mode & 0o077:   # made earlier by another cache's user
        root.chmod(0o700)
    return root


def _load(path: Path) -> Outputs:
    with np.load(path, allow_pickle=False) as data:
        return {k: data[k] for k in data.files}


def _store(path: Path, arrays: Outputs) -> None:
    """Write atomically, through a temporary file of this process's own: the workers of a roster may compute and
    store the same answer at once, and a shared temporary name let one move the other's half-written file."""
    tmp = path.with_name(f"{path.stem}.{os.getpid()}.{threading.get_ident()}.tmp.npz")
    try:
        np.savez(tmp, **arrays)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


class ReferenceAnswers:
    """The reference's answers to probes, computed once in a trusted worker and kept on disk."""

    def __init__(self, stage: str, cache_dir: Path | None = None):
        self.stage = stage
        if is_student_copy(stage):
            self.impl, self.dir = None, packaged_answers_dir(stage)
            return
        from ..impl import resolve_impl
        self.impl = resolve_impl("reference", stage)
        version = tree_hash(self.impl, ENGINE_DIR)
        self.dir = cache_root(cache_dir) / "reference" / stage / version
        self.dir.mkdir(parents=True, exist_ok=True)

    def path(self, probe: str, params: dict[str, Any], inputs: Outputs | None = None) -> Path:
        """Where the reference's answer to this probe lies (or will), in the cache or a student copy's answers."""
        return self.dir / answer_key(probe, params, inputs)

    def get(self, probe: str, params: dict[str, Any], inputs: Outputs | None = None) -> Outputs:
        """The reference's answer to a probe: from disk, or computed once in a trusted worker and stored (the grader
        compares every submission with it); a student copy without it raises KitError."""
        path = self.path(probe, params, inputs)
        if path.exists():
            return _load(path)
        if self.impl is None:
            raise KitError(f"this copy of the kit has no reference answer for probe {probe!r} "
                           f"(its answers in {self.dir} are older than the test; ask for an updated copy)")
        result = run_trusted_probe(self.stage, self.impl, probe, params, inputs, timeout=300)
        if not result.ok:
            raise KitError(f"the reference failed on probe {probe} {params}: {result.error}\n{result.output}")
        _store(path, result.outputs)
        return result.outputs


def _as_arrays(value: Any) -> Outputs:
    if isinstance(value, dict):
        return {k: np.asarray(v) for k, v in value.items()}
    return {"value": np.asarray(value)}


class TruthValues:
    """Truths' arrays for tests' parameters: evaluated here in the kit (and cached), read from disk in a student copy."""

    def __init__(self, stage: str, cache_dir: Path | None = None):
        self.stage = stage
        if is_student_copy(stage):
            self.live, self.dir = False, packaged_answers_dir(stage)
            return
        self.live = True
        version = tree_hash(KIT_ROOT / "autograder", ENGINE_DIR)
        self.dir = cache_root(cache_dir) / "truth" / stage / version
        self.dir.mkdir(parents=True, exist_ok=True)

    def path(self, test: Test) -> Path:
        """Where a test's truth arrays lie (or will), in the cache or a student copy's packaged answers."""
        assert test.truth is not None
        return self.dir / truth_key(test.truth, test.params)

    def get(self, test: Test) -> Outputs:
        """A test's truth arrays: from disk, or its truth function evaluated here once and stored (a student copy only
        reads them, and raises KitError where one is missing)."""
        path = self.path(test)
        if path.exists():
            return _load(path)
        if not self.live:
            raise KitError(f"this copy of the kit has no truth for test {test.name!r} (ask for an updated copy)")
        fn = test.truth.resolve(TRUTH_MODULES)   # imports autograder.<stage>.truth from KIT_ROOT
        arrays = _as_arrays(fn(test.params, **test.truth.kwargs))
        _store(path, arrays)
        return arrays


def expected_for(test: Test, reference: ReferenceAnswers, truths: TruthValues) -> tuple[Outputs | None, Outputs]:
    """(trusted inputs for the probe, what the check compares with) for one test."""
    given = reference.get(test.given, test.params) if test.given else None
    expected: Outputs = {}
    if test.expected == "reference":
        expected.update(reference.get(test.probe, test.params, given))
    if test.truth is not None:
        arrays = truths.get(test)
        clash = set(arrays) & set(expected)
        if clash:
            raise KitError(f"{test.name}: the truth and the reference both answer {sorted(clash)}")
        expected.update(arrays)
    return given, expected
