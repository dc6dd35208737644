"""``pip install .`` gives a working ``cs451``: the wheel carries the kit beside the engine (setup.py).

The fast test builds the wheel, reads what it holds, and runs the installed command on the trusted paths
(rendering, the reference's grade, the starter check) in a venv that borrows this one's dependencies.
The slow one installs the wheel with its dependencies into a fresh venv, as an instructor would, and
grades a folder there: the submission runs in the sandbox, which must hide the installed kit.
"""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest

from cs451 import KIT_ROOT

from conftest import world_readable_dir

#: a Python the sandbox user can run (a venv made from a private interpreter, under /root, cannot be)
BASE_PYTHON = shutil.which("python3.11", path="/usr/bin:/usr/local/bin") or sys.executable


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("wheel")
    before = set(os.listdir(KIT_ROOT))
    done = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", str(KIT_ROOT),
                           "-w", str(out)], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert set(os.listdir(KIT_ROOT)) - before <= {"cs451_kit.egg-info"}, "the build left litter in the checkout"
    return next(out.glob("*.whl"))


@pytest.mark.spawns
def test_the_wheel_carries_the_kit_beside_the_engine_and_no_litter(wheel):
    names = zipfile.ZipFile(wheel).namelist()
    tops = {n.split("/")[0] for n in names}
    assert tops == {"cs451", "cs451_kit", next(t for t in tops if t.endswith(".dist-info"))}
    for part in ("reference/sphere/__init__.py", "starter/sphere/__init__.py", "autograder/sphere/public.py",
                 "assignments/01-sphere/README.md", "setup.sh", "KIT"):
        assert f"cs451_kit/{part}" in names, part
    assert "cs451/scenes/sphere.json" in names
    for part in ("slides/templates/deck.html.j2", "slides/templates/deck.js", "slides/vendor/reveal.js/reveal.js",
                 "slides/vendor/reveal.js/plugin/notes.js", "slides/vendor/katex/fonts/KaTeX_Main-Regular.woff2",
                 "slides/vendor/katex/LICENSE"):        # `cs451 slides build` from an installed kit
        assert f"cs451/{part}" in names, part
    assert "cs451_kit/slides/04-radiosity.md" in names
    assert not [n for n in names if n.startswith("cs451/") and "reference" in n.split("/")[:-1]]
    assert not [n for n in names if "__pycache__" in n or n.endswith(".pyc") or ".cs451-cache" in n]


def _venv(path: Path, borrow: bool) -> Path:
    subprocess.run([BASE_PYTHON, "-m", "venv", str(path)], check=True, timeout=120)
    python = path / "bin" / "python"
    if borrow:        # this venv's packages, without its editable cs451 (a .pth line adds the folder only)
        site = subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                              capture_output=True, text=True, check=True).stdout.strip()
        Path(site, "borrowed.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    return python


def _cs451(venv_python: Path, *args: str, cwd: Path) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "CS451_HOME")}
    return subprocess.run([str(venv_python.parent / "cs451"), *args], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=600)


@pytest.mark.spawns
def test_the_installed_command_renders_and_grades_away_from_the_checkout(wheel, tmp_path):
    python = _venv(tmp_path / "venv", borrow=True)
    subprocess.run([str(python), "-m", "pip", "install", "-q", "--no-deps", str(wheel)], check=True, timeout=300)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    where = subprocess.run([str(python), "-c", "import cs451; print(cs451.KIT_ROOT)"], cwd=elsewhere,
                           capture_output=True, text=True, check=True).stdout.strip()
    assert where.endswith("site-packages/cs451_kit"), where
    done = _cs451(python, "render", "sphere", "-o", "s.png", "--size", "64x64", cwd=elsewhere)
    assert done.returncode == 0 and (elsewhere / "s.png").exists(), done.stderr
    done = _cs451(python, "starter", "--check", cwd=elsewhere)
    assert done.returncode == 0 and "in step" in done.stdout, done.stdout + done.stderr
    done = _cs451(python, "grade", "sphere", "--submission", "reference", "--tasks", "S1,S2", cwd=elsewhere)
    assert done.returncode == 0 and "total with the hidden tests: 20 / 20" in done.stdout, done.stdout[-1500:] + done.stderr[-1500:]


STEAL = """
try:
    import importlib.util as _u
    _spec = _u.spec_from_file_location("_stolen", "{reference}/__init__.py", submodule_search_locations=["{reference}"])
    _mod = _u.module_from_spec(_spec)
    _spec.loader.exec_module(_mod)
    globals().update({{k: getattr(_mod, k) for k in dir(_mod) if not k.startswith("_")}})
except Exception:
    pass
"""


@pytest.mark.spawns
@pytest.mark.slow
def test_a_fresh_venv_installs_the_wheel_and_grades_a_folder_in_the_sandbox(wheel):
    top = world_readable_dir("cs451-wheel-")
    try:
        python = _venv(top / "venv", borrow=False)
        done = subprocess.run([str(python), "-m", "pip", "install", "-q", str(wheel)], capture_output=True, text=True,
                              timeout=900)
        assert done.returncode == 0, done.stderr[-2000:]
        shutil.copytree(KIT_ROOT / "reference" / "sphere", top / "mine" / "sphere",
                        ignore=shutil.ignore_patterns("__pycache__"))
        os.system(f"chmod -R a+rX {top}")
        done = _cs451(python, "grade", "sphere", "--submission", str(top / "mine"), cwd=top)
        assert done.returncode == 0 and "total with the hidden tests: 100 / 100" in done.stdout, done.stdout[-2000:] + done.stderr[-1500:]
        assert "isolation: bubblewrap" in done.stdout

        # the starter, which takes the installed kit's reference if it can read it: it must score nothing (exit 1:
        # under full marks)
        site = subprocess.run([str(python), "-c", "import cs451_kit, os; print(os.path.dirname(cs451_kit.__path__[0]))"],
                              capture_output=True, text=True).stdout.strip() or str(next((top / "venv" / "lib").glob(
                                  "python3*/site-packages")))
        shutil.copytree(KIT_ROOT / "starter" / "sphere", top / "thief" / "sphere", ignore=shutil.ignore_patterns("__pycache__"))
        init = top / "thief" / "sphere" / "__init__.py"
        init.write_text(init.read_text() + STEAL.format(reference=f"{site}/cs451_kit/reference/sphere"))
        os.system(f"chmod -R a+rX {top}")
        done = _cs451(python, "grade", "sphere", "--submission", str(top / "thief"), cwd=top)
        assert done.returncode == 1 and "total with the hidden tests: 0 / 100" in done.stdout, done.stdout[-2000:] + done.stderr[-1500:]
    finally:
        shutil.rmtree(top, ignore_errors=True)
