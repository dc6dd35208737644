"""What each ``cs451`` subcommand does once its command line is parsed (``cs451/cliargs.py``): one function per
subcommand over the functions the tests and the Python API call too. Each returns the exit status; a mistake the
user can fix raises :class:`~cs451.errors.KitError`, which ``cs451/cli.py`` prints as one line (status 2).

Everything a command will write (``--results``, ``--report``, ``-o``) is checked before its work starts.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .errors import KitError
from .outputs import check_writable
from .progress import warn


def cmd_render(a: argparse.Namespace) -> int:
    """``cs451 render``: a scene (or a handout figure's test) to a PNG."""
    from .copy import default_impl
    from .render import render_figure, render_scene
    if a.figure:
        given = [o for o, v in (("a scene", a.scene), ("--size", a.size), ("--stage", a.stage),
                                ("--shading", a.shading)) if v]
        if given:
            raise KitError(f"--figure {a.figure} draws the figure's own scene, size and settings: drop {', '.join(given)}")
        path, seconds = render_figure(figure=a.figure, output=a.output, impl=a.impl or default_impl())
        print(f"wrote {path} ({seconds:.2f} s; figure {a.figure}, drawn as its test draws it)")
        return 0
    if not a.scene:
        raise KitError("render: give a scene (a bundled name or a scene file) or --figure TEST")
    path, seconds = render_scene(scene=a.scene, output=a.output, impl=a.impl or default_impl(), size=a.size,
                                 stage=a.stage, shading=a.shading)
    print(f"wrote {path} ({seconds:.2f} s)")
    return 0


def cmd_compare(a: argparse.Namespace) -> int:
    """``cs451 compare``: exit 1 when the render differs from its target as the image tests judge."""
    from .side_by_side import compare_files
    out = compare_files(a.mine, a.target, a.output)
    verdict = "matches" if out.passed else "differs"
    print(f"{a.mine} {verdict} {a.target} as the image tests judge it: {out.message}; FLIP {out.flip_mean:.3f}")
    print(f"wrote {out.output} (target, mine, the grader's error map, FLIP)")
    return 0 if out.passed else 1


def task_ids(stage: str, text: str | None, option: str = "--tasks") -> list[str] | None:
    """``S1,S2`` as task ids of ``stage``; an id the stage does not have is refused (it would grade nothing)."""
    if text is None:
        return None
    from .stages import get_stage
    ids = [t.strip() for t in text.split(",") if t.strip()]
    known = [t.id for t in get_stage(stage).tasks]
    if not ids:
        raise KitError(f"{option}: give task ids, e.g. {','.join(known[:2])} (stage {stage}'s tasks: {', '.join(known)})")
    unknown = [t for t in ids if t not in known]
    if unknown:
        raise KitError(f"{option} {text}: stage {stage} has no task {', '.join(unknown)} "
                       f"(its tasks: {', '.join(known)})")
    return ids


def below_bar(score: float, max_score: float, fail_under: float) -> bool:
    """Whether a grade is under ``--fail-under`` (a percentage): a grade with no points to earn never is."""
    return max_score > 0 and 100.0 * score / max_score < fail_under - 1e-9


def cmd_grade(a: argparse.Namespace) -> int:
    """``cs451 grade``: exit 1 when one submission's grade is under ``--fail-under`` (full marks unless told);
    a roster exits 0 once its gradebook is written, whatever the grades."""
    tasks = task_ids(a.stage, a.tasks)
    if a.roster:
        if a.fail_under is not None:
            raise KitError("--fail-under: a roster's grading exits 0 once its gradebook is written (each student's "
                           "grade is in it); drop --fail-under or --roster")
        from .grading.roster import grade_roster
        output = check_writable(a.report or "grades", "--report", folder=True)
        path = grade_roster(stage=a.stage, roster=a.roster, output=output, include_hidden=not a.public_only,
                            parallel=a.jobs, only=tasks)
        print(f"wrote {path} and one report per student beside it")
        return 0
    if a.results:
        check_writable(a.results, "--results")
    if a.report:
        check_writable(a.report, "--report", folder=True)
    from .grading.report import write_report
    from .grading.results import format_table, write_failure, write_results
    from .grading.runner import grade
    try:
        from .copy import default_submission
        result = grade(a.stage, a.submission or default_submission(), include_hidden=not a.public_only, jobs=a.jobs,
                       tasks=tasks)
    except BaseException as err:  # a results file is always written, with the reason, before we fail
        if a.results:
            write_failure(a.results, f"{type(err).__name__}: {err}")
            from .grading.untrusted import printable
            print(printable(f"wrote {a.results} (grading failed: {err})", lines=False), file=sys.stderr)
        raise
    print(format_table(result))
    if a.results:
        print(f"wrote {write_results(a.results, result)}")
    if a.report:
        print(f"wrote {write_report(a.report, result, show_hidden=not a.student_view)}")
    limit = 100.0 if a.fail_under is None else a.fail_under
    if not below_bar(result.score, result.max_score, limit):
        return 0
    if a.fail_under is not None:
        print(f"{result.score:g} / {result.max_score:g} = {100 * result.score / result.max_score:.4g}%, under "
              f"--fail-under {limit:g}: exit 1", file=sys.stderr)
    return 1


def cmd_starter(a: argparse.Namespace) -> int:
    """``cs451 starter``: regenerate starter/, or (``--check``) exit 1 when it has drifted."""
    from .starter import check_starter, generate_starter
    if a.check:
        drift = check_starter()
        for d in drift:
            print(f"starter/{d.path}: {d.reason}")
        if drift:
            print("starter/ has drifted from reference/: run `cs451 starter` to regenerate it", file=sys.stderr)
            return 1
        print("starter/ is in step with reference/")
        return 0
    files = generate_starter()
    print(f"regenerated starter/ from reference/ ({len(files)} files)")
    return 0


def cmd_figures(a: argparse.Namespace) -> int:
    """``cs451 figures``: the handouts' target images, or (``--check``) exit 1 when they have drifted."""
    from .packaging.diagrams import check_diagrams, write_diagrams
    from .packaging.figures import check_figures, write_figures
    from .stages import stage_names
    stages = [a.stage] if a.stage else stage_names()
    if a.check:
        problems = [p for s in stages for p in check_figures(s) + check_diagrams(s)]
        for p in problems:
            print(p)
        if problems:
            print("the handouts' figures have drifted from the reference: run `cs451 figures` to regenerate them",
                  file=sys.stderr)
            return 1
        print("the handouts' figures are in step with the reference")
        return 0
    for s in stages:
        files = write_figures(s)
        diagrams = write_diagrams(s)
        print(f"{s}: wrote {len(files) - 1} figures and the handout's figures block"
              + (f", and {len(diagrams)} diagrams" if diagrams else ""))
    return 0


def cmd_demo(a: argparse.Namespace) -> int:
    """``cs451 demo``: the lecture demo, in a window or as images."""
    from .demos import run_demo
    window = True if a.window else (False if a.no_window else None)
    from .copy import default_impl
    paths = run_demo(stage=a.stage, impl=a.impl or default_impl(), output=a.output, window=window, frames=a.frames,
                     scene=a.scene, size=a.size, screenshot=a.screenshot, fullscreen=a.fullscreen)
    if a.screenshot:
        print(f"wrote {a.screenshot} (the window, as the display shows it)")
    for p in paths:
        print(f"wrote {p}")
    if paths:
        print("(no display: wrote images instead of opening a window)")
    return 0


def slides_commands():
    """The slides' commands (lecturer-only: a student's release has no cs451/slides)."""
    from .slides import commands
    return commands


def cmd_warm(a: argparse.Namespace) -> int:
    """``cs451 warm``: compile now what a first render or demo would."""
    from .warm import warm
    done = warm([a.stage] if a.stage else None)
    print(f"warm: {len(done)} steps in {sum(s for _, s in done):.1f} s; first renders and demos compile nothing now")
    return 0


def cmd_scenes(a: argparse.Namespace) -> int:
    """``cs451 scenes``: each bundled scene, the stages that draw it (``cs451 render``'s choice marked) and what it
    is; ``--json`` the same as a list a script can read."""
    import json

    from .copy import student_stage
    from .render import infer_stage
    from .scene import bundled_scenes, load_scene
    from .stages import get_stage, stage_names
    if a.schema:
        from .scene_schema import schema_text
        print(schema_text(), end="")
        return 0
    mine = student_stage()
    rows = []
    for name in bundled_scenes():
        scene = load_scene(name)
        drawing = [s for s in stage_names() if get_stage(s).draws_scene(scene)]
        try:
            chosen = mine or infer_stage(scene)
        except KitError:    # its options name several stages: `cs451 render` asks for --stage
            chosen = None
        rows.append({"name": name, "description": scene.description, "stages": drawing,
                     "render": chosen if chosen in drawing else None})
    if a.json:
        print(json.dumps(rows, indent=2))
        return 0
    drawn = [", ".join(s + ("*" if s == r["render"] else "") for s in r["stages"]) or "-" for r in rows]
    head = ("scene", "drawn by (* = cs451 render's choice)")
    w1 = max(len(head[0]), *(len(r["name"]) for r in rows))
    w2 = max(len(head[1]), *(len(d) for d in drawn))
    print(f"{head[0]:<{w1}}  {head[1]:<{w2}}  description")
    for r, d in zip(rows, drawn):
        print(f"{r['name']:<{w1}}  {d:<{w2}}  {r['description']}")
    return 0


def cmd_bench(a: argparse.Namespace) -> int:
    """``cs451 bench``: refused before anything runs when its output folder or its plotting library is missing."""
    from .bench import check_bench, run_bench
    check_writable(a.output, "-o", folder=True)
    check_bench(a.stage)
    run_bench(stage=a.stage, output=a.output, quick=a.quick)
    return 0


def cmd_autograder(a: argparse.Namespace) -> int:
    """``cs451 autograder build | warm | run``: the Gradescope autograder's steps (``run`` exits 0 once it has
    written results.json, whatever the grade: Gradescope reads the grade from the file)."""
    if a.action == "build":
        from .packaging.gradescope import build_gradescope
        check_writable(a.output, "-o", example="autograder.zip")
        print(f"wrote {build_gradescope(a.stage, a.output)} (upload it as the Gradescope autograder)")
        return 0
    if a.action == "warm":
        from .packaging.answers import answer_files
        print(f"{len(answer_files(a.stage, show_progress=True))} reference answers ready for {a.stage}")
        return 0
    if a.action == "run":
        from .packaging.gradescope import run_gradescope
        return run_gradescope(a.stage, a.submission, a.results, tasks=task_ids(a.stage, a.tasks))
    raise KitError(f"unknown action {a.action}")


def cmd_passed(a: argparse.Namespace) -> int:
    """Exit 0 when every test of a task passed in a results.json (one GitHub Classroom test per task)."""
    import json
    try:
        tests = json.loads(Path(a.results).read_text())["tests"]
    except (OSError, ValueError, KeyError, TypeError) as err:
        raise KitError(f"{a.results}: not a results file ({err})") from None
    from .grading.untrusted import printable
    mine = [t for t in tests if a.task in t.get("tags", [])]
    for t in mine:   # the Classroom step's output: the submission's text made printable
        line = f"{t['number']} {t['status']:6} {t['score']:g}/{t['max_score']:g}  {t['name']}"
        print(printable(line, lines=False))
        if t["status"] != "passed":
            print(f"        {printable(t['output'].splitlines()[0] if t['output'] else '', lines=False)}")
    if not mine:
        print(f"no tests of task {a.task} in {a.results}")
        return 1
    return 0 if all(t["status"] == "passed" for t in mine) else 1


def cmd_release(a: argparse.Namespace) -> int:
    """``cs451 release``: the students' repository for a stage."""
    from .packaging.release import build_release, release_warnings
    included = tuple(a.include_reference or ())
    for warning in release_warnings(a.stage, included):
        warn(warning)
    out = build_release(a.stage, a.output, include_reference=included)
    print(f"wrote the student repository for {a.stage} to {out} (push it as the GitHub Classroom template)")
    return 0
