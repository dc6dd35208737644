"""The ``cs451`` command line: its subcommands, their options and help (``cs451 --help``), and the options every
subcommand takes (``-v``, ``-q``, before or after the subcommand's name). What each subcommand does is in
``cs451/commands.py``; ``cs451/cli.py`` runs it and turns errors into one line and an exit status.
"""
from __future__ import annotations

import argparse

from . import __version__
from .commands import (cmd_autograder, cmd_bench, cmd_compare, cmd_demo, cmd_figures, cmd_grade, cmd_passed,
                       cmd_release, cmd_render, cmd_scenes, cmd_starter, cmd_warm, slides_commands)

def exit_codes(student: bool) -> str:
    """The exit statuses, for ``cs451 --help``: a student's copy has no roster, autograder run or lecturers' checks."""
    checks = "compare: the images differ, autograder passed: a test of the task failed" if student else \
        ("starter --check, figures --check,\n     slides check, compare: the images differ, autograder passed: a test of "
         "the task failed")
    success = "" if student else ("; a --roster once its\n     gradebook is written; cs451 autograder run once it has "
                                  "written results.json, whatever the grade")
    return f"""exit status:
  0  success (cs451 grade: the grade reaches --fail-under, full marks unless told{success})
  1  a grade under --fail-under; a check that found something ({checks})
  2  a mistake on the command line or in a file it names (one line says which); interrupted: 130
  3  a bug in the kit (one line; CS451_TRACEBACK=1 shows the whole traceback)"""


class OneLineParser(argparse.ArgumentParser):
    """argparse, with a mistake on the command line said in one line (as every other mistake is), pointing at the
    subcommand's ``--help`` instead of printing its usage."""

    def error(self, message: str):  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def count(minimum: int = 1):
    """An argparse type: a whole number of at least ``minimum`` (``--jobs 0`` is refused by argparse, in its own
    usage-and-error lines, before anything runs)."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be a whole number, got {text!r}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"must be at least {minimum}, got {value}")
        return value
    parse.__name__ = "count"
    return parse


def percent(text: str) -> float:
    """An argparse type: a percentage from 0 to 100 (``--fail-under``)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a percentage from 0 to 100, got {text!r}") from None
    if not 0 <= value <= 100:
        raise argparse.ArgumentTypeError(f"must be a percentage from 0 to 100, got {text}")
    return value


def repeats(text: str) -> int:
    """An argparse type for ``slides record --repeats``: at least the records' minimum of runs per timing."""
    from .slides.records import MIN_REPEATS
    return count(MIN_REPEATS)(text)


def global_options(parser: argparse.ArgumentParser, top: bool) -> None:
    """``-v`` and ``-q``, on the main parser (``top``, with their defaults) and on every subcommand's, where they
    default to nothing so that ``cs451 -v render …`` keeps its ``-v`` when the subcommand's parser runs."""
    default = {} if top else {"default": argparse.SUPPRESS}
    group = parser.add_mutually_exclusive_group()
    group.add_argument("-v", "--verbose", action="store_true", help="print every counter of a job, not only its "
                       "summary (before or after the subcommand)", **default)
    group.add_argument("-q", "--quiet", action="store_true", help="no progress bars and no warnings: only results "
                       "(the \"wrote …\" lines, tables) and errors (before or after the subcommand)", **default)


def subparsers(parser: argparse.ArgumentParser) -> list[argparse.ArgumentParser]:
    """Every subcommand's parser below ``parser``, nested ones (``autograder run``, ``slides build``) included."""
    out = []
    for action in parser._actions:   # argparse keeps its subparsers private
        if isinstance(action, argparse._SubParsersAction):
            for child in dict.fromkeys(action.choices.values()):
                out += [child, *subparsers(child)]
    return out


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
    """The commands of this copy (a student's copy, made by ``cs451 release``, has only the student's), each
    taking ``-v``/``-q`` wherever they stand on the line."""
    parser = _commands()
    global_options(parser, top=True)
    for child in subparsers(parser):
        global_options(child, top=False)
    return parser


