"""The ``cs451`` command: argument parsing and messages over the functions the tests and the Python API call
too (as otter-grader's CLI), one per subcommand.

Errors a user can fix print as one line, without a traceback, and exit with 2.
"""
from __future__ import annotations

import argparse
import os
import sys
import traceback
from pathlib import Path

from . import __version__
from .errors import KitError


def _cmd_render(a: argparse.Namespace) -> int:
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


def _cmd_compare(a: argparse.Namespace) -> int:
    from .side_by_side import compare_files
    out = compare_files(a.mine, a.target, a.output)
    verdict = "matches" if out.passed else "differs"
    print(f"{a.mine} {verdict} {a.target} as the image tests judge it: {out.message}; FLIP {out.flip_mean:.3f}")
    print(f"wrote {out.output} (target, mine, the grader's error map, FLIP)")
    return 0 if out.passed else 1


def _cmd_grade(a: argparse.Namespace) -> int:
    if a.roster:
        from .grading.roster import grade_roster
        path = grade_roster(stage=a.stage, roster=a.roster, output=a.report or "grades",
                            include_hidden=not a.public_only, parallel=a.jobs, only=_tasks(a.tasks))
        print(f"wrote {path} and one report per student beside it")
        return 0
    from .grading.report import write_report
    from .grading.results import format_table, write_results
    from .grading.results import write_failure
    from .grading.runner import grade
    try:
        from .copy import default_submission
        result = grade(a.stage, a.submission or default_submission(), include_hidden=not a.public_only, jobs=a.jobs,
                       tasks=_tasks(a.tasks))
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
    return 0


def _tasks(text: str | None) -> list[str] | None:
    return [t.strip() for t in text.split(",") if t.strip()] if text else None


def _cmd_starter(a: argparse.Namespace) -> int:
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


def _cmd_figures(a: argparse.Namespace) -> int:
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


def _cmd_demo(a: argparse.Namespace) -> int:
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


def _cmd_warm(a: argparse.Namespace) -> int:
    from .warm import warm
    done = warm([a.stage] if a.stage else None)
    print(f"warm: {len(done)} steps in {sum(s for _, s in done):.1f} s; first renders and demos compile nothing now")
    return 0


def _cmd_scenes(a: argparse.Namespace) -> int:
    from .scene import bundled_scenes, load_scene
    for name in bundled_scenes():
        print(f"{name:<16} {load_scene(name).description}")
    return 0


def _cmd_bench(a: argparse.Namespace) -> int:
    from .bench import run_bench
    run_bench(stage=a.stage, output=a.output, quick=a.quick)
    return 0


def _cmd_autograder(a: argparse.Namespace) -> int:
    if a.action == "build":
        from .packaging.gradescope import build_gradescope
        print(f"wrote {build_gradescope(a.stage, a.output)} (upload it as the Gradescope autograder)")
        return 0
    if a.action == "warm":
        from .packaging.answers import answer_files
        print(f"{len(answer_files(a.stage, show_progress=True))} reference answers ready for {a.stage}")
        return 0
    if a.action == "run":
        from .packaging.gradescope import run_gradescope
        return run_gradescope(a.stage, a.submission, a.results, tasks=_tasks(a.tasks))
    raise KitError(f"unknown action {a.action}")


def _cmd_passed(a: argparse.Namespace) -> int:
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


def _cmd_release(a: argparse.Namespace) -> int:
    from .packaging.release import build_release, release_warnings
    included = tuple(a.include_reference or ())
    for warning in release_warnings(a.stage, included):
        print(f"warning: {warning}", file=sys.stderr)
    out = build_release(a.stage, a.output, include_reference=included)
    print(f"wrote the student repository for {a.stage} to {out} (push it as the GitHub Classroom template)")
    return 0



def _demo_options(stages: list[str]) -> dict[str, tuple[str, str]]:
    """For --scene, --size and --screenshot: the demos that take each (asked of each stage's demo, by its
    parameters), and their default scenes."""
    import inspect
    from .demos import demo_entry
    from .stages import get_stage
    out = {}
    for option in ("scene", "size", "screenshot"):
        params = {name: inspect.signature(demo_entry(name)).parameters for name in stages if get_stage(name).demo}
        takers = [name for name, p in params.items() if option in p]
        defaults = [str(params[name][option].default) for name in takers]
        out[option] = (", ".join(takers) or "no demo here", ", ".join(defaults))
    return out

