"""``cs451 release``: the starter repository students clone (a GitHub Classroom template).

It holds the engine, the student's package (the starter), the handout, the public
tests as data (``public.json``) with the answers they compare with (the reference's
and the truths', as arrays), the checks that compare, a count of the hidden tests,
and a workflow that runs the public tests on every push. It never holds the
reference, the hidden tests, the truths or any code that computes an answer; a
test builds a submission from everything shipped and expects 0. An earlier
stage's reference (a later stage may build on it) ships only when asked for.
"""
from __future__ import annotations

import json
import shutil
from pathlib import Path

from .. import ENGINE_DIR, KIT_ROOT, __version__, instructor_only
from ..copy import MARKER
from ..errors import KitError
from ..grading.loader import hidden_summary, load_tests, write_manifest
from ..stages import get_stage
from .answers import export_answers
from .files import LITTER, copy_tree, write_executable
from .handout import for_release

#: What of ``autograder/<stage>/`` a student copy holds: the package marker and the checks (which only compare).
SHIPPED_SPEC_FILES = ("__init__.py", "checks.py")
#: A folder beside a handout for the kit's copy only (the bench's figures, which its ``<!-- kit -->`` blocks show).
KIT_FOLDER = "kit"


#: The release's .gitignore: what set-up and the commands its README and handout name write, anchored at the top
#: so that nothing the release ships (the handout's figures and diagrams above all) is ever ignored.
GITIGNORE = """# what ./setup.sh writes
/.venv/
*.egg-info/
__pycache__/
/.cs451-cache/
# what the README's and the handout's commands write: renders and comparisons at the top, reports, demos
/*.png
/report/
/results.json
/demo/
"""


def _engine_litter(folder: str, names: list[str]) -> set[str]:
    """What ``copy_tree("cs451", …)`` leaves out of a release: the usual litter, and what only lecturers use."""
    return set(LITTER(folder, names)) | {name for name in names if instructor_only(Path(folder) / name)}

WORKFLOW_HEADER = """# Runs the public tests of stage {stage} on every push (GitHub Classroom autograding).
# Built by `cs451 release {stage}`; the points per task are the public tests' points.
name: Autograding Tests
on: [push, workflow_dispatch, repository_dispatch]
permissions:
  checks: write
  actions: read
  contents: read
jobs:
  run-autograding-tests:
    runs-on: ubuntu-22.04
    if: github.actor != 'github-classroom[bot]'
    steps:
      - name: Checkout code
        uses: actions/checkout@v4
      - name: Set up the kit (Mesa's EGL for headless OpenGL, a Python virtual environment)
        run: ./setup.sh
      - name: Grade the public tests (the same as `cs451 grade {stage} --submission . --public-only`)
        run: .venv/bin/cs451 grade {stage} --submission . --public-only --results results.json --report report --student-view --fail-under 0
      - name: Keep the image report (reference, yours, difference, error map)
        if: always()
        uses: actions/upload-artifact@v4
        with:
          name: cs451-report
          path: report/
"""

WORKFLOW_TASK = """      - name: {id} {title}
        id: {step}
        uses: classroom-resources/autograding-command-grader@v1
        with:
          test-name: {id} {title}
          setup-command: ''
          command: .venv/bin/cs451 autograder passed results.json {id}
          timeout: 1
          max-score: {points:g}
"""

WORKFLOW_REPORTER = """      - name: Autograding Reporter
        uses: classroom-resources/autograding-grading-reporter@v1
        env:
{env}
        with:
          runners: {runners}
"""

