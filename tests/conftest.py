"""Shared fixtures: the kit root, a scratch copy of the reference for broken-submission tests."""
from __future__ import annotations

import os
import re
import shutil
import tempfile
from pathlib import Path

import pytest

from cs451 import KIT_ROOT

import selection


def pytest_configure(config: pytest.Config) -> None:
    selection.register_markers(config)


@pytest.hookimpl(tryfirst=True)          # before pytest's own -m selection reads the markers
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    selection.mark_and_select(config, items)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_setup(item: pytest.Item):
    with selection.watching_spawns(item):      # a fixture that starts a process counts for the test that asked for it
        return (yield)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_call(item: pytest.Item):
    with selection.watching_spawns(item):
        result = yield
    selection.check_spawns(item)
    return result


@pytest.fixture
def kit_root() -> Path:
    return KIT_ROOT


@pytest.fixture
def make_submission(tmp_path: Path):
    """Copy reference/<stage> into a temporary submission and apply text replacements to one file."""
    def make(stage: str, file: str | None = None, old: str = "", new: str = "", name: str = "sub") -> Path:
        root = tmp_path / name
        shutil.copytree(KIT_ROOT / "reference" / stage, root / stage,
                        ignore=shutil.ignore_patterns("__pycache__"))
        if file is not None:
            path = root / stage / file
            text = path.read_text()
            assert old in text, f"{old!r} not in {file}"
            path.write_text(text.replace(old, new, 1))
        return root
    return make


def world_readable_dir(prefix: str) -> Path:
    """A scratch folder the grader's sandbox user may enter (pytest's tmp_path is private to root)."""
    import os
    import tempfile
    path = Path(tempfile.mkdtemp(prefix=prefix))
    os.chmod(path, 0o755)
    return path


def clean_env(home: Path, *bin_dirs: Path) -> dict[str, str]:
    """What ``env -i HOME=<home> PATH=<bin_dirs>:/usr/bin:/bin`` leaves: nothing of this machine's environment (no
    PIP_*, PYTHON*, DISPLAY, no kit venv on PATH), so a command sees what a user's fresh shell would."""
    home.mkdir(parents=True, exist_ok=True)
    return {"HOME": str(home), "PATH": ":".join([*(str(b) for b in bin_dirs), "/usr/bin", "/bin"])}


def set_up_release(release: Path, home: Path) -> dict[str, str]:
    """A student's repository set up as its README says (its own ``./setup.sh``, which makes ``.venv`` from this
    machine's registries, in a clean environment); returns the environment of a student's shell after
    ``source .venv/bin/activate``: the release's ``.venv/bin`` and the system's folders on PATH, nothing else."""
    import subprocess
    done = subprocess.run(["./setup.sh"], cwd=release, env=clean_env(home), capture_output=True, text=True,
                          timeout=1800)
    assert done.returncode == 0, f"setup.sh failed:\n{done.stdout[-2000:]}\n{done.stderr[-3000:]}"
    assert (release / ".venv" / "bin" / "cs451").is_file(), "setup.sh made no .venv/bin/cs451"
    return clean_env(home, release / ".venv" / "bin")


@pytest.fixture(scope="session")
def gradescope(request) -> tuple[Path, dict]:
    """Stage 1's autograder zip in Gradescope's layout, after its own setup.sh ran (the kit moved to opt/)."""
    import sys
    from cs451.packaging.gradescope import build_gradescope, setup_like_gradescope
    top = world_readable_dir("cs451-gs-")
    request.addfinalizer(lambda: shutil.rmtree(top, ignore_errors=True))
    return setup_like_gradescope(build_gradescope("sphere", top / "autograder.zip"), top, sys.prefix)


@pytest.fixture(scope="session")
def reference_grade_of():
    """``reference_grade_of(stage)``: the reference's grade of a stage, graded once per session and shared."""
    from cs451.grading.runner import grade
    cache: dict = {}

    def of(stage: str):
        if stage not in cache:
            cache[stage] = grade(stage, "reference", show_progress=False)
        return cache[stage]
    return of


@pytest.fixture(scope="session")
def bench_run(tmp_path_factory):
    """``bench_run(name)``: ``cs451 bench NAME --quick`` run once a session through the console script; returns (its
    output folder, the finished process). The benchmarks' smoke test and a stage's own tests of its benchmark read the
    same run. The environment is the tests' own (a copy of the kit run from its folder keeps its PYTHONPATH), without
    a display: the plots are files."""
    import subprocess
    import sys
    runs: dict = {}

    def run(name: str):
        if name not in runs:
            folder = tmp_path_factory.mktemp(f"bench-{name}")
            env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
            done = subprocess.run([str(Path(sys.executable).with_name("cs451")), "bench", name, "--quick", "-o",
                                   str(folder / "out")], cwd=folder, env=env, capture_output=True, text=True,
                                  timeout=1800)
            runs[name] = (folder / "out", done)
        return runs[name]
    return run


@pytest.fixture(autouse=True)
def speed_layers_choose_as_in_a_fresh_process():
    """A stage's speed layer runs every batch compiled once a large one has paid for the kernels: forget that
    before every test, so which path a test runs never depends on the tests before it."""
    import sys
    for name, module in list(sys.modules.items()):
        if name.startswith("cs451.stages.") and callable(getattr(module, "forget_compiled", None)):
            module.forget_compiled()
    yield


def assert_images_match(target, mine, tolerance, what: str, labels: tuple[str, str] = ("truth", "kit")):
    """``compare_images`` as the image tests judge, returning its comparison; on failure the assertion names the
    picture it wrote (both images, the grader's error map and ꟻLIP's, side by side) in ``$CS451_TEST_PICTURES``
    (default: cs451-test-pictures in the temporary folder), so a failing image test shows where, not only how much."""
    from cs451.compare import compare_images
    from cs451.side_by_side import side_by_side
    comparison = compare_images(target, mine, tolerance)
    if not comparison.passed:
        folder = Path(os.environ.get("CS451_TEST_PICTURES") or Path(tempfile.gettempdir()) / "cs451-test-pictures")
        folder.mkdir(parents=True, exist_ok=True)
        picture = folder / (re.sub(r"[^\w.-]+", "-", what).strip("-")[:120] + ".png")
        side_by_side(target, mine, picture, tolerance, labels)
        raise AssertionError(f"{what}: {comparison.message}; difference picture: {picture}")
    return comparison