def _commands() -> argparse.ArgumentParser:
    """The main parser and its subcommands, with their own options."""
    from .copy import student_stage
    from .stages import stage_names
    mine = student_stage()
    stages = [mine] if mine else stage_names()
    what = f"stage {mine}" if mine else "the course's stages"
    p = OneLineParser(prog="cs451", description=f"cs451-kit: render and grade {what}.", epilog=exit_codes(bool(mine)),
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--version", action="version", version=f"cs451-kit {__version__}")
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
    r.set_defaults(func=cmd_render)

    c = sub.add_parser("compare", help="a render beside its target, judged as the image tests judge",
                       description="Compare your render with a target image (a handout figure, or a reference "
                                   "render) as the image tests do, and write them side by side with the error maps.")
    c.add_argument("mine", help="your PNG (cs451 render … -o mine.png)")
    c.add_argument("target", help="the target PNG, e.g. assignments/…/figures/S5.1.png")
    c.add_argument("-o", "--output", default="compare.png", help="side-by-side PNG to write (default: compare.png)")
    c.set_defaults(func=cmd_compare)
    g = sub.add_parser("grade", help="grade a submission and write a report", description="Run a stage's autograder tests on a submission.")
    g.add_argument("stage", choices=stages, help="the stage whose tests are run")
    g.add_argument("--submission", help=f"{'' if mine else 'reference, starter, or '}a folder holding the stage's "
                                        f"package (default: {'your package' if mine else 'starter'})")
    g.add_argument("--results", metavar="FILE", help="write Gradescope's results.json here (folders are made as needed)")
    g.add_argument("--report", help="write an HTML report (reference, yours, difference, error map) into this folder"
                                    + ("" if mine else "; with --roster, the folder for the gradebook and reports (default: grades)"))
    g.add_argument("--public-only", action="store_true", help="run only the public tests" + (" (a student copy has no others)" if mine else ", as a student's copy does"))
    g.add_argument("--student-view", action="store_true", help="report: count hidden tests without showing them")
    g.add_argument("--jobs", type=count(1), default=None, help="tests run at once (default: 2)"
                   + ("" if mine else "; with --roster, submissions graded at once (default: one per CPU)"))
    g.add_argument("--tasks", help="only these tasks' tests, e.g. S1,S2 (ids the stage does not have are refused)")
    g.add_argument("--fail-under", type=percent, metavar="PERCENT",
                   help="exit 1 when the grade is under PERCENT of the points (default: 100, so anything below full "
                        "marks exits 1; 0 always exits 0)" + ("" if mine else "; not with --roster"))
    if not mine:
        g.add_argument("--roster", help="grade every submission folder inside this folder (one per student); exits 0 "
                                        "once the gradebook is written, whatever the grades")
    g.set_defaults(func=cmd_grade, roster=None)

    from .demos.controls import help_text
    d = sub.add_parser("demo", help="the lecture demo: a window, or images without a display", description="Run a stage's demo.",
                       epilog=help_text(stages), formatter_class=argparse.RawDescriptionHelpFormatter)
    d.add_argument("stage", choices=stages, help="the stage whose demo is run")
    d.add_argument("--impl", help=f"a folder holding the stage's package (default: {yours})")
    d.add_argument("-o", "--output", default="demo", help="folder for the images when there is no display (default: demo)")
    d.add_argument("--window", action="store_true", help="open a window even if no display is detected")
    d.add_argument("--no-window", action="store_true", help="write images even if there is a display")
    takes = _demo_options(stages)
    d.add_argument("--frames", type=count(1), help="close the window after this many frames (for scripted demos); "
                                             f"without a window ({takes['scene'][0]}), write only the first that many")
    d.add_argument("--scene", help=f"{takes['scene'][0]}: a bundled scene or scene file (default: {takes['scene'][1]})")
    d.add_argument("--size", help=f"{takes['size'][0]}: WIDTHxHEIGHT of the picture, overriding the scene's")
    d.add_argument("--screenshot", help=f"{takes['screenshot'][0]}: in the window, play the frames' script, save the "
                                        "window as the display shows it to this PNG, and close")
    d.add_argument("--fullscreen", action="store_true", help="open the window full screen (f toggles it in any demo)")
    d.set_defaults(func=cmd_demo)

    sc = sub.add_parser("scenes", help="list the bundled scenes and the stages that draw them",
                        description="List the bundled scenes: the stages that draw each (* marks the one `cs451 "
                                    "render SCENE` uses) and what it is.")
    sc.add_argument("--json", action="store_true", help="print a JSON list (name, description, stages, render) instead")
    sc.add_argument("--schema", action="store_true", help="print the scene format as a JSON Schema, for an editor "
                                                          "(docs/scene.schema.json holds the same)")
    sc.set_defaults(func=cmd_scenes)

    ag = sub.add_parser("autograder", help="the autograder's own steps" if mine else "build or run the Gradescope autograder",
                        description="`passed` reads a results.json (GitHub Classroom)." if mine else
                        "Gradescope: `build` writes the autograder zip; inside it, `warm` (setup.sh) computes every "
                        "answer once and `run` (run_autograder) grades one submission; `passed` reads a results.json "
                        "(GitHub Classroom).")
    agsub = ag.add_subparsers(dest="action", required=True, metavar="ACTION")
    agp = agsub.add_parser("passed", help="exit 0 when every test of TASK passed in RESULTS")
    agp.add_argument("results", help="a results.json written by `cs451 grade --results`")
    agp.add_argument("task", help="a task ID, e.g. S1")
    agp.set_defaults(func=cmd_passed)
    if mine:
        return p

    agb = agsub.add_parser("build", help="write the Gradescope autograder zip for a stage")
    agb.add_argument("stage", choices=stages, help="the stage the autograder grades")
    agb.add_argument("-o", "--output", default="autograder.zip", help="zip file to write (default: autograder.zip)")
    agw = agsub.add_parser("warm", help="compute every answer the tests compare with (setup.sh does this)")
    agw.add_argument("stage", choices=stages, help="the stage whose answers are computed")
    agr = agsub.add_parser("run", help="grade one submission the Gradescope way (run_autograder does this)")
    agr.add_argument("stage", choices=stages, help="the stage the submission is for")
    agr.add_argument("--submission", default="/autograder/submission",
                     help="the uploaded folder (default: /autograder/submission, where Gradescope puts it)")
    agr.add_argument("--results", default="/autograder/results/results.json",
                     help="where results.json is written (default: /autograder/results/results.json, where "
                          "Gradescope reads it); exits 0 once it is written, whatever the grade")
    agr.add_argument("--tasks", help="only these tasks' tests (for testing the autograder; ids the stage does not "
                                     "have are refused)")
    for p_ in (agb, agw, agr):
        p_.set_defaults(func=cmd_autograder)

    w = sub.add_parser("warm", help="compile, once, what a first render or demo would (setup.sh does this)",
                       description="Compile the reference's kernels (the ray tracer's) now, so that no first render "
                                   "or lecture demo waits for a compiler; numba's cache keeps them.")
    w.add_argument("stage", nargs="?", choices=stages, help="one stage (default: all)")
    w.set_defaults(func=cmd_warm)

    s = sub.add_parser("starter", help="regenerate starter/ from reference/", description="Regenerate starter/ from the solution regions of reference/.")
    s.add_argument("--check", action="store_true", help="only check: exit 1 if starter/ has drifted")
    s.set_defaults(func=cmd_starter)

    fg = sub.add_parser("figures", help="regenerate the handouts' target images from the reference",
                        description="Render the reference's target image of every public image test into "
                                    "assignments/<handout>/figures/ and the handout's figures block.")
    fg.add_argument("stage", nargs="?", choices=stages, help="one stage (default: all)")
    fg.add_argument("--check", action="store_true", help="only check: exit 1 if the figures have drifted")
    fg.set_defaults(func=cmd_figures)

    rl = sub.add_parser("release", help="build the students' starter repository (GitHub Classroom template)",
                        description="Write a repository for students: the starter, the handout, the public tests "
                                    "with the reference's answers, and a workflow that runs them on push.")
    rl.add_argument("stage", choices=stages, help="the stage the repository is for")
    rl.add_argument("-o", "--output", required=True, help="a new folder to write the repository into")
    rl.add_argument("--include-reference", action="append", metavar="STAGE",
                    help="also ship this earlier stage's reference (one the stage builds on), after its deadline")
    rl.set_defaults(func=cmd_release)

    from .bench import benches
    found = benches()                     # read from the files: each stage's package, then the kit's bench/
    b = sub.add_parser("bench", help="time-against-error benchmarks", description="Run a benchmark; prints a table and "
                       "writes JSON.", epilog="benchmarks:\n" + "\n".join(f"  {name:<15} {bench.summary}"
                                                                          for name, bench in found.items()),
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    b.add_argument("stage", metavar="NAME", choices=list(found),
                   help=f"a stage ({', '.join(n for n, x in found.items() if x.name == x.stage)}) or another "
                        f"benchmark ({', '.join(n for n, x in found.items() if x.name != x.stage)}): see below")
    b.add_argument("-o", "--output", default="bench-results",
                   help="folder for the JSON and plots (default: bench-results); the plots need "
                        "pip install 'cs451-kit[bench]' (matplotlib)")
    b.add_argument("--quick", action="store_true", help="a small run that shows the benchmark works (the tests run every "
                   "benchmark so), not a measurement")
    b.set_defaults(func=cmd_bench)

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
    slr.add_argument("names", nargs="*", metavar="NAME", help="the records' names, the decks' benchmark figures' "
                                                              "(default: all of them; cs451 slides record --help "
                                                              "lists them)")
    slr.add_argument("--quick", action="store_true", help="small sizes (for tests; never commit a quick record)")
    slr.add_argument("--repeats", type=repeats, default=3, help="each timing is the median of this many runs (at least 3)")
    slr.add_argument("-o", "--output", help="folder for the records (default: slides/records in the kit)")
    slr.set_defaults(func=lambda a: slides_commands().cmd_record(a))
    return p


def _deck_options(parser: argparse.ArgumentParser, stages: list[str],
                  quick: str = "small, fast figures (drafts)") -> None:
    """What every ``cs451 slides`` action that builds decks takes: the deck, the figures' cache, draft figures."""
    parser.add_argument("deck", nargs="?", help=f"overview, {', '.join(stages)} (default: all)")
    parser.add_argument("--cache", help="folder for the rendered figures (default: .cs451-cache/slides in the kit)")
    parser.add_argument("--quick", action="store_true", help=quick)


