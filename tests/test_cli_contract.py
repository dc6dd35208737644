"""The command line's contract with its user: exit statuses (0 done, 1 a grade under the bar, 2 the user's mistake,
3 a bug in the kit), one line naming each mistake before any work starts, global options anywhere on the line,
help for every option, and progress shown within a second.

Grading is replaced by a made-up result where the test is about the command line, not the grade: these run in
seconds."""
from __future__ import annotations

import argparse
import io
import json
import sys
import time

import pytest

from cs451.cli import build_parser, main
from cs451.grading.runner import GradeResult, TestResult as Result
from cs451.grading.spec import Test as Spec, Verdict, check
from cs451.grading.checks import close_to
from cs451.stages import get_stage, stage_names

STAGE = stage_names()[0]
TASKS = [t.id for t in get_stage(STAGE).tasks]


@pytest.fixture(autouse=True)
def _loud_again():
    """``-q`` and ``-v`` are process-wide: each test starts and ends without them."""
    from cs451.progress import set_quiet, set_verbose
    yield
    set_quiet(False)
    set_verbose(False)


def run(argv: list[str], capsys) -> tuple[int, str, str]:
    """``cs451 ARGV`` in this process: its status (argparse's exits included), stdout and stderr."""
    try:
        code = main(argv)
    except SystemExit as exit_:
        code = exit_.code
    out = capsys.readouterr()
    return code, out.out, out.err


def one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err and "internal error" not in err, err
    return lines[0]


def graded(*fractions: float) -> GradeResult:
    """A made-up grade of ``STAGE``: one 10-point test of its first task per fraction earned."""
    specs = [Spec(f"test {i}", TASKS[0], 10.0, "render", {}, check(close_to, key="image"), "tol",
                  number=f"{TASKS[0]}.{i + 1}") for i in range(len(fractions))]
    return GradeResult(STAGE, "sub", [Result(t, 10.0 * f, Verdict(f, "ok" if f >= 1 else "wrong"))
                                      for t, f in zip(specs, fractions)], seconds=0.1, isolation="none (a test)")


@pytest.fixture
def fake_grade(monkeypatch):
    """Replace grading with a made-up result; ``calls`` says whether grading started."""
    import cs451.grading.runner as runner
    state = {"result": graded(1.0), "calls": 0}

    def grade(stage, submission, **_):
        state["calls"] += 1
        return state["result"]
    monkeypatch.setattr(runner, "grade", grade)
    return state


@pytest.fixture
def no_grading(monkeypatch):
    """Grading must not start: the command line is refused first."""
    import cs451.grading.runner as runner
    import cs451.packaging.gradescope as gradescope

    def never(*_, **__):
        raise AssertionError("the work started before the command line was checked")
    monkeypatch.setattr(runner, "grade", never)
    monkeypatch.setattr(gradescope, "build_gradescope", never)
    monkeypatch.setattr(gradescope, "run_gradescope", never)


# --- 1. exit statuses ------------------------------------------------------------------------------------------

def test_help_lists_the_exit_statuses(capsys):
    code, out, _ = run(["--help"], capsys)
    assert code == 0
    epilog = out[out.index("exit status:"):]
    for status, words in (("0", "success"), ("1", "--fail-under"), ("2", "mistake"), ("3", "bug in the kit")):
        assert f"  {status}  " in epilog and words in epilog, epilog
    assert "--roster" in epilog and "autograder run" in epilog


@pytest.mark.parametrize("fractions, argv, code", [
    ((1.0, 1.0), [], 0),                              # full marks
    ((1.0, 0.5), [], 1),                              # below full marks, the default bar
    ((1.0, 0.5), ["--fail-under", "75"], 0),          # 75 % reaches 75
    ((1.0, 0.4), ["--fail-under", "75"], 1),          # 70 % does not
    ((0.0, 0.0), ["--fail-under", "0"], 0),           # 0 never fails
])
def test_grade_exits_1_only_under_the_fail_under_bar(fractions, argv, code, fake_grade, capsys):
    fake_grade["result"] = graded(*fractions)
    got, out, err = run(["grade", STAGE, "--submission", "anything", *argv], capsys)
    assert got == code, (got, out, err)
    assert "total:" in out and fake_grade["calls"] == 1
    assert ("under --fail-under" in err) == (code == 1 and bool(argv)), err


def test_fail_under_takes_a_percentage_and_not_a_roster(capsys, no_grading, tmp_path):
    code, _, err = run(["grade", STAGE, "--fail-under", "101"], capsys)
    assert code == 2 and "argument --fail-under: must be a percentage from 0 to 100, got 101" in err
    code, _, err = run(["grade", STAGE, "--roster", str(tmp_path), "--fail-under", "50"], capsys)
    assert code == 2 and "--fail-under" in one_line(err) and "roster" in err
    help_text = build_parser()._subparsers._group_actions[0].choices["grade"].format_help()
    assert "exits 0" in help_text.replace("\n", " ").replace("  ", " ")


