"""The grader side: run each test's probe on the submission in the sandbox and judge what comes back.

Student code never runs in this process. A submission is first copied as
hostile data (:mod:`.staging`), then every test runs in a fresh worker inside
one :class:`~.sandbox.Sandbox`; what the worker leaves is read as hostile data
(:mod:`.untrusted`), and each check runs with its own time and memory limit
(:mod:`.guard`), so a bad answer fails its test and never the run. The truth for
a test comes from the reference running the same probe (cached), from a truth
function, or both (:mod:`.expected`).
"""
from __future__ import annotations

import itertools
import os
import time
from concurrent.futures import Future, ThreadPoolExecutor, as_completed
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Iterator

import numpy as np

from .. import ENGINE_DIR, KIT_ROOT, instructor_paths
from ..caches import cache_home
from ..errors import KitError, SubmissionError
from ..impl import resolve_impl
from ..progress import Progress
from ..stages import get_stage
from . import sandbox
from .expected import ReferenceAnswers, TruthValues, expected_for, is_student_copy
from .probes import ProbeResult, interpret, run_trusted_probe, write_request
from .checks import target_images
from .guard import CheckFailed, GuardError, run_guarded
from .loader import hidden_summary, load_tests, variant_secret
from .spec import CHECK_MODULES, Outputs, Test, Verdict

#: The word that grades the kit's own reference without the sandbox; no path, however it resolves, does.
TRUSTED = "reference"


class _SandboxedProbes:
    """Probes on a staged submission, one fresh worker per call."""

    def __init__(self, box: sandbox.Sandbox, stage: str, impl: str):
        self.box, self.stage, self.impl = box, stage, impl

    def run(self, probe: str, params: dict[str, Any], inputs: Outputs | None, timeout: float) -> ProbeResult:
        start = time.perf_counter()
        job = self.box.new_job()
        try:
            write_request(job, self.stage, self.impl, probe, params, inputs)
            done = self.box.run(self.box.worker_args(job), job, sandbox.Limits(wall_seconds=timeout))
            return interpret(done, job, timeout, time.perf_counter() - start, self.box.submission_memory)
        finally:
            self.box.finish_job(job)


class _TrustedProbes:
    def __init__(self, stage: str, impl: Path):
        self.stage, self.impl = stage, impl

    def run(self, probe: str, params: dict[str, Any], inputs: Outputs | None, timeout: float) -> ProbeResult:
        return run_trusted_probe(self.stage, self.impl, probe, params, inputs, timeout)


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
    def graded(self) -> list[TestResult]:
        """The tests that make the grade: every test but those of optional extensions."""
        return [r for r in self.results if not r.test.extension]

    @property
    def extensions(self) -> list[TestResult]:
        """The tests of optional extensions: reported and scored apart, never part of the grade."""
        return [r for r in self.results if r.test.extension]

    @property
    def score(self) -> float:
        """The grade: the points earned on the graded tests, hidden ones included, extensions not."""
        return sum(r.score for r in self.graded)

    @property
    def max_score(self) -> float:
        """What the graded tests are worth together, hidden ones included, extensions not."""
        return sum(r.test.points for r in self.graded)

    @property
    def extension_score(self) -> float:
        """The points earned on optional extensions, reported beside the grade."""
        return sum(r.score for r in self.extensions)

    @property
    def extension_max(self) -> float:
        """What the optional extensions' tests are worth together."""
        return sum(r.test.points for r in self.extensions)


def _judge(test: Test, outputs: Outputs, expected: Outputs) -> Verdict:
    """In the guarded child: the test's check on the answer."""
    return test.check.resolve(CHECK_MODULES)(outputs, expected, test.params, **test.check.kwargs)


