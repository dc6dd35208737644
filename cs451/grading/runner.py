"""The grader side: run each test's probe on the submission in a subprocess and judge what comes back.

Student code never runs in this process. The truth for a test comes from a
closed form or library in the spec, or from the reference running the same
probe (in a worker too, cached on disk so a class of hundreds renders each
reference image once).
"""
from __future__ import annotations

import hashlib
import importlib
import json
import os
import signal
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from .. import KIT_ROOT
from ..errors import KitError
from ..impl import resolve_impl
from ..progress import Progress
from ..stages import get_stage
from . import sandbox
from .spec import Outputs, Test, Verdict

@dataclass
class ProbeResult:
    ok: bool
    outputs: Outputs
    error: str
    output: str
    seconds: float


def _read_outputs(job: Path) -> tuple[bool, Outputs, str]:
    """Read the worker's answer as untrusted data: JSON status, arrays without pickles."""
    try:
        status = json.loads((job / "status.json").read_text())
        ok, error = bool(status.get("ok")), str(status.get("error", ""))[:2000]
    except (OSError, ValueError, AttributeError):
        return False, {}, "the submission stopped before finishing this test (it crashed, exited or was killed)"
    if not ok:
        return False, {}, error
    try:
        with np.load(job / "output.npz", allow_pickle=False) as data:
            return True, {k: data[k] for k in data.files}, ""
    except Exception as err:  # a corrupt or forged file is the submission's failure, not the grader's
        return False, {}, f"the answer could not be read ({type(err).__name__})"


def run_probe(stage: str, impl_dir: Path, probe: str, params: dict[str, Any],
              inputs: Outputs | None = None, timeout: float = 60.0, trusted: bool = False,
              drop_privileges: bool = True) -> ProbeResult:
    """Run one probe on an implementation in a fresh sandboxed subprocess (see :mod:`.sandbox`)."""
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="cs451-") as tmp:
        job = Path(tmp) / "job"
        job.mkdir()
        (job / "request.json").write_text(json.dumps({"stage": stage, "impl": str(impl_dir), "probe": probe,
                                                      "params": params}))
        if inputs:
            np.savez(job / "inputs.npz", **inputs)
        done = sandbox.run_untrusted([sys.executable, "-m", "cs451.grading.worker", str(job)], job,
                                     sandbox.Limits(wall_seconds=timeout), trusted=trusted,
                                     drop_privileges=drop_privileges)
        seconds = time.perf_counter() - start
        if done.timed_out:
            return ProbeResult(False, {}, f"took longer than the {timeout:g} s limit (an infinite loop?)", done.output, seconds)
        ok, outputs, error = _read_outputs(job)
        if not ok and done.returncode is not None and done.returncode < 0:
            sig = signal.Signals(-done.returncode).name
            reason = {"SIGXCPU": "it used more CPU time than allowed", "SIGXFSZ": "it wrote more output than allowed",
                      "SIGKILL": "it was killed (out of memory?)", "SIGSEGV": "it crashed (segmentation fault)"}
            error = f"the submission stopped: {reason.get(sig, sig)}"
        elif not ok and "MemoryError" in error:
            error += f" (the limit is {sandbox.MEMORY_LIMIT >> 30} GiB)"
        return ProbeResult(ok, outputs, error or "failed without a message", done.output, seconds)


# --- reference answers, cached ------------------------------------------------

def _tree_hash(*folders: Path) -> str:
    """A version of the code that answers probes; independent of where the tree lives, so answers
    computed when an autograder is built stay valid where it is unpacked."""
    h = hashlib.sha256()
    for folder in folders:
        for path in sorted(folder.rglob("*.py")):
            if "__pycache__" not in path.parts:
                h.update(path.relative_to(folder).as_posix().encode())
                h.update(path.read_bytes())
    return h.hexdigest()[:16]


def answer_key(probe: str, params: dict[str, Any], inputs: Outputs | None = None) -> str:
    """The file name of the answer to a probe: the same in the cache and in a student copy's packaged answers."""
    key = hashlib.sha256(json.dumps([probe, params, sorted(inputs or {})], sort_keys=True).encode()).hexdigest()[:20]
    return f"{probe}-{key}.npz"


