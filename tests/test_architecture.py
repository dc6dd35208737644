"""The recipes of docs/adding-a-stage.md, followed on a toy fifth stage in a copy of the kit.

Adding a stage must touch only the files the recipe names, and the new stage must then pass the
same contract, handout and scene-kind tests as the four real ones. The layering rule is checked
too: no module of the engine imports a stage module.
"""
from __future__ import annotations

import ast
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from cs451 import KIT_ROOT

from conftest import world_readable_dir
from imports import CODE, import_graph, private_reaches, single_stage_modules, stages_using
from toy_stage import DERIVED, EDITS, RECIPE, apply_edit

def tracked_files() -> list[str]:
    out = subprocess.run(["git", "ls-files", "-z"], cwd=KIT_ROOT, capture_output=True, check=True).stdout
    return [f for f in out.decode().split("\0") if f and (KIT_ROOT / f).is_file()]


def run(cmd: list[str], cwd: Path, timeout: float = 600) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(cwd), "PYTHONDONTWRITEBYTECODE": "1"}
    env.pop("CS451_HOME", None)
    return subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)


#: What tests/test_stage_lists.py said in the toy's kit before the recipe's lines were added to the lists of stages.
LISTS_BEFORE: dict[Path, subprocess.CompletedProcess] = {}


@pytest.fixture(scope="module")
def kit_with_toy_stage():
    """A copy of the kit's tracked files (as committed in git there), with the toy stage added by the recipe: its files
    first; then, once the lists of stages have been checked without it (:data:`LISTS_BEFORE`), its lines in them."""
    top = world_readable_dir("cs451-toy-")
    kit = top / "kit"
    for rel in tracked_files():
        (kit / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(KIT_ROOT / rel, kit / rel)
    git = ["git", "-c", "user.name=t", "-c", "user.email=t@t", "-c", "commit.gpgsign=false"]
    subprocess.run(git + ["init", "-q"], cwd=kit, check=True)
    subprocess.run(git + ["add", "-A"], cwd=kit, check=True)
    subprocess.run(git + ["commit", "-qm", "kit"], cwd=kit, check=True)
    for rel, text in RECIPE.items():
        (kit / rel).parent.mkdir(parents=True, exist_ok=True)
        (kit / rel).write_text(text)
    done = run([sys.executable, "-m", "cs451", "starter"], kit)
    assert done.returncode == 0, done.stderr
    LISTS_BEFORE[kit] = run([sys.executable, "-m", "pytest", "-q", "-n", "0", "-p", "no:cacheprovider", "-k", "test_every_list",
                             "tests/test_stage_lists.py"], kit)
    for rel, anchor, line in EDITS:
        (kit / rel).write_text(apply_edit((kit / rel).read_text(), anchor, line))
    yield kit
    shutil.rmtree(top, ignore_errors=True)


@pytest.mark.spawns
def test_the_recipe_touches_only_the_files_it_names(kit_with_toy_stage):
    status = run(["git", "status", "--porcelain", "--untracked-files=all"], kit_with_toy_stage).stdout
    changed = {line[3:] for line in status.splitlines()}
    named = set(RECIPE) | DERIVED | {rel for rel, _, _ in EDITS}
    assert changed == named, sorted(changed ^ named)


@pytest.mark.spawns
def test_a_stage_left_out_of_a_list_of_stages_fails_a_test(kit_with_toy_stage):
    """Before the recipe's lines went into the lists of stages, every list's test failed in the toy's kit, naming the
    toy: no list a person keeps can silently leave a stage out."""
    from test_stage_lists import LISTS
    said = LISTS_BEFORE[kit_with_toy_stage].stdout
    failed = re.findall(r"^FAILED [^\[\n]+\[(.*?)\](?: - |$)", said, re.M)
    assert sorted(failed) == sorted(f"{path}: {what}" for path, what, _ in LISTS), said[-3000:]
    assert said.count("no entry for ['toy']") >= len(LISTS), said[-3000:]


@pytest.mark.spawns
def test_the_toy_stage_passes_every_test_of_a_stage(kit_with_toy_stage):
    """Every stage-parametrised test of the contract, the handouts, the scene kinds, the demos and the benchmarks on
    the toy (slow ones too), every list of stages, and the deck showing a figure of the toy's own."""
    done = run([sys.executable, "-m", "pytest", "-q", "-n", "0", "-p", "no:cacheprovider", "-m", "slow or not slow", "-k", "toy",
                "tests/test_stage_contract.py", "tests/test_handout.py", "tests/test_scene_kinds.py",
                "tests/test_demo_screen.py", "tests/test_benches.py"], kit_with_toy_stage)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-2000:]
    summary = done.stdout.strip().splitlines()[-1]
    assert " passed" in summary and "failed" not in summary and "skipped" not in summary, summary
    assert int(summary.split(" passed")[0].split()[-1]) >= 13, summary  # 5 contract, 6 handout, 2 scene kinds, demo, bench
    done = run([sys.executable, "-m", "pytest", "-q", "-n", "0", "-p", "no:cacheprovider", "tests/test_stage_lists.py",
                "tests/test_slides.py::test01_every_stage_s_deck_shows_a_figure_of_its_own"], kit_with_toy_stage)
    assert done.returncode == 0 and "failed" not in done.stdout, done.stdout[-3000:] + done.stderr[-2000:]