def _verdict(test: Test, result: ProbeResult, expected: Outputs) -> Verdict:
    try:
        verdict = run_guarded(_judge, test, result.outputs, expected)
    except CheckFailed as err:  # a malformed answer the check did not foresee is the submission's, not a crash
        verdict = Verdict(0.0, f"the answer has the wrong form ({err})")
    except GuardError as err:
        verdict = Verdict(0.0, f"the answer could not be checked: {err}")
    if not isinstance(verdict, Verdict):
        raise KitError(f"{test.name}: its check returned {type(verdict).__name__}, not a Verdict")
    return verdict


def _score(test: Test, verdict: Verdict) -> float:
    fraction = min(max(float(np.nan_to_num(verdict.fraction)), 0.0), 1.0)
    return round(test.points * fraction, 4)


def protected_paths(extra: tuple[Path, ...] = ()) -> list[Path]:
    """What no submission may read: the kit's reference, specs, tests, history and cached answers, the engine's
    instructors-only parts (every stage's benchmarks, deck figures and speed layer: they would answer tasks), and
    ``extra``."""
    names = ("reference", "autograder", "starter", "tests", "bench", ".git", ".cs451-cache", "assignments")
    cache = cache_home()   # the user's, where the kit cannot be written: the answers are there then
    return ([KIT_ROOT / n for n in names] + ([cache] if cache != KIT_ROOT / ".cs451-cache" else []) + instructor_paths()
            + list(extra))


def engine_sources(stage: str) -> list[tuple[Path, str]]:
    """What the worker imports: the engine alone, for every stage. No stage's code enters a sandbox: a stage that
    builds on an earlier one (radiosity on the hemicube) gets that stage's results from the reference as arrays
    (its tests' ``given``: form factors, camera views), computed outside and cached with the reference's answers."""
    get_stage(stage)
    return [(ENGINE_DIR, "cs451")]


def _problems(outputs: Outputs) -> list[str]:
    raw = outputs.get("problems")
    if raw is None:
        return []
    arr = np.asarray(raw)
    if arr.dtype.kind != "U" or arr.ndim != 1:
        return ["the submission's interface could not be read"]
    return [str(p)[:300] for p in arr[:50]]


def grade(stage: str, submission: str | Path, include_hidden: bool = True, show_progress: bool = True,
          jobs: int | None = None, total_timeout: float = 600.0, tasks: list[str] | None = None,
          test_timeout: float | None = None, protected: tuple[Path, ...] = (), unwritable: tuple[Path, ...] = (),
          submission_memory: int | None = None, fresh: bool | None = None) -> GradeResult:
    """Grade one submission of a stage: what its code does (wrong answers, crashes, hangs, attacks) costs points.

    ``submission``: the word ``reference`` (the kit's own, trusted), ``starter``, or a folder;
    ``tasks`` keeps only those tasks' tests; ``test_timeout`` overrides every test's time limit;
    ``protected`` adds paths the sandbox must hide (a roster's other submissions, its output),
    ``unwritable`` folders it must not write in (Gradescope's results).
    ``fresh``: grade the public tests on fresh cases from the kit's secret (default: whenever the hidden tests
    are graded in the instructor's kit; a student copy, or ``include_hidden=False``, keeps the shipped cases).
    Raises ``SubmissionError`` (a ``KitError``) when the upload holds no gradable package (none, too large, not a
    folder: the student can fix it) and ``KitError`` when it cannot be isolated here; in both cases none of its
    code has run.
    """
    start = time.perf_counter()
    # drawn from the start (within a second), not once the tests, answers and sandbox are ready: they take seconds
    bar = Progress(f"grading {stage}", 1) if show_progress else None
    try:
        get_stage(stage)
        if fresh is None:
            fresh = include_hidden and not is_student_copy(stage)
        secret = variant_secret() if fresh else None
        tests = [t for t in load_tests(stage, include_hidden, secret) if tasks is None or t.task in tasks]
        if test_timeout is not None:
            tests = [replace(t, timeout=test_timeout) for t in tests]
        if bar:
            bar.set_total(len(tests))
        return _grade(GradeResult(stage, str(submission)), stage, submission, tests, bar, start, total_timeout, jobs,
                      include_hidden, protected, unwritable, submission_memory)
    finally:
        if bar:
            bar.close()