def build_parser() -> argparse.ArgumentParser:
    """The commands of this copy: a student's copy (``cs451 release``) has only the student's."""
    from .copy import student_stage
    from .stages import stage_names
    mine = student_stage()
    stages = [mine] if mine else stage_names()
    what = f"stage {mine}" if mine else "the course's stages"
    p = argparse.ArgumentParser(prog="cs451", description=f"cs451-kit: render and grade {what}.")
    p.add_argument("--version", action="version", version=f"cs451-kit {__version__}")
    p.add_argument("-v", "--verbose", action="store_true", help="print every counter of a job, not only its summary")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    yours = "your package (this repository's)" if mine else "reference"

    r = sub.add_parser("render", help="render a scene to a PNG", description="Render a scene with an implementation of a stage.")
    r.add_argument("scene", nargs="?", help="a bundled scene name (see `cs451 scenes`) or a path to a scene JSON file")
    r.add_argument("--figure", metavar="TEST", help="instead of a scene, a handout figure: its image test (e.g. S5.1) "
                                                    "drawn as the test draws it, to compare with the figure")
    r.add_argument("-o", "--output", required=True, help="PNG file to write")
    r.add_argument("--impl", help=f"{'.' if mine else 'reference, starter'}, or the path of a folder holding the "
                                  f"stage's package (default: {yours})")
    r.add_argument("--size", help="WIDTHxHEIGHT, overriding the scene's image size")
    r.add_argument("--stage", choices=stages, help=f"which stage renders the scene (default: "
                                                   f"{mine or 'from the scene options'})")
    r.add_argument("--shading", choices=["gouraud", "phong"], help="stage 1 only: override the scene's shading")
    r.set_defaults(func=_cmd_render)

    c = sub.add_parser("compare", help="a render beside its target, judged as the image tests judge",
                       description="Compare your render with a target image (a handout figure, or a reference "
                                   "render) as the image tests do, and write them side by side with the error maps.")
    c.add_argument("mine", help="your PNG (cs451 render … -o mine.png)")
    c.add_argument("target", help="the target PNG, e.g. assignments/…/figures/S5.1.png")
    c.add_argument("-o", "--output", default="compare.png", help="side-by-side PNG to write (default: compare.png)")
    c.set_defaults(func=_cmd_compare)
    g = sub.add_parser("grade", help="grade a submission and write a report", description="Run a stage's autograder tests on a submission.")
    g.add_argument("stage", choices=stages)
    g.add_argument("--submission", help=f"{'' if mine else 'reference, starter, or '}a folder holding the stage's "
                                        f"package (default: {'your package' if mine else 'starter'})")
    g.add_argument("--results", help="write Gradescope's results.json here")
    g.add_argument("--report", help="write an HTML report (reference, yours, difference, error map) into this folder"
                                    + ("" if mine else "; with --roster, the folder for the gradebook and reports (default: grades)"))
    g.add_argument("--public-only", action="store_true", help="run only the public tests" + (" (a student copy has no others)" if mine else ", as a student's copy does"))
    g.add_argument("--student-view", action="store_true", help="report: count hidden tests without showing them")
    g.add_argument("--jobs", type=int, default=None, help="tests run at once (default: 2)")
    g.add_argument("--tasks", help="only these tasks' tests, e.g. S1,S2")
    if not mine:
        g.add_argument("--roster", help="grade every submission folder inside this folder (one per student)")
    g.set_defaults(func=_cmd_grade, roster=None)

    from .demos.controls import help_text
    d = sub.add_parser("demo", help="the lecture demo: a window, or images without a display", description="Run a stage's demo.",
                       epilog=help_text(stages), formatter_class=argparse.RawDescriptionHelpFormatter)
    d.add_argument("stage", choices=stages)
    d.add_argument("--impl", help=f"a folder holding the stage's package (default: {yours})")
    d.add_argument("-o", "--output", default="demo", help="folder for the images when there is no display (default: demo)")
    d.add_argument("--window", action="store_true", help="open a window even if no display is detected")
    d.add_argument("--no-window", action="store_true", help="write images even if there is a display")
    takes = _demo_options(stages)
    d.add_argument("--frames", type=int, help="close the window after this many frames (for scripted demos); "
                                             f"without a window ({takes['scene'][0]}), write only the first that many")
    d.add_argument("--scene", help=f"{takes['scene'][0]}: a bundled scene or scene file (default: {takes['scene'][1]})")
    d.add_argument("--size", help=f"{takes['size'][0]}: WIDTHxHEIGHT of the picture, overriding the scene's")
    d.add_argument("--screenshot", help=f"{takes['screenshot'][0]}: in the window, play the frames' script, save the "
                                        "window as the display shows it to this PNG, and close")
    d.add_argument("--fullscreen", action="store_true", help="open the window full screen (f toggles it in any demo)")
    d.set_defaults(func=_cmd_demo)

    sc = sub.add_parser("scenes", help="list the bundled scenes", description="List the bundled scenes.")
    sc.set_defaults(func=_cmd_scenes)

    ag = sub.add_parser("autograder", help="the autograder's own steps" if mine else "build or run the Gradescope autograder",
                        description="`passed` reads a results.json (GitHub Classroom)." if mine else
                        "Gradescope: `build` writes the autograder zip; inside it, `warm` (setup.sh) computes every "
                        "answer once and `run` (run_autograder) grades one submission; `passed` reads a results.json "
                        "(GitHub Classroom).")
    agsub = ag.add_subparsers(dest="action", required=True, metavar="ACTION")
    agp = agsub.add_parser("passed", help="exit 0 when every test of TASK passed in RESULTS")
    agp.add_argument("results", help="a results.json written by `cs451 grade --results`")
    agp.add_argument("task", help="a task ID, e.g. S1")
    agp.set_defaults(func=_cmd_passed)
    if mine:
        return p

    agb = agsub.add_parser("build", help="write the Gradescope autograder zip for a stage")
    agb.add_argument("stage", choices=stages)
    agb.add_argument("-o", "--output", default="autograder.zip", help="zip file to write (default: autograder.zip)")
    agw = agsub.add_parser("warm", help="compute every answer the tests compare with (setup.sh does this)")
    agw.add_argument("stage", choices=stages)
    agr = agsub.add_parser("run", help="grade one submission the Gradescope way (run_autograder does this)")
    agr.add_argument("stage", choices=stages)
    agr.add_argument("--submission", default="/autograder/submission")
    agr.add_argument("--results", default="/autograder/results/results.json")
    agr.add_argument("--tasks", help="only these tasks' tests (for testing the autograder)")
    for p_ in (agb, agw, agr):
        p_.set_defaults(func=_cmd_autograder)

    w = sub.add_parser("warm", help="compile, once, what a first render or demo would (setup.sh does this)",
                       description="Compile the reference's kernels (the ray tracer's) now, so that no first render "
                                   "or lecture demo waits for a compiler; numba's cache keeps them.")
    w.add_argument("stage", nargs="?", choices=stages, help="one stage (default: all)")
    w.set_defaults(func=_cmd_warm)

    s = sub.add_parser("starter", help="regenerate starter/ from reference/", description="Regenerate starter/ from the solution regions of reference/.")
    s.add_argument("--check", action="store_true", help="only check: exit 1 if starter/ has drifted")
    s.set_defaults(func=_cmd_starter)

    fg = sub.add_parser("figures", help="regenerate the handouts' target images from the reference",
                        description="Render the reference's target image of every public image test into "
                                    "assignments/<handout>/figures/ and the handout's figures block.")
    fg.add_argument("stage", nargs="?", choices=stages, help="one stage (default: all)")
    fg.add_argument("--check", action="store_true", help="only check: exit 1 if the figures have drifted")
    fg.set_defaults(func=_cmd_figures)

    rl = sub.add_parser("release", help="build the students' starter repository (GitHub Classroom template)",
                        description="Write a repository for students: the starter, the handout, the public tests "
                                    "with the reference's answers, and a workflow that runs them on push.")
    rl.add_argument("stage", choices=stages)
    rl.add_argument("-o", "--output", required=True, help="a new folder to write the repository into")
    rl.add_argument("--include-reference", action="append", metavar="STAGE",
                    help="also ship this earlier stage's reference (one the stage builds on), after its deadline")
    rl.set_defaults(func=_cmd_release)

    b = sub.add_parser("bench", help="time-against-error benchmarks", description="Run a stage's benchmark; prints a table and writes JSON.")
    b.add_argument("stage", choices=stages + ["autograder", "tolerance", "fair_share", "mutation"],
                   help="a stage; 'autograder' (grading time and memory per stage, against Gradescope's limits); "
                        "'mutation' (mistakes planted in the reference's task regions: which the tests catch); "
                        "'tolerance' (image tests' spread across rasterisers and thread counts); 'fair_share' (an "
                        "honest student's roster grading beside a CPU burner, with and without the CPU share)")
    b.add_argument("-o", "--output", default="bench-results", help="folder for the JSON and plots (default: bench-results)")
    b.add_argument("--quick", action="store_true", help="fewer repetitions")
    b.set_defaults(func=_cmd_bench)

    sl = sub.add_parser("slides", help="build the lecture decks (slides/) into self-contained HTML",
                        description="Build the decks of slides/ into one HTML file each, with reveal.js, KaTeX and "
                                    "the reference's figures inside: they open offline.")
    slsub = sl.add_subparsers(dest="action", required=True, metavar="ACTION")
    slb = slsub.add_parser("build", help="build one deck or all of them")
    _deck_options(slb, stages)
    slb.add_argument("-o", "--output", required=True, help="folder for the HTML files (one per deck)")
    slb.set_defaults(func=lambda a: slides_commands().cmd_build(a))
    slc = slsub.add_parser("check", help="measure the decks in headless Chromium as a projector shows them",
                           description="Build the decks and measure every slide at 1920×1080 and 1280×720 in headless "
                                       "Chromium: text under 24 px, code under 20 px or wrapped, figure text under "
                                       "16 px, figures with fewer than 2 pixels per slide pixel, anything under the "
                                       "navigation controls. Exits 1 if any is found.")
    _deck_options(slc, stages, "small, fast figures (drafts; figures then fail the density floor)")
    slc.add_argument("--json", metavar="FILE", help="also write the measurements to FILE")
    slc.set_defaults(func=lambda a: slides_commands().cmd_check(a))
    slp = slsub.add_parser("pdf", help="print the decks to PDF (one slide a page) with headless Chromium",
                           description="Build the decks and print each to a PDF, one slide a page, in headless Chromium "
                                       "once reveal.js has laid them out for print.")
    _deck_options(slp, stages)
    slp.add_argument("-o", "--output", required=True, help="a .pdf file for one deck, or a folder (one PDF per deck)")
    slp.set_defaults(func=lambda a: slides_commands().cmd_pdf(a))
    slr = slsub.add_parser("record", help="measure the benchmark figures' records (slides/records/NAME.json)",
                           description="Measure what the decks' benchmark figures show and write each as "
                                       "slides/records/NAME.json, with the machine, the date and this command: the "
                                       "figures draw only from these records, never timing anything while a deck "
                                       "is built. Run it on a quiet machine.")
    slr.add_argument("names", nargs="*", metavar="NAME", help="whitted, hemicube, radiosity (default: all)")
    slr.add_argument("--quick", action="store_true", help="small sizes (for tests; never commit a quick record)")
    slr.add_argument("--repeats", type=int, default=3, help="each timing is the median of this many runs (at least 3)")
    slr.add_argument("-o", "--output", help="folder for the records (default: slides/records in the kit)")
    slr.set_defaults(func=lambda a: slides_commands().cmd_record(a))
    return p


