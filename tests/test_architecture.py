"""The recipes of docs/adding-a-stage.md, followed on a toy fifth stage in a copy of the kit.

Adding a stage must touch only the files the recipe names, and the new stage must then pass the
same contract, handout and scene-kind tests as the four real ones. The layering rule is checked
too: no module of the engine imports a stage module.
"""
from __future__ import annotations

import ast
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from cs451 import KIT_ROOT

from conftest import world_readable_dir

TOY_STAGE = '''\
"""Stage 6 (a toy, for the architecture test): scale a colour; the image is the scaled colour."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ... import schema
from ...errors import KitError
from ...scene import AreaLight, Polygon, Scene
from ...schema import field
from ..base import Out, Probes, Stage, Task

TASKS = (Task("T1", "scale", "Scaling a colour", ("values", "factor"), (Out("scaled", ("len(values)",)),)),)


@dataclass(frozen=True)
class ToyOptions:
    factor: float = field("What the colour is scaled by.", 0.5, schema.positive)


def render(scene: Scene, impl: Any, size: tuple[int, int] | None = None, **_: Any) -> np.ndarray:
    """The polygons' mean diffuse colour, scaled by T1; any other kind is refused (a consumer never skips)."""
    for group in ("objects", "lights"):
        for k, item in enumerate(getattr(scene, group)):
            if not isinstance(item, (Polygon, AreaLight)):
                raise KitError(f"{scene.label}: {group}[{k}]: the toy stage has no {type(item).__name__}")
    diffuse = [scene.material(o.material).diffuse for o in scene.objects] or [(0.0, 0.0, 0.0)]
    colour = STAGE.call(impl, "T1", np.mean(diffuse, axis=0), STAGE.options(scene).factor)
    w, h = size or (scene.image.width, scene.image.height)
    return np.broadcast_to(colour, (h, w, 3)).copy()


PROBES = Probes()


@PROBES.register
def probe_scale(impl: Any, values: list, factor: float) -> dict[str, np.ndarray]:
    return {"scaled": STAGE.call(impl, "T1", np.asarray(values, dtype=np.float64), float(factor))}


STAGE = Stage(name="toy", number=6, title="A toy stage", handout="06-toy", tasks=TASKS, render=render,
              probes=PROBES, options_type=ToyOptions, draws=(Polygon, AreaLight))
'''

TOY_REFERENCE = '''\
"""The toy stage's solution."""
import numpy as np


def scale(values, factor):
    """``values`` times ``factor`` (handout §T1)."""
    # BEGIN SOLUTION T1: multiply every value by the factor (handout §T1)
    return np.asarray(values, dtype=np.float64) * factor
    # END SOLUTION
'''

TOY_TESTS = '''\
"""Toy {kind} tests."""
from cs451.grading.checks import array_close
from cs451.grading.spec import Test

SCALED = array_close("scaled", truth_key="scaled", what="the scaled values")
TESTS = [Test("T1 scale: {name}", "T1", {points}, "scale", {{"values": {values}, "factor": {factor}}}, SCALED,
              "entries within 1e-6 relative"),
         Test("T1 scale: {name}, negated", "T1", {points}, "scale", {{"values": {values}, "factor": -{factor}}}, SCALED,
              "entries within 1e-6 relative")]
'''

TOY_HANDOUT = '''\
# Stage 6: a toy stage

Scale a colour. Render it with `cs451 render cornell-box --stage toy -o toy.png` and check it with
`cs451 grade toy --public-only`.

| Task | Function | Points |
|---|---|---|
| T1 | `scale` | 100 |
| Total | | 100 |

### T1 Scaling a colour

```python
def scale(values, factor):
```

Return `values` times `factor`.
'''