def packaged_answers_dir(stage: str) -> Path:
    """Where a student copy (without reference/) keeps the reference's answers to the public tests."""
    return KIT_ROOT / "autograder" / stage / "answers"


class ReferenceAnswers:
    """The reference's answers to probes, computed once in a worker and kept on disk.

    In a student copy there is no reference/: the answers to the public tests ship
    in ``autograder/<stage>/answers/`` instead (written by ``cs451 release``).
    """

    def __init__(self, stage: str, cache_dir: Path | None = None):
        self.stage = stage
        if not (KIT_ROOT / "reference" / stage).is_dir() and packaged_answers_dir(stage).is_dir():
            self.impl = None
            self.dir = packaged_answers_dir(stage)
            return
        self.impl = resolve_impl("reference", stage)
        version = _tree_hash(self.impl, KIT_ROOT / "cs451")
        self.dir = (cache_dir or KIT_ROOT / ".cs451-cache") / "reference" / stage / version
        self.dir.mkdir(parents=True, exist_ok=True)

    def path(self, probe: str, params: dict[str, Any], inputs: Outputs | None = None) -> Path:
        return self.dir / answer_key(probe, params, inputs)

    def get(self, probe: str, params: dict[str, Any], inputs: Outputs | None = None) -> Outputs:
        path = self.path(probe, params, inputs)
        if path.exists():
            with np.load(path, allow_pickle=False) as data:
                return {k: data[k] for k in data.files}
        if self.impl is None:
            raise KitError(f"this copy of the kit has no reference answer for probe {probe!r} "
                           f"(its answers in {self.dir} are older than the test; ask for an updated copy)")
        result = run_probe(self.stage, self.impl, probe, params, inputs, timeout=300, trusted=True)
        if not result.ok:
            raise KitError(f"the reference failed on probe {probe} {params}: {result.error}\n{result.output}")
        np.savez(path.with_suffix(".tmp.npz"), **result.outputs)
        os.replace(path.with_suffix(".tmp.npz"), path)
        return result.outputs


# --- loading specs --------------------------------------------------------------

def _load_spec_module(stage: str, name: str) -> ModuleType | None:
    """Import autograder/<stage>/<name>.py in the grader's process (specs import each other as ``autograder.*``)."""
    if not (KIT_ROOT / "autograder" / stage / f"{name}.py").exists():
        return None
    if str(KIT_ROOT) not in sys.path:
        sys.path.insert(0, str(KIT_ROOT))
    return importlib.import_module(f"autograder.{stage}.{name}")


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
    path = KIT_ROOT / "autograder" / stage / "hidden.json"
    if path.exists():
        return json.loads(path.read_text())
    return {"count": 0, "points": 0.0, "by_task": {}}


def load_tests(stage: str, include_hidden: bool = True) -> list[Test]:
    """The stage's tests in rubric order, numbered per task (S1.1, S1.2, …)."""
    public = _load_spec_module(stage, "public")
    if public is None:
        raise KitError(f"no autograder tests for stage {stage!r} (expected autograder/{stage}/public.py)")
    tests = list(public.TESTS)
    hidden = _load_spec_module(stage, "hidden") if include_hidden else None
    if hidden is not None:
        tests += [t for t in hidden.TESTS]
    order = [t.id for t in get_stage(stage).tasks]
    tests.sort(key=lambda t: (order.index(t.task), t.hidden))
    counts: dict[str, int] = {}
    numbered = []
    for t in tests:
        counts[t.task] = counts.get(t.task, 0) + 1
        numbered.append(Test(**{**t.__dict__, "number": f"{t.task}.{counts[t.task]}"}))
    return numbered


# --- grading ------------------------------------------------------------------------

@dataclass
class TestResult:
    test: Test
    score: float
    verdict: Verdict
    output: str = ""
    seconds: float = 0.0


@dataclass
class GradeResult:
    stage: str
    submission: str
    results: list[TestResult] = field(default_factory=list)
    problems: list[str] = field(default_factory=list)   # interface problems found before the tests ran
    seconds: float = 0.0
    isolation: str = ""                                  # how the submission was isolated, for the report
    hidden_not_run: dict[str, Any] = field(default_factory=dict)  # hidden_summary() when only public tests ran

    @property
    def score(self) -> float:
        return sum(r.score for r in self.results)

    @property
    def max_score(self) -> float:
        return sum(r.test.points for r in self.results)