@pytest.mark.spawns
def test_the_toy_stage_works_from_the_command_line(kit_with_toy_stage):
    """Render, grade, demo, benchmark and its deck, as a user types them."""
    kit = kit_with_toy_stage
    done = run([sys.executable, "-m", "cs451", "render", "cornell-box", "--stage", "toy", "-o", str(kit / "t.png"),
                "--size", "8x6"], kit)
    assert done.returncode == 0 and (kit / "t.png").exists(), done.stderr
    done = run([sys.executable, "-m", "cs451", "grade", "toy", "--submission", "starter"], kit)
    assert "0/100" in done.stdout.replace(" ", "") or "0.0/100" in done.stdout.replace(" ", ""), done.stdout[-1500:]
    done = run([sys.executable, "-m", "cs451", "demo", "toy", "--no-window", "-o", str(kit / "demo")], kit)
    assert done.returncode == 0 and (kit / "demo" / "toy.gif").is_file(), done.stderr[-2000:]
    done = run([sys.executable, "-m", "cs451", "bench", "toy", "--quick", "-o", str(kit / "bench")], kit)
    assert done.returncode == 0 and (kit / "bench" / "toy.json").is_file(), done.stderr[-2000:]
    done = run([sys.executable, "-m", "cs451", "slides", "build", "toy", "--quick", "-o", str(kit / "html"),
                "--cache", str(kit / "cache")], kit)
    assert done.returncode == 0 and "toy-scaled" in (kit / "html" / "toy.html").read_text(), done.stderr[-2000:]


def test_no_engine_module_imports_a_stage_module():
    """The engine (everything in cs451/ but stages/) may use the registry, never a particular stage."""
    stage_modules = {p.name for p in (KIT_ROOT / "cs451" / "stages").iterdir() if (p / "__init__.py").is_file()}
    offenders = []
    for path in (KIT_ROOT / "cs451").rglob("*.py"):
        if "stages" in path.relative_to(KIT_ROOT / "cs451").parts:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            names = []
            if isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module + "." + a.name for a in node.names]
            elif isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            for name in names:
                parts = name.split(".")
                if "stages" in parts and any(p in stage_modules for p in parts[parts.index("stages") + 1:]):
                    offenders.append(f"{path.relative_to(KIT_ROOT)}: {name}")
    assert not offenders, offenders


def test_the_architecture_documents_name_modules_that_exist():
    text = "\n".join((KIT_ROOT / "docs" / name).read_text() for name in ("ARCHITECTURE.md", "adding-a-stage.md"))
    import re
    for path in set(re.findall(r"`((?:cs451|tests|bench)/[\w/.]+?\.py)`", text)):
        assert (KIT_ROOT / path).is_file(), path
    for name in set(re.findall(r"`((?:stages|grading|packaging|demos|formfactors)/[\w.]+?)`", text)):
        if "<" not in name:
            assert (KIT_ROOT / "cs451" / name).exists() or (KIT_ROOT / "cs451" / (name + ".py")).exists(), name