def _deck_options(parser: argparse.ArgumentParser, stages: list[str],
                  quick: str = "small, fast figures (drafts)") -> None:
    """What every ``cs451 slides`` action that builds decks takes: the deck, the figures' cache, draft figures."""
    parser.add_argument("deck", nargs="?", help=f"overview, {', '.join(stages)} (default: all)")
    parser.add_argument("--cache", help="folder for the rendered figures (default: .cs451-cache/slides in the kit)")
    parser.add_argument("--quick", action="store_true", help=quick)


def _joined_values(argv: list[str]) -> list[str]:
    """``--size -5x10`` as ``--size=-5x10``, so that argparse reports the bad size, not a missing one."""
    out: list[str] = []
    for token in argv:
        if out and out[-1] in VALUE_OPTIONS and token[:1] == "-" and token[1:2].isdigit():
            out[-1] = f"{out[-1]}={token}"
        else:
            out.append(token)
    return out


VALUE_OPTIONS = {"--size", "--frames", "--jobs"}


def main(argv: list[str] | None = None) -> int:
    argv = _joined_values(list(sys.argv[1:] if argv is None else argv))
    args = build_parser().parse_args(argv)
    from .progress import set_verbose
    set_verbose(getattr(args, "verbose", False))
    try:
        return args.func(args)
    except KitError as err:   # it may quote a submission (its file names): made printable
        from .grading.untrusted import printable
        print(printable(f"cs451: error: {err}"), file=sys.stderr)
        return 2
    except MemoryError:
        print("cs451: error: out of memory (the job's estimate missed it: please report the command)", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("cs451: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # `cs451 scenes | head`: the reader left; say nothing more
        try:
            sys.stdout = open(os.devnull, "w")
        except OSError:
            pass
        return 0
    except Exception as err:   # a bug in the kit, never the user's input: one line, the traceback on request
        if os.environ.get("CS451_TRACEBACK"):
            raise
        where = traceback.extract_tb(err.__traceback__)[-1]
        print(f"cs451: internal error: {type(err).__name__}: {err} (at {Path(where.filename).name}:{where.lineno}; "
              f"a bug in the kit: please report it, with CS451_TRACEBACK=1 for the whole traceback)", file=sys.stderr)
        return 3


if __name__ == "__main__":
    sys.exit(main())