def _grade(out: GradeResult, stage: str, submission: str | Path, tests: list[Test], bar: "Progress | None",
           start: float, total_timeout: float, jobs: int | None, include_hidden: bool, protected: tuple[Path, ...],
           unwritable: tuple[Path, ...], submission_memory: int | None) -> GradeResult:
    """:func:`grade` once its tests are chosen: the trusted reference in plain subprocesses, anything else in the
    sandbox."""
    if not include_hidden or is_student_copy(stage):  # a student copy has no hidden tests to run: say so
        out.hidden_not_run = hidden_summary(stage)
    reference = ReferenceAnswers(stage)
    truths = TruthValues(stage)
    if str(submission) == TRUSTED:
        out.isolation = "the kit's own reference (trusted): each test in a plain subprocess with limits"
        probes = _TrustedProbes(stage, resolve_impl(TRUSTED, stage))
        _grade_tests(out, tests, probes, reference, truths, start + total_timeout, jobs, bar)
        out.seconds = time.perf_counter() - start
        return out
    upload = KIT_ROOT / "starter" if str(submission) == "starter" else Path(submission).expanduser()
    box = sandbox.Sandbox(stage, upload, engine_sources(stage), protected_paths(tuple(protected)),
                          unwritable=[Path(p) for p in unwritable], student_copy=is_student_copy(stage),
                          submission_memory=submission_memory or sandbox.SUBMISSION_MEMORY)
    with box:
        staged_root = box.run_dir / "upload"
        try:
            impl = resolve_impl(staged_root, stage)
        except SubmissionError as err:
            skipped = f" ({box.staged.note()})" if box.staged.note() else ""
            raise SubmissionError(str(err).replace(str(staged_root), str(upload)) + skipped) from None
        out.isolation = box.describe()
        if box.staged.note():
            out.problems.append(box.staged.note())
        probes = _SandboxedProbes(box, stage, box.visible(impl))
        _grade_tests(out, tests, probes, reference, truths, start + total_timeout,
                     jobs if box.parallel else 1, bar)
    out.seconds = time.perf_counter() - start
    return out


def _grade_tests(out: GradeResult, tests: list[Test], probes: Any, reference: ReferenceAnswers, truths: TruthValues,
                 deadline: float, jobs: int | None, bar: "Progress | None") -> None:
    """The interface probe, then every test: workers in parallel threads, checks here, one at a time."""
    probe = probes.run("__interface__", {}, None, 60.0)
    if not probe.ok:  # the submission does not even import: every test gets the same reason
        out.problems.append(probe.error)
        out.results = [TestResult(t, 0.0, Verdict(0.0, f"not run: {probe.error}"), probe.output) for t in tests]
        return
    out.problems += _problems(probe.outputs)
    prepared: dict[int, tuple[Outputs | None, Outputs] | TestResult] = {}
    if bar:
        bar.advance(0, note="the reference's answers")
    for i, t in enumerate(tests):  # trusted answers first: the reference's runs are not charged to the submission
        try:
            prepared[i] = expected_for(t, reference, truths)
        except KitError as err:
            prepared[i] = TestResult(t, 0.0, Verdict(0.0, f"grader error, not your fault: {err}"))

    def work(i: int) -> ProbeResult | TestResult:
        if isinstance(prepared[i], TestResult):
            return prepared[i]
        remaining = deadline - time.perf_counter()
        if remaining <= 1:
            return TestResult(tests[i], 0.0, Verdict(0.0, "not run: the time limit for the whole submission was reached"))
        return probes.run(tests[i].probe, tests[i].params, prepared[i][0], min(tests[i].timeout, remaining))

    results: dict[int, TestResult] = {}
    workers = max(1, jobs or min(2, os.cpu_count() or 1))
    with ThreadPoolExecutor(max_workers=workers) as pool:
        for future, i in _visible_then_hidden(pool, work, tests, workers):
            done = future.result()
            if isinstance(done, TestResult):
                results[i] = done
            elif not done.ok:
                target = target_images(prepared[i][1], tests[i].params)
                results[i] = TestResult(tests[i], 0.0, Verdict(0.0, done.error, target), done.output, done.seconds)
            else:
                verdict = _verdict(tests[i], done, prepared[i][1])
                results[i] = TestResult(tests[i], _score(tests[i], verdict), verdict, done.output, done.seconds)
                done.outputs = {}   # judged: the answer is let go before the next test starts
            if bar:
                bar.advance(note=tests[i].number)
    out.results = _name_failing_dependencies(out.stage, _edge_cases_need_the_main_tests([results[i] for i in range(len(tests))]))