def test_no_module_outside_a_stage_package_names_a_stage():
    """The engine and the tools ask the registry; a stage's name as a literal lives only in its own package
    (and in the package of a stage that builds on it). A scene kind registered by name ("sphere") is the scene
    format's word, not a stage's."""
    import re
    names = "|".join(p.name for p in (KIT_ROOT / "cs451" / "stages").iterdir() if (p / "__init__.py").is_file())
    literal = re.compile(rf"""["']({names})["']""")
    offenders = []
    for path in (KIT_ROOT / "cs451").rglob("*.py"):
        rel = path.relative_to(KIT_ROOT / "cs451")
        if rel.parts[0] == "stages" and len(rel.parts) > 2:
            continue
        tree = ast.parse(path.read_text())
        kinds = {id(arg) for node in ast.walk(tree) if isinstance(node, ast.Call)           # scene kinds ("sphere")
                 and isinstance(node.func, ast.Attribute) and node.func.attr == "register" for arg in node.args}
        for node in ast.walk(tree):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and literal.fullmatch(repr(node.value)) \
                    and id(node) not in kinds:
                offenders.append(f"{rel}:{node.lineno}: {node.value!r}")
    assert not offenders, offenders


def test_the_engine_has_no_import_cycle():
    """No import cycle between the modules of cs451/ (function-level imports included, type-checking ones not: they
    never run), measured on the source."""
    graph = import_graph(KIT_ROOT, ("cs451",))
    cycles, state = [], {}

    def visit(node: str, stack: list[str]) -> None:
        state[node] = 1
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                cycles.append(stack[stack.index(nxt):] + [nxt] if nxt in stack else [node, nxt])
            elif nxt not in state:
                visit(nxt, stack + [nxt])
        state[node] = 2
    for node in sorted(graph):
        if node not in state:
            visit(node, [node])
    assert not cycles, "\n".join(" -> ".join(c) for c in cycles[:10])


def test_a_module_that_serves_one_stage_lives_in_that_stage_s_package():
    """Judged by the import graph, not by names: a module outside ``cs451/stages/<s>/`` that only stage s's modules
    (its package, reference or autograder, or modules that themselves serve s alone) import belongs in s's package;
    ``cs451/`` keeps what two or more stages share."""
    from cs451.stages import stage_names
    found = single_stage_modules(import_graph(KIT_ROOT), set(stage_names()))
    assert not found, {name: f"serves {stage} alone: move it into cs451/stages/{stage}/" for name, stage in found.items()}


def test_a_stage_reaches_another_only_through_its_interface():
    """A stage may use an earlier stage's interface (its package: ``from ..hemicube import calls``), never another
    module of that stage's package (its figures, demo or benchmarks)."""
    from cs451.stages import stage_names
    assert not private_reaches(import_graph(KIT_ROOT), set(stage_names()))


def test_the_architecture_names_what_cs451_shares_and_with_whom():
    """docs/ARCHITECTURE.md's table "What cs451/ shares, and with whom": every module or package of the shared engine
    that some stages use but not all is a row, and its "shared by" is the import graph's."""
    from cs451.stages import stage_names
    stages = set(stage_names())
    users = stages_using(import_graph(KIT_ROOT), stages)
    text = (KIT_ROOT / "docs" / "ARCHITECTURE.md").read_text()
    section = text.split("## What `cs451/` shares, and with whom", 1)[1].split("\n## ", 1)[0]
    rows = re.findall(r"^\| (`[^|]+`) \| ([a-z, ]+) \| ", section, re.M)
    assert rows, "no table of what cs451/ shares"

    def used_by(entry: str) -> set[str]:
        if entry.endswith("/"):                      # a package: what its modules serve, as one
            package = "cs451." + entry.strip("/").replace("/", ".")
            return set().union(*(u for m, u in users.items() if m == package or m.startswith(package + ".")))
        return users["cs451." + entry.removesuffix(".py").replace("/", ".")]
    listed = set()
    for names, shared in rows:
        for entry in re.findall(r"`([^`]+)`", names):
            listed.add(entry)
            assert used_by(entry) == set(shared.split(", ")), f"{entry}: shared by {sorted(used_by(entry))}"
    engine = [m for m in users if m.startswith("cs451.") and not m.startswith("cs451.stages")]
    packages = {m.split(".")[1] + "/" for m in engine if m.count(".") >= 2}
    tops = {m.split(".")[1] + ".py" for m in engine if m.count(".") == 1 and m.split(".")[1] + "/" not in packages}
    for entry in sorted(packages | tops):
        if 1 < len(used_by(entry)) < len(stages):
            assert entry in listed, f"{entry} is shared by {sorted(used_by(entry))}: add it to the table"


