"""``cs451 autograder build``: the zip Gradescope runs, and ``cs451 autograder run``, what runs inside it.

Gradescope's contract (Ubuntu 22.04, no GPU, 768 MB, 10 minutes by default): the
zip holds ``setup.sh`` (run once, as root, when the image is built) and
``run_autograder`` (run for each submission, as root), which must leave
``/autograder/results/results.json``. The kit installs itself into its own folder
(``/opt/cs451-kit``) so that the unprivileged worker can read the engine while
the reference and hidden tests stay at mode 0700.
"""
from __future__ import annotations

import json
import os
import shutil
import tempfile
import time
import zipfile
from pathlib import Path

from .. import __version__
from ..errors import KitError, SubmissionError
from ..grading.loader import load_tests
from ..stages import get_stage
from .files import LITTER_PATTERNS, copy_tree, write_executable

#: Seconds the whole grading may take inside Gradescope's default 10-minute limit (the rest: start-up and margin).
GRADESCOPE_BUDGET = 480.0

SETUP_SH = """#!/usr/bin/env bash
# Gradescope runs this once, as root, when it builds the autograder image (Ubuntu 22.04, no GPU).
# Built by `cs451 autograder build {stage}` (cs451-kit {version}); do not edit, rebuild instead.
# It leaves nothing a submission could use where a submission could read it: the kit moves to
# $KIT, private to root except the Python environment the sandboxed worker runs; the source
# folder keeps only this script and run_autograder.
set -euo pipefail
SOURCE="$(cd "$(dirname "$0")" && pwd)"           # /autograder/source
KIT="${{CS451_HOME:-/opt/cs451-kit}}"
export DEBIAN_FRONTEND=noninteractive
if [ -z "${{CS451_SKIP_SYSTEM_PACKAGES:-}}" ]; then   # (the kit's tests reuse the machine's packages)
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends python3 python3-venv python3-pip bubblewrap \\
      libegl1 libopengl0 libegl-mesa0 libgl1-mesa-dri >/dev/null   # EGL and GL by versioned names (cs451/gl.py)
fi
rm -rf "$KIT" && mkdir -p "$KIT" && cp -a "$SOURCE/." "$KIT/"
if [ -n "${{CS451_VENV:-}}" ]; then                 # (the kit's tests reuse an environment)
  ln -s "$CS451_VENV" "$KIT/.venv"
else
  /usr/bin/python3 -m venv "$KIT/.venv"
  echo "setup: installing the kit's Python packages (a few minutes)"
  "$KIT/.venv/bin/python" -m pip install --progress-bar off --upgrade pip | tail -n 1
  "$KIT/.venv/bin/python" -m pip install --progress-bar off -e "$KIT" | tail -n 1
fi
# every answer, once per image: the hidden tests' and the public tests' on fresh cases of the same kind, drawn
# from a secret made here (in $KIT/.cs451-cache, private to root below), so a release's answers replay nothing
cd "$KIT" && "$KIT/.venv/bin/python" -m cs451 autograder warm {stage}
chmod -R go-rwx "$KIT" && chmod 0711 "$KIT"       # the worker may pass through to its Python, and read nothing
[ -L "$KIT/.venv" ] || chmod -R a+rX "$KIT/.venv"
find "$SOURCE" -mindepth 1 -maxdepth 1 ! -name setup.sh ! -name run_autograder -exec rm -rf {{}} +
chmod 0700 "$SOURCE"
"""

RUN_AUTOGRADER = """#!/usr/bin/env bash
# Gradescope runs this for every submission, as root. It always leaves results/results.json.
ROOT="${{AUTOGRADER_ROOT:-/autograder}}"
KIT="${{CS451_HOME:-/opt/cs451-kit}}"
PY="${{CS451_PYTHON:-$KIT/.venv/bin/python}}"
mkdir -p "$ROOT/results"
cd "$KIT" && "$PY" -m cs451 autograder run {stage} --submission "$ROOT/submission" \\
    --results "$ROOT/results/results.json" "$@"
status=$?
if [ ! -s "$ROOT/results/results.json" ]; then   # the grader itself died: still leave a result, and say so
  printf '{{"score": 0, "output": "The autograder stopped unexpectedly (exit %s). This is not a verdict on your code; tell your instructor.", "tests": []}}' "$status" > "$ROOT/results/results.json"
fi
exit 0
"""