def test_autograder_run_still_exits_0_once_it_wrote_results(monkeypatch, capsys, tmp_path):
    import cs451.packaging.gradescope as gradescope
    monkeypatch.setattr(gradescope, "run_gradescope", lambda stage, submission, results, tasks=None: 0)
    assert run(["autograder", "run", STAGE, "--results", str(tmp_path / "r.json")], capsys)[0] == 0


# --- 1. where a command writes: checked before the work ----------------------------------------------------------

@pytest.mark.parametrize("option", ["--results", "--report"])
def test_an_output_under_a_file_is_refused_before_grading(option, tmp_path, no_grading, capsys):
    blocker = tmp_path / "file.txt"
    blocker.write_text("x")
    code, _, err = run(["grade", STAGE, option, str(blocker / "results.json")], capsys)
    assert code == 2 and one_line(err) == f"cs451: error: {option} {blocker / 'results.json'}: {blocker} is a file, " \
                                           "not a folder"


def test_results_into_a_folder_or_report_into_a_file_is_refused(tmp_path, no_grading, capsys):
    blocker = tmp_path / "file.txt"
    blocker.write_text("x")
    code, _, err = run(["grade", STAGE, "--results", str(tmp_path)], capsys)
    assert code == 2 and "is a folder; give a file name such as" in one_line(err)
    code, _, err = run(["grade", STAGE, "--report", str(blocker)], capsys)
    assert code == 2 and one_line(err) == f"cs451: error: --report {blocker}: is a file, not a folder"


def test_an_output_in_a_folder_that_takes_no_file_is_refused(tmp_path, no_grading, monkeypatch, capsys):
    """Root may write anywhere by its permission bits: /proc takes no new file even from root; a folder that refuses
    (a read-only mount, a non-root user's 0555) is made here by refusing the probe."""
    code, _, err = run(["grade", STAGE, "--results", "/proc/x/results.json"], capsys)
    assert code == 2 and one_line(err).startswith("cs451: error: --results /proc/x/results.json: the folder /proc "
                                                  "cannot be written (")
    import cs451.outputs

    def refuse(*_, **__):
        raise PermissionError(13, "Permission denied")
    monkeypatch.setattr(cs451.outputs.tempfile, "TemporaryFile", refuse)
    code, _, err = run(["grade", STAGE, "--report", str(tmp_path / "report")], capsys)
    assert code == 2 and one_line(err) == (f"cs451: error: --report {tmp_path / 'report'}: the folder {tmp_path} "
                                           "cannot be written (Permission denied)")


def test_a_missing_results_folder_is_made(tmp_path, fake_grade, capsys):
    target = tmp_path / "missing" / "deeper" / "results.json"
    code, out, err = run(["grade", STAGE, "--results", str(target)], capsys)
    assert code == 0 and json.loads(target.read_text())["tests"], err
    assert f"wrote {target}" in out


def test_autograder_build_into_a_place_it_cannot_write_is_refused(tmp_path, no_grading, capsys):
    blocker = tmp_path / "file.txt"
    blocker.write_text("x")
    code, _, err = run(["autograder", "build", STAGE, "-o", str(blocker / "a.zip")], capsys)
    assert code == 2 and one_line(err).endswith(f"{blocker} is a file, not a folder")
    code, _, err = run(["autograder", "build", STAGE, "-o", "/proc/a.zip"], capsys)
    assert code == 2 and "the folder /proc cannot be written" in one_line(err)


def test_bench_into_a_file_is_refused(tmp_path, monkeypatch, capsys):
    import cs451.bench
    monkeypatch.setattr(cs451.bench, "bench_module", lambda name: pytest.fail("the benchmark ran"))
    blocker = tmp_path / "file.txt"
    blocker.write_text("x")
    code, _, err = run(["bench", STAGE, "-o", str(blocker)], capsys)
    assert code == 2 and one_line(err) == f"cs451: error: -o {blocker}: is a file, not a folder"


def test_bench_without_matplotlib_is_refused_before_it_runs(tmp_path, monkeypatch, capsys):
    import cs451.bench
    monkeypatch.setitem(sys.modules, "matplotlib", None)          # `import matplotlib` now fails
    monkeypatch.setattr(cs451.bench, "bench_module", lambda name: pytest.fail("the benchmark ran"))
    start = time.perf_counter()
    code, _, err = run(["bench", STAGE, "-o", str(tmp_path / "out")], capsys)
    assert code == 2 and time.perf_counter() - start < 5
    assert "pip install 'cs451-kit[bench]'" in one_line(err) and "matplotlib" in err