README = """# {title}

Your repository for stage {number} of the course. It holds your package `{stage}/` (the starter:
every function you write raises `NotImplementedError` with a hint until you write it), the kit's
engine (`cs451/`), the public tests (`autograder/{stage}/`) and the handout,
[`{handout}`]({handout}). Read the handout first: it says what each function must do and how
it is graded.

## Set up (once)

On Debian or Ubuntu (or WSL on Windows), from this folder:

```sh
./setup.sh                    # Mesa's EGL driver (apt) and a Python environment in .venv
source .venv/bin/activate     # puts `cs451` on your path
```

{earlier}## Work, look, check

Edit the files in `{stage}/`; the handout names the function of every task. Then:

```sh
cs451 render {scene} -o mine.png
cs451 grade {stage} --report report
```

The first writes your render of a bundled scene (`cs451 scenes` lists them). The second runs the
public tests on your package and writes `report/report.html`: for each image test the reference,
yours, their difference and an error map, failures first. The public tests compare your answers
with the reference's, shipped as arrays in `autograder/{stage}/answers/` (the reference's code is
not in this repository). {hidden}

## Your GitHub repository

Your instructor publishes this folder as the assignment's template on GitHub Classroom; accepting
the assignment makes your own repository from it. Every push to it runs the public tests on GitHub
(the Actions tab) and keeps the report as an artifact. Those points are your own check, not your
grade: the grade comes from your instructor's grader, with the hidden tests, and with the public
tests run on fresh cases of the same kind (new numbers and scenes; the handout says more). If you got this
folder another way, make it a repository of your own with `git init`, `git add -A` and
`git commit -m start`, then push it to a new repository on GitHub.
"""


EARLIER_SECTION = """## Before you render: your stage-{number} `{earlier}/`

This stage draws with a stage-{number} ({earlier}) implementation, and this repository holds none: until
you copy in your own `{earlier}/` package, `cs451 render` and `cs451 demo` stop and say so. Copy it from
your stage-{number} repository (`{source}` stands for wherever that repository is), beside `{stage}/`:

```sh
{command}
```

The grade does not depend on it: the tests give your functions the patches and form factors themselves.

"""


def copy_command(earlier: str) -> str:
    """The command a release's README gives to copy the student's own earlier-stage package in."""
    return f"cp -r {earlier_source(earlier)}/{earlier} ."


def earlier_source(earlier: str) -> str:
    """Where the README says the student's earlier-stage repository is (a name that reads as a placeholder)."""
    return f"../your-{earlier}-repository"


def missing_earlier(stage: str, include_reference: tuple[str, ...] = ()) -> list[str]:
    """The earlier stages whose implementation ``stage`` draws with and that a release without their reference lacks."""
    return [e for e in get_stage(stage).builds_on if e not in include_reference]


def release_warnings(stage: str, include_reference: tuple[str, ...] = ()) -> list[str]:
    """What ``cs451 release`` warns about: references it ships, and earlier stages it cannot draw without."""
    out = []
    if include_reference:
        out.append(f"the release ships the reference solution of {', '.join(include_reference)}: give it to students "
                   "only after that stage's deadline")
    for earlier in missing_earlier(stage, include_reference):
        n = get_stage(earlier).number
        out.append(f"stage {stage} draws with a stage-{n} ({earlier}) implementation and this release ships none: "
                   f"`cs451 render` and `cs451 demo` fail there until a student copies in their own {earlier}/ package "
                   f"(its README says how: `{copy_command(earlier)}`); grading works without it. After stage "
                   f"{n}'s deadline, build with --include-reference {earlier} to ship the reference instead")
    return out


def workflow_text(stage: str) -> str:
    """The GitHub Actions workflow: grade once, then one Classroom test per task worth its public points (none for
    the optional extension, whose points are not in the grade; the report shows how it did)."""
    st = get_stage(stage)
    public = [t for t in load_tests(stage, include_hidden=False)]
    points = {task.id: sum(t.points for t in public if t.task == task.id) for task in st.tasks}
    text = WORKFLOW_HEADER.format(stage=stage)
    steps = []
    for task in st.tasks:
        if points[task.id] <= 0 or task.optional:
            continue
        step = task.id.lower()
        steps.append(step)
        text += WORKFLOW_TASK.format(id=task.id, title=task.title, step=step, points=points[task.id])
    env = "\n".join(f'          {s.upper()}_RESULTS: "${{{{steps.{s}.outputs.result}}}}"' for s in steps)
    return text + WORKFLOW_REPORTER.format(env=env, runners=",".join(steps))


def _setup_script(stage: str) -> str:
    """The kit's setup.sh, ending with what a student does next instead of the kit's main job."""
    text = (KIT_ROOT / "setup.sh").read_text()
    cut = text.find("# The main job")
    if cut < 0:
        raise KitError("setup.sh: no '# The main job' section to replace")
    lines = text[:cut].splitlines(keepends=True)
    first_code = next(i for i, line in enumerate(lines) if i > 0 and not line.startswith("#"))
    body = [line.replace('-e ".[dev,bench]"   # the kit, its tests and its benchmarks', "-e .   # the kit's engine")
            for line in lines[first_code:]]  # the kit's header comment talks of its main job
    header = ["#!/usr/bin/env bash\n",
              "# One command for a fresh Debian/Ubuntu machine: installs what this repository needs.\n",
              "# Safe to run again; it skips what is already there.\n"]
    return "".join(header + body) + (f"echo 'next: .venv/bin/cs451 grade {stage} --submission . --public-only "
                                     f"(see README.md)'\n")