def _visible_then_hidden(pool: ThreadPoolExecutor, work: Any, tests: list[Test], window: int
                         ) -> Iterator[tuple[Future, int]]:
    """Each test's finished run and its index: every visible test's, then the hidden tests' (started only once the
    visible ones have all ended), so no visible test runs after a hidden one and nothing a hidden test's parameters
    leave on the machine can reach what a student sees. At most ``window`` runs are started and not yet taken: a
    test starts only once the caller has judged an earlier one, so at most that many answers (each up to
    ``untrusted.ARRAYS_LIMIT``) are held at once, however fast the workers finish."""
    for hidden in (False, True):
        waiting = iter([i for i, t in enumerate(tests) if t.hidden == hidden])
        running = {pool.submit(work, i): i for i in itertools.islice(waiting, window)}
        while running:
            future = next(as_completed(running))
            yield future, running.pop(future)
            running.update({pool.submit(work, i): i for i in itertools.islice(waiting, 1)})


def _edge_cases_need_the_main_tests(results: list[TestResult]) -> list[TestResult]:
    """An edge case whose right answer is to do nothing (max_edge 0 keeps the quads) earns its points only
    when some other test of its task earns points: a submission that does nothing earns nothing. A visible
    edge case looks at visible tests only, so its score says nothing about a hidden one."""
    earning = {(r.test.task, r.test.hidden) for r in results if not r.test.edge_case and r.score > 0}
    out = []
    for r in results:
        seen = {(r.test.task, False)} | ({(r.test.task, True)} if r.test.hidden else set())
        if r.test.edge_case and r.score > 0 and not seen & earning:
            r = TestResult(r.test, 0.0, Verdict(0.0, f"{r.verdict.message}; but this edge case counts only once another "
                                                     f"{r.test.task} test passes"), r.output, r.seconds)
        out.append(r)
    return out


def _name_failing_dependencies(stage: str, results: list[TestResult]) -> list[TestResult]:
    """A test that lost points and runs the submission's own earlier functions (``depends_on``) says so, and
    which of those lose points in their own tests here: fix those first (the test may be right then). A visible
    test's note counts visible tests only, so it says nothing about a hidden one."""
    losing = {(r.test.task, r.test.hidden) for r in results if r.score < r.test.points}
    spec = get_stage(stage)
    out = []
    for r in results:
        deps = [d for d in r.test.depends_on if d != r.test.task]
        if deps and r.score < r.test.points:
            names = [f"{d} {spec.task(d).function}()" for d in deps]
            failing = [n for d, n in zip(deps, names) if (d, False) in losing or (r.test.hidden and (d, True) in losing)]
            if failing:
                note = (f"; this test relies on your own {_and(names)}, and {_and(failing)} "
                        f"{'loses' if len(failing) == 1 else 'lose'} points in {'its' if len(failing) == 1 else 'their'} "
                        f"own tests: fix {'that' if len(failing) == 1 else 'those'} first")
            else:
                note = f"; this test relies on your own {_and(names)}"
            r = TestResult(r.test, r.score, replace(r.verdict, message=r.verdict.message + note), r.output, r.seconds)
        out.append(r)
    return out


def _and(items: list[str]) -> str:
    return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " and " + items[-1]