def test_a_read_only_kit_keeps_its_answers_in_the_users_cache_privately(tmp_path, monkeypatch):
    import cs451.caches
    from cs451.grading.expected import cache_root
    from cs451.grading.runner import protected_paths
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    monkeypatch.setattr(cs451.caches.os, "access", lambda *_: False)   # the kit's folder cannot be written
    root = cache_root()
    assert root == tmp_path / "xdg" / "cs451" and root.is_dir()
    assert root.stat().st_mode & 0o777 == 0o700                          # the reference's answers stay private
    assert root in protected_paths()                                    # and hidden from every submission


def test_an_os_error_naming_a_path_is_the_users_and_any_other_a_bug(monkeypatch, capsys):
    import cs451.scene

    def denied():
        raise PermissionError(13, "Permission denied", "/srv/scenes")
    monkeypatch.setattr(cs451.scene, "bundled_scenes", denied)
    code, _, err = run(["scenes"], capsys)
    assert code == 2 and one_line(err) == "cs451: error: /srv/scenes: Permission denied"

    def broken():
        raise OSError(5, "Input/output error")
    monkeypatch.setattr(cs451.scene, "bundled_scenes", broken)
    code, _, err = run(["scenes"], capsys)
    assert code == 3 and "internal error" in err


# --- 2, 3. counts and task ids --------------------------------------------------------------------------------------

@pytest.mark.parametrize("argv, said", [
    (["grade", STAGE, "--jobs", "0"], "argument --jobs: must be at least 1, got 0"),
    (["grade", STAGE, "--jobs", "-2"], "argument --jobs: must be at least 1, got -2"),
    (["grade", STAGE, "--jobs", "two"], "argument --jobs: must be a whole number, got 'two'"),
    (["demo", STAGE, "--frames", "0"], "argument --frames: must be at least 1, got 0"),
    (["slides", "record", "--repeats", "2"], "argument --repeats: must be at least 3, got 2"),
])
def test_a_count_under_its_least_is_refused_by_argparse(argv, said, no_grading, capsys):
    code, _, err = run(argv, capsys)
    last = err.strip().splitlines()[-1]
    assert code == 2 and said in last and last.startswith("cs451 ") and err.count("error:") == 1, err


@pytest.mark.parametrize("command", [["grade", STAGE], ["autograder", "run", STAGE]])
def test_unknown_task_ids_are_refused_naming_the_stages_tasks(command, no_grading, capsys):
    code, _, err = run([*command, "--tasks", f"{TASKS[0]},Z99"], capsys)
    line = one_line(err)
    assert code == 2 and "Z99" in line and ", ".join(TASKS) in line and "no task Z99" in line
    assert TASKS[0] not in line.split("no task", 1)[1].split("(", 1)[0]


# --- 4. global options anywhere ----------------------------------------------------------------------------------

@pytest.mark.parametrize("argv", [["-v", "scenes"], ["scenes", "-v"], ["--verbose", "scenes", "--json"],
                                  ["-v", "autograder", "run", STAGE], ["autograder", "run", STAGE, "-v"]])
def test_verbose_works_before_and_after_the_subcommand(argv):
    args = build_parser().parse_args(argv)
    assert args.verbose is True and args.quiet is False


def test_quiet_after_the_subcommand_and_both_refused(capsys):
    from cs451.progress import quiet, verbose
    code, out, _ = run(["scenes", "-q"], capsys)
    assert code == 0 and quiet() and not verbose() and out
    code, _, _ = run(["-v", "scenes"], capsys)
    assert code == 0 and verbose() and not quiet()            # the subcommand's parser kept the -v before it
    for argv in (["-v", "scenes", "-q"], ["scenes", "-q", "--verbose"]):
        code, _, err = run(argv, capsys)
        assert code == 2 and "not allowed with" in err.strip().splitlines()[-1], err


# --- 5. help for every option ---------------------------------------------------------------------------------------

def test_every_option_of_every_subcommand_has_help():
    parser = build_parser()
    missing = []

    def walk(p: argparse.ArgumentParser, path: str) -> None:
        for action in p._actions:
            if isinstance(action, argparse._HelpAction):
                continue
            if isinstance(action, argparse._SubParsersAction):
                helps = {c.dest: c.help for c in action._choices_actions}
                for name, child in action.choices.items():
                    if not helps.get(name):
                        missing.append(f"{path} {name} (the subcommand)")
                    walk(child, f"{path} {name}")
                continue
            if not (action.help or "").strip() or action.help == argparse.SUPPRESS:
                missing.append(f"{path} {'/'.join(action.option_strings) or action.dest}")
    walk(parser, "cs451")
    assert not missing, missing


# --- 6. scenes ------------------------------------------------------------------------------------------------------