def build_release(stage: str, output: str | Path, include_reference: tuple[str, ...] = ()) -> Path:
    """Write the student repository for ``stage`` into the folder ``output`` (which must not exist).

    ``include_reference``: earlier stages (of those this stage builds on) whose reference solution
    ships too, so the stage's engine can run it; only once their deadlines have passed.
    """
    st = get_stage(stage)
    out = Path(output)
    if out.exists() and not out.is_dir():
        raise KitError(f"-o {out}: is a file, not a folder; choose a new folder")
    if out.exists() and any(out.iterdir()):
        raise KitError(f"-o {out}: exists and is not empty; choose a new folder")
    unknown = [s for s in include_reference if s not in st.builds_on]
    if unknown:
        raise KitError(f"--include-reference {', '.join(unknown)}: stage {stage} builds on "
                       f"{', '.join(st.builds_on) or 'no earlier stage'}; only those references can ship with it")
    starter = KIT_ROOT / "starter" / stage
    if not starter.is_dir():
        raise KitError(f"starter/{stage}: missing; run `cs451 starter` first")
    out.mkdir(parents=True, exist_ok=True)
    copy_tree("cs451", out, ignore=_engine_litter)
    for rel in ("pyproject.toml", "autograder/__init__.py"):
        copy_tree(rel, out)
    handout = out / "assignments" / st.handout / "README.md"
    handout.parent.mkdir(parents=True)
    handout.write_text(for_release((KIT_ROOT / "assignments" / st.handout / "README.md").read_text(), stage,
                                   f"assignments/{st.handout}/README.md"))
    for extra in (KIT_ROOT / "assignments" / st.handout).iterdir():  # figures beside the handout
        if extra.name not in ("README.md", KIT_FOLDER):
            copy_tree(str(extra.relative_to(KIT_ROOT)), out)
    shutil.copytree(starter, out / stage, ignore=LITTER)
    for earlier in include_reference:
        copy_tree(f"reference/{earlier}", out)
    spec_out = out / "autograder" / stage
    spec_out.mkdir(parents=True)
    for name in SHIPPED_SPEC_FILES:
        if (KIT_ROOT / "autograder" / stage / name).exists():      # a stage may use only the kit's generic checks
            shutil.copy2(KIT_ROOT / "autograder" / stage / name, spec_out / name)
    public = load_tests(stage, include_hidden=False)
    write_manifest(stage, public, spec_out)
    export_answers(stage, public, spec_out / "answers")
    hidden = hidden_summary(stage)
    (spec_out / "hidden.json").write_text(json.dumps(hidden, indent=2) + "\n")
    write_executable(out / "setup.sh", _setup_script(stage))
    workflow = out / ".github" / "workflows" / "classroom.yml"
    workflow.parent.mkdir(parents=True)
    workflow.write_text(workflow_text(stage))
    hidden_line = (f"After the deadline, {hidden['count']} hidden tests ({hidden['points']:g} points) check the "
                   "same tasks on scenes and parameters you have not seen." if hidden["count"] else "")
    scene = stage if (ENGINE_DIR / "scenes" / f"{stage}.json").exists() else "cornell-box"
    earlier = "".join(EARLIER_SECTION.format(number=get_stage(e).number, earlier=e, stage=stage,
                                             source=earlier_source(e), command=copy_command(e))
                      for e in missing_earlier(stage, include_reference))
    (out / "README.md").write_text(README.format(title=st.title, number=st.number, stage=stage, scene=scene,
                                                 handout=f"assignments/{st.handout}/README.md", hidden=hidden_line,
                                                 earlier=earlier))
    (out / MARKER).write_text(json.dumps({"stage": stage, "kit_version": __version__,
                                           "includes_reference": list(include_reference)}, indent=2) + "\n")
    (out / ".gitignore").write_text(GITIGNORE)
    return out