def test_the_import_checks_find_a_planted_module(tmp_path):
    """The two checks above, on a copy of the kit's code with a module planted outside radiosity's package that only
    radiosity imports, and a stage importing another's figures: each is found (the checks can fail)."""
    from cs451.stages import stage_names
    for top in CODE:
        for path in (KIT_ROOT / top).rglob("*.py"):
            if "vendor" not in path.parts:
                (tmp_path / path.relative_to(KIT_ROOT)).parent.mkdir(parents=True, exist_ok=True)
                (tmp_path / path.relative_to(KIT_ROOT)).write_text(path.read_text())
    (tmp_path / "cs451" / "planted.py").write_text("def helper():\n    return 1\n")
    (tmp_path / "cs451" / "planted_too.py").write_text("from .planted import helper\n")
    demo = tmp_path / "cs451" / "stages" / "radiosity" / "demo.py"
    demo.write_text(demo.read_text() + "\nfrom ...planted_too import helper  # noqa\nfrom ..whitted.figures import FIGURES\n")
    graph = import_graph(tmp_path)
    assert single_stage_modules(graph, set(stage_names())) == {"cs451.planted": "radiosity",
                                                               "cs451.planted_too": "radiosity"}
    assert private_reaches(graph, set(stage_names())) == ["cs451.stages.radiosity.demo imports cs451.stages.whitted.figures"]


#: Modules allowed past the limit, each with why; the list may only shrink.
LONG_MODULES = {
    # the Whitted speed layer's kernels: numba's cache checks only the file a kernel is defined in, and the frame
    # kernel inlines the traversal, so split across files a changed helper would run as stale machine code
    "cs451/stages/whitted/accel/kernels.py": 900,
}
MODULE_LINES = 450


def test_no_module_is_longer_than_a_reader_can_hold():
    long = {}
    for top in ("cs451", "reference", "autograder"):
        for path in (KIT_ROOT / top).rglob("*.py"):
            rel = path.relative_to(KIT_ROOT).as_posix()
            if "vendor" in path.parts or "__pycache__" in path.parts:
                continue
            lines = len(path.read_text().splitlines())
            if lines > LONG_MODULES.get(rel, MODULE_LINES):
                long[rel] = lines
    assert not long, f"modules over {MODULE_LINES} lines (split them by job): {long}"


def test_a_stage_imports_another_only_where_it_builds_on_it():
    """A stage's package names another stage's package only where its ``builds_on`` declares it (radiosity runs the
    hemicube): the deck figures of one stage do not borrow another's."""
    import ast
    from cs451.stages import get_stage, stage_names
    names = set(stage_names())
    found = []
    for stage in names:
        allowed = set(get_stage(stage).builds_on) | {stage}
        for path in (KIT_ROOT / "cs451" / "stages" / stage).rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, ast.ImportFrom):
                    parts = ("." * node.level + (node.module or "")).split(".")
                    other = {p for p in parts if p in names} - allowed
                    if other:
                        found.append(f"{path.relative_to(KIT_ROOT)}: {sorted(other)}")
    assert not found, found


def test_every_public_function_of_the_grader_and_the_stages_says_why():
    """Every public function and method in cs451/grading/ and cs451/stages/ has a docstring: these are the parts a new
    engineer reads first (the sandbox, and each stage's interface and probes)."""
    missing = []
    for top in ("grading", "stages"):
        for path in sorted((KIT_ROOT / "cs451" / top).rglob("*.py")):
            def walk(node: ast.AST, prefix: str) -> None:
                for child in ast.iter_child_nodes(node):
                    if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)) and not child.name.startswith("_") \
                            and ast.get_docstring(child) is None:
                        missing.append(f"{path.relative_to(KIT_ROOT)}:{child.lineno} {prefix}{child.name}")
                    elif isinstance(child, ast.ClassDef) and not child.name.startswith("_"):
                        walk(child, f"{prefix}{child.name}.")
            walk(ast.parse(path.read_text()), "")
    assert not missing, f"{len(missing)} public functions without a docstring: {missing[:20]}"


def test_every_stage_is_named_as_its_package():
    """``get_stage(name)`` imports the package of that name alone (a grading worker pays for one stage, not five):
    every stage's name must be its package's."""
    from cs451.stages import _module_names, get_stage, stage_names
    assert sorted(stage_names()) == sorted(_module_names())
    assert all(get_stage(name).name == name for name in stage_names())