def test_scenes_names_the_stages_that_draw_each_and_renders_choice(capsys):
    from cs451.render import infer_stage
    from cs451.scene import bundled_scenes, load_scene
    code, out, _ = run(["scenes"], capsys)
    lines = out.rstrip("\n").splitlines()
    assert code == 0 and lines[0].startswith("scene") and "description" in lines[0]
    assert len(lines) == 1 + len(bundled_scenes())
    column = lines[0].index("drawn by")
    for name, line in zip(bundled_scenes(), lines[1:]):
        scene = load_scene(name)
        drawing = [s for s in stage_names() if get_stage(s).draws_scene(scene)]
        assert line.startswith(name + " ") and scene.description in line
        stages = line[column:].split("  ", 1)[0]
        assert stages.replace("*", "").split(", ") == drawing, line
        assert f"{infer_stage(scene)}*" in stages and stages.count("*") == 1, line
    code, out, _ = run(["scenes", "--json"], capsys)
    rows = json.loads(out)
    assert [r["name"] for r in rows] == bundled_scenes() and all(r["render"] in r["stages"] for r in rows)


# --- 7. failures first ----------------------------------------------------------------------------------------------

def test_the_table_and_the_report_list_failures_first_in_test_order():
    from cs451.grading.loader import load_tests
    from cs451.grading.report import render_report
    from cs451.grading.results import format_table
    tests = [t for t in load_tests(STAGE, include_hidden=False) if not t.extension][:8]
    fail = {t.number for t in tests[1::3]} | {tests[-1].number}
    result = GradeResult(STAGE, "starter", [Result(t, 0.0 if t.number in fail else t.points,
                                                       Verdict(0.0 if t.number in fail else 1.0, "x"))
                                            for t in tests])
    failed = [t.number for t in tests if t.number in fail]
    passed = [t.number for t in tests if t.number not in fail]
    rows = [line.split()[0] for line in format_table(result).splitlines()
            if line.split() and line.split()[0] in {t.number for t in tests}]
    assert rows == failed + passed
    html = render_report(result)
    summary = html[html.index("<table>"):html.index("</table>")]
    assert [s.split('"', 1)[0] for s in summary.split('href="#t')[1:]] == failed + passed


# --- 8. progress within a second --------------------------------------------------------------------------------------

class FakeTerminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_a_bar_shows_its_label_within_a_second_without_any_item_done():
    from cs451.progress import Progress
    stream = FakeTerminal()
    bar = Progress("compiling the kernels", 10, stream=stream)
    try:
        time.sleep(1.0)
        assert "compiling the kernels" in stream.getvalue()
    finally:
        bar.close()
    assert stream.getvalue().endswith("\n")


def test_quiet_shows_no_bar(capsys):
    from cs451.progress import Progress, set_quiet
    set_quiet(True)
    stream = FakeTerminal()
    bar = Progress("compiling the kernels", 10, stream=stream)
    time.sleep(1.0)
    bar.advance()
    bar.close()
    assert stream.getvalue() == ""


@pytest.mark.spawns
def test_grading_starts_its_bar_before_it_loads_tests_answers_or_a_sandbox(monkeypatch):
    """The seconds before the first test (loading tests, the reference's answers, the sandbox) are under the bar."""
    from cs451.grading import runner
    made, seen = [], []
    real = runner.Progress

    class Recorded(real):
        def __init__(self, *a, **k):
            made.append(a[0])
            super().__init__(*a, **k)
    monkeypatch.setattr(runner, "Progress", Recorded)
    real_load = runner.load_tests
    monkeypatch.setattr(runner, "load_tests", lambda *a, **k: (seen.append(list(made)), real_load(*a, **k))[1])
    runner.grade(runner.get_stage("sphere").name, "reference", include_hidden=False, tasks=["S1"])
    assert seen == [["grading sphere"]]


def test_a_long_whitted_render_is_traced_in_bands_under_a_bar(monkeypatch):
    """A render estimated past a second is traced in bands (its bar moves), and the bands join into the very image
    one call draws."""
    import numpy as np
    from cs451.impl import load_impl, resolve_impl
    from cs451.scene import load_scene
    from cs451.stages import get_stage
    from cs451.stages import whitted
    stage = get_stage("whitted")
    scene, impl = load_scene("cornell-spheres"), load_impl(resolve_impl("reference", "whitted"), "whitted")
    assert len(whitted.cost.bands(120_000, whitted.cost.trace_seconds(scene, 120_000, stage.options(scene)))) == 1
    whole = whitted.render(scene, impl, (24, 18))
    monkeypatch.setattr(whitted.cost, "BANDED_SECONDS", 0.0)
    monkeypatch.setattr(whitted.cost, "BAND_SECONDS", 1e-4)
    assert len(whitted.cost.bands(24 * 18, 1e-3 + whitted.cost.trace_seconds(scene, 24 * 18, stage.options(scene)))) > 1
    banded = whitted.render(scene, impl, (24, 18))
    np.testing.assert_array_equal(banded, whole)