def _run_test(test: Test, stage: str, impl_dir: Path, reference: ReferenceAnswers, drop: bool,
              deadline: float) -> TestResult:
    remaining = deadline - time.perf_counter()
    if remaining <= 1:
        return TestResult(test, 0.0, Verdict(0.0, "not run: the time limit for the whole submission was reached"))
    try:
        given = reference.get(test.given, test.params) if test.given else None
        expected = reference.get(test.probe, test.params, given) if test.expected == "reference" else None
    except KitError as err:
        return TestResult(test, 0.0, Verdict(0.0, f"grader error, not your fault: {err}"))
    result = run_probe(stage, impl_dir, test.probe, test.params, given, timeout=min(test.timeout, remaining),
                       drop_privileges=drop)
    if not result.ok:
        return TestResult(test, 0.0, Verdict(0.0, result.error), result.output, result.seconds)
    try:
        verdict = test.check(result.outputs, expected, test.params)
    except Exception as err:  # a malformed answer the check did not foresee is the submission's, not a crash
        verdict = Verdict(0.0, f"the answer has the wrong form ({type(err).__name__}: {err})")
    fraction = min(max(float(np.nan_to_num(verdict.fraction)), 0.0), 1.0)
    return TestResult(test, round(test.points * fraction, 4), verdict, result.output, result.seconds)


def grade(stage: str, submission: str | Path, include_hidden: bool = True, show_progress: bool = True,
          jobs: int | None = None, total_timeout: float = 600.0, tasks: list[str] | None = None,
          test_timeout: float | None = None) -> GradeResult:
    """Grade one submission of a stage; never raises for anything the submission does.

    ``tasks`` keeps only those tasks' tests; ``test_timeout`` overrides every test's time limit.
    """
    start = time.perf_counter()
    deadline = start + total_timeout
    get_stage(stage)
    tests = [t for t in load_tests(stage, include_hidden) if tasks is None or t.task in tasks]
    if test_timeout is not None:
        tests = [Test(**{**t.__dict__, "timeout": test_timeout}) for t in tests]
    impl_dir = resolve_impl(submission, stage)
    out = GradeResult(stage, str(submission))
    if not include_hidden:
        out.hidden_not_run = hidden_summary(stage)
    reference = ReferenceAnswers(stage)
    problem = sandbox.isolation_problem(impl_dir)
    if impl_dir.resolve().is_relative_to((KIT_ROOT / "reference").resolve()):
        problem = "grading the reference itself, a self-test: the files it would be locked out of are its own"
    drop = sandbox.is_root() and problem is None
    if drop:  # the worker's user must not read the reference, the hidden tests or the cached answers
        sandbox.protect(KIT_ROOT / "reference", KIT_ROOT / "autograder", reference.dir.parent.parent)
        out.isolation = f"each test in a subprocess as '{sandbox.UNPRIVILEGED_USER}', with time, memory, CPU, file and process limits"
    elif problem:
        out.isolation = f"each test in a subprocess with limits, as the grader's user ({problem})"
    else:
        out.isolation = "each test in a subprocess with time, memory, CPU, file and process limits"
    probe = run_probe(stage, impl_dir, "__interface__", {}, timeout=60, drop_privileges=drop)
    if not probe.ok:  # the submission does not even import: every test gets the same reason
        out.problems = [probe.error]
        out.results = [TestResult(t, 0.0, Verdict(0.0, f"not run: {probe.error}"), probe.output) for t in tests]
        out.seconds = time.perf_counter() - start
        return out
    out.problems = [str(p) for p in probe.outputs.get("problems", [])]
    bar = Progress(f"grading {stage}", len(tests)) if show_progress else None
    results: dict[int, TestResult] = {}
    with ThreadPoolExecutor(max_workers=jobs or min(2, os.cpu_count() or 1)) as pool:
        futures = {pool.submit(_run_test, t, stage, impl_dir, reference, drop, deadline): i
                   for i, t in enumerate(tests)}
        for future in futures:
            results[futures[future]] = future.result()
            if bar:
                bar.advance(note=tests[futures[future]].number)
    if bar:
        bar.close()
    out.results = [results[i] for i in range(len(tests))]
    out.seconds = time.perf_counter() - start
    return out