def build_gradescope(stage: str, output: str | Path) -> Path:
    """Write the Gradescope autograder zip for ``stage``; returns its path."""
    st = get_stage(stage)
    tests = load_tests(stage)  # fails here, not on Gradescope, if a spec is broken
    output = Path(output)
    with tempfile.TemporaryDirectory(prefix="cs451-gradescope-") as tmp:
        root = Path(tmp)
        for rel in ("cs451", "reference", "autograder", "pyproject.toml", "README.md"):
            copy_tree(rel, root, ignore=shutil.ignore_patterns(*LITTER_PATTERNS, "answers"))
        write_executable(root / "setup.sh", SETUP_SH.format(stage=stage, version=__version__))
        write_executable(root / "run_autograder", RUN_AUTOGRADER.format(stage=stage))
        manifest = {"stage": stage, "title": st.title, "kit_version": __version__,
                    "built": time.strftime("%Y-%m-%d %H:%M:%S"), "tests": len(tests),
                    "hidden_tests": sum(t.hidden for t in tests), "points": sum(t.points for t in tests),
                    "time_budget_s": GRADESCOPE_BUDGET}
        (root / "autograder.json").write_text(json.dumps(manifest, indent=2) + "\n")
        output.parent.mkdir(parents=True, exist_ok=True)
        # the zip holds the reference and the hidden tests: private to the instructor (a readable one in the kit's
        # folder reached the uid-only sandbox), whatever the umask or an older file's mode
        fd = os.open(output, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
        os.fchmod(fd, 0o600)
        with os.fdopen(fd, "wb") as raw, zipfile.ZipFile(raw, "w", zipfile.ZIP_DEFLATED) as zf:
            for path in sorted(root.rglob("*")):
                if path.is_file():
                    info = zipfile.ZipInfo.from_file(path, path.relative_to(root).as_posix())
                    info.compress_type = zipfile.ZIP_DEFLATED
                    zf.writestr(info, path.read_bytes())
    return output


#: Memory for everything one test of a submission starts, together: Gradescope gives the container 768 MB,
#: and the grader itself needs the rest (measured by `cs451 bench autograder`).
GRADESCOPE_SUBMISSION_MEMORY = 448 << 20


def run_gradescope(stage: str, submission: str | Path, results: str | Path,
                   budget: float = GRADESCOPE_BUDGET, tasks: list[str] | None = None) -> int:
    """Grade one Gradescope submission into ``results`` (results.json); always writes it.

    ``tasks`` keeps only those tasks' tests (the kit's own tests use it; Gradescope never passes it)."""
    from ..grading.results import write_failure, write_results
    from ..grading.runner import grade
    results = Path(results)
    results.parent.mkdir(parents=True, exist_ok=True)
    root = Path(os.environ.get("AUTOGRADER_ROOT", "/autograder"))
    try:
        result = grade(stage, Path(submission), include_hidden=True, show_progress=False, jobs=1, total_timeout=budget,
                       tasks=tasks,
                       protected=(root / "source",), unwritable=(results.parent,),
                       submission_memory=GRADESCOPE_SUBMISSION_MEMORY)
    except SubmissionError as err:  # nothing gradable was uploaded: say what is expected
        write_failure(results, str(err), blame_submission=True)
        return 0
    except KitError as err:         # e.g. no isolation here: grading must not go on
        write_failure(results, str(err))
        return 0
    except BaseException as err:
        write_failure(results, f"{type(err).__name__}: {err}")
        raise
    write_results(results, result)
    return 0


def unpack_like_gradescope(zip_path: Path, top: Path) -> Path:
    """Unpack an autograder zip into ``top/autograder/source`` as Gradescope does; returns ``top/autograder``."""
    root = top / "autograder"
    (root / "source").mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(zip_path) as zf:
        zf.extractall(root / "source")
    for script in ("setup.sh", "run_autograder"):
        (root / "source" / script).chmod(0o755)
    for path in [top, root, *root.rglob("*")]:
        if path.is_dir():
            path.chmod(0o755)
    return root


def simulated_env(root: Path, venv: str) -> dict[str, str]:
    """The environment for the zip's own scripts in ``root`` (``top/autograder``), outside Gradescope.

    The kit goes to ``top/opt/cs451-kit`` as setup.sh would put it in ``/opt``; the system packages
    are taken as installed and the Python environment ``venv`` is reused (building one takes minutes).
    Nothing else is inherited from the caller: Gradescope's root shell has none of this machine's
    ``PYTHON*`` settings (``PYTHONDONTWRITEBYTECODE`` once hid bytecode left readable in the kit).
    """
    kit = root.parent / "opt" / "cs451-kit"
    return {"PATH": "/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin", "HOME": os.environ.get("HOME", "/root"),
            "LANG": "C.UTF-8", "AUTOGRADER_ROOT": str(root), "CS451_HOME": str(kit), "CS451_SKIP_SYSTEM_PACKAGES": "1",
            "CS451_VENV": venv, "CS451_PYTHON": str(kit / ".venv" / "bin" / "python")}


def setup_like_gradescope(zip_path: Path, top: Path, venv: str) -> tuple[Path, dict[str, str]]:
    """Unpack the zip and run its own setup.sh as Gradescope would; returns ``top/autograder`` and the environment."""
    import subprocess
    root = unpack_like_gradescope(zip_path, top)
    env = simulated_env(root, venv)
    (root.parent / "opt").mkdir(exist_ok=True)
    done = subprocess.run([str(root / "source" / "setup.sh")], env=env, capture_output=True, text=True, timeout=1800)
    if done.returncode != 0:
        raise KitError(f"the autograder's setup.sh failed (exit {done.returncode}): {done.stderr[-2000:]}")
    return root, env