#: every file the recipe names for a stage called "toy" (the starter is derived by `cs451 starter`)
RECIPE = {
    "cs451/stages/toy/__init__.py": TOY_STAGE,
    "cs451/stages/toy/adversary.py": 'HEADER = ""\nNOTHING = {"T1": "return np.zeros(3)"}\n',
    "cs451/stages/toy/tolerances.py": ('from ..base import Tolerance\n\nSCALED = Tolerance(1e-12, "a product of two '
                                       'float64 numbers against the same product: rounding only")\n'),
    "reference/toy/__init__.py": "from .scale import scale\n",
    "reference/toy/scale.py": TOY_REFERENCE,
    "autograder/toy/__init__.py": "",
    "autograder/toy/public.py": TOY_TESTS.format(kind="public", name="doubles", points=30, values=[0.1, 0.2, 0.3],
                                                 factor=2.0),
    "autograder/toy/hidden.py": TOY_TESTS.format(kind="hidden", name="halves", points=20, values=[1.0, 3.0],
                                                 factor=0.5),
    "assignments/06-toy/README.md": TOY_HANDOUT,
}
DERIVED = {"starter/toy/__init__.py", "starter/toy/scale.py"}


def tracked_files() -> list[str]:
    out = subprocess.run(["git", "ls-files", "-z"], cwd=KIT_ROOT, capture_output=True, check=True).stdout
    return [f for f in out.decode().split("\0") if f and (KIT_ROOT / f).is_file()]


def run(cmd: list[str], cwd: Path, timeout: float = 600) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(cwd), "PYTHONDONTWRITEBYTECODE": "1"}
    env.pop("CS451_HOME", None)
    return subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)


@pytest.fixture(scope="module")
def kit_with_toy_stage():
    """A copy of the kit's tracked files (as committed in git there), with the toy stage added by the recipe."""
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
    yield kit
    shutil.rmtree(top, ignore_errors=True)


def test_the_recipe_touches_only_the_files_it_names(kit_with_toy_stage):
    status = run(["git", "status", "--porcelain", "--untracked-files=all"], kit_with_toy_stage).stdout
    changed = {line[3:] for line in status.splitlines()}
    assert changed == set(RECIPE) | DERIVED, sorted(changed ^ (set(RECIPE) | DERIVED))


def test_the_toy_stage_passes_the_contract_and_the_handout_and_scene_tests(kit_with_toy_stage):
    """Every stage-parametrised test of the contract, the handouts and the scene kinds, on the toy (slow ones too)."""
    done = run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-m", "", "-k", "toy",
                "tests/test_stage_contract.py", "tests/test_handout.py", "tests/test_scene_kinds.py"], kit_with_toy_stage)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-2000:]
    summary = done.stdout.strip().splitlines()[-1]
    assert " passed" in summary and "failed" not in summary and "skipped" not in summary, summary
    assert int(summary.split(" passed")[0].split()[-1]) >= 11, summary    # 5 contract, 6 handout, 2 scene kinds


def test_the_toy_stage_renders_and_grades_from_the_command_line(kit_with_toy_stage):
    kit = kit_with_toy_stage
    done = run([sys.executable, "-m", "cs451", "render", "cornell-box", "--stage", "toy", "-o", str(kit / "t.png"),
                "--size", "8x6"], kit)
    assert done.returncode == 0 and (kit / "t.png").exists(), done.stderr
    done = run([sys.executable, "-m", "cs451", "grade", "toy", "--submission", "starter"], kit)
    assert "0/100" in done.stdout.replace(" ", "") or "0.0/100" in done.stdout.replace(" ", ""), done.stdout[-1500:]


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
    graph: dict[str, set[str]] = {}
    root = KIT_ROOT / "cs451"
    modules = {".".join(("cs451", *p.relative_to(root).with_suffix("").parts)).removesuffix(".__init__"): p
               for p in root.rglob("*.py")}
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
        targets = set()
        tree = ast.parse(path.read_text())
        typing_only = {id(n) for block in ast.walk(tree) if isinstance(block, ast.If)       # `if TYPE_CHECKING:`
                       and getattr(block.test, "id", None) == "TYPE_CHECKING" for n in ast.walk(block)}
        for node in ast.walk(tree):
            if id(node) in typing_only:
                continue
            if isinstance(node, ast.ImportFrom):
                base = package
                for _ in range(max(node.level - 1, 0)):
                    base = base.rsplit(".", 1)[0]
                mod = (f"{base}.{node.module}" if node.module else base) if node.level else (node.module or "")
                for alias in node.names:
                    sub = f"{mod}.{alias.name}"
                    targets.add(sub if sub in modules else mod)
            elif isinstance(node, ast.Import):
                targets |= {a.name for a in node.names}
        graph[name] = {t for t in targets if t in modules and t != name}
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
