"""The kit's import graph, read from the source (function-level imports included, ``if TYPE_CHECKING:`` ones not:
they never run), and what the architecture tests judge by it: which stage a module serves, and which imports reach
into another stage's private parts.

A module belongs to stage S when it sits in ``cs451/stages/S/``, ``reference/S/`` or ``autograder/S/``. Tests and
benchmarks outside a stage's package neither own nor share a module: they may import anything.
"""
from __future__ import annotations

import ast
from pathlib import Path

#: The kit's folders whose modules run as the kit (tests and the kit's own benchmarks import, but do not count).
CODE = ("cs451", "reference", "autograder")


def module_name(root: Path, path: Path) -> str:
    """``cs451/stages/radiosity/display.py`` → ``cs451.stages.radiosity.display`` (a package by its folder)."""
    return ".".join(path.relative_to(root).with_suffix("").parts).removesuffix(".__init__")


def modules(root: Path, tops: tuple[str, ...] = CODE) -> dict[str, Path]:
    """Every module under ``tops`` of ``root`` by its dotted name."""
    found = {}
    for top in tops:
        for path in (root / top).rglob("*.py"):
            if "vendor" not in path.parts and "__pycache__" not in path.parts:
                found[module_name(root, path)] = path
    return found


def imports_of(name: str, path: Path, known: dict[str, Path]) -> set[str]:
    """The modules of ``known`` that ``path`` (module ``name``) imports, ``from . import x`` resolved to ``x``."""
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    tree = ast.parse(path.read_text())
    typing_only = {id(n) for block in ast.walk(tree) if isinstance(block, ast.If)
                   and getattr(block.test, "id", None) == "TYPE_CHECKING" for n in ast.walk(block)}
    targets = set()
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
                targets.add(sub if sub in known else mod)
        elif isinstance(node, ast.Import):
            targets |= {a.name for a in node.names}
    return {t for t in targets if t in known and t != name}


def import_graph(root: Path, tops: tuple[str, ...] = CODE) -> dict[str, set[str]]:
    """Module → the modules it imports, over ``tops``."""
    known = modules(root, tops)
    return {name: imports_of(name, path, known) for name, path in known.items()}


def stage_of(name: str, stages: set[str]) -> str | None:
    """The stage whose folder holds module ``name`` (``cs451.stages.S…``, ``reference.S…``, ``autograder.S…``)."""
    parts = name.split(".")
    if parts[:2] == ["cs451", "stages"] and len(parts) > 2 and parts[2] in stages:
        return parts[2]
    if parts[0] in ("reference", "autograder") and len(parts) > 1 and parts[1] in stages:
        return parts[1]
    return None


def single_stage_modules(graph: dict[str, set[str]], stages: set[str]) -> dict[str, str]:
    """Modules outside every stage's folder that serve one stage only: each imported only by that stage's modules,
    or by other such modules of the same stage (found to a fixed point). Module → its stage."""
    importers: dict[str, set[str]] = {name: set() for name in graph}
    for name, targets in graph.items():
        for target in targets:
            importers[target].add(name)
    owner: dict[str, str] = {}
    changed = True
    while changed:
        changed = False
        for name in graph:
            if stage_of(name, stages) is not None or name in owner or not importers[name]:
                continue
            served = {stage_of(i, stages) or owner.get(i) for i in importers[name]}
            if len(served) == 1 and None not in served:
                owner[name] = served.pop()
                changed = True
    return owner


def private_reaches(graph: dict[str, set[str]], stages: set[str]) -> list[str]:
    """Imports of another stage's private parts: any module of ``cs451/stages/T/`` but its package (the interface)
    imported from outside stage T's folders."""
    found = []
    for name, targets in graph.items():
        mine = stage_of(name, stages)
        for target in targets:
            theirs = stage_of(target, stages)
            parts = target.split(".")
            if theirs is not None and theirs != mine and parts[:2] == ["cs451", "stages"] and len(parts) > 3:
                found.append(f"{name} imports {target}")
    return found


def stages_using(graph: dict[str, set[str]], stages: set[str]) -> dict[str, set[str]]:
    """For every module outside the stages' folders, the stages whose modules import it, directly or through other
    such modules (a stage's own modules count for that stage only)."""
    importers: dict[str, set[str]] = {name: set() for name in graph}
    for name, targets in graph.items():
        for target in targets:
            importers[target].add(name)
    out: dict[str, set[str]] = {}

    def users(name: str, seen: set[str]) -> set[str]:
        found = set()
        for importer in importers[name]:
            stage = stage_of(importer, stages)
            if stage is not None:
                found.add(stage)
            elif importer not in seen and not importer.startswith("cs451.stages."):
                seen.add(importer)
                found |= users(importer, seen)
        return found
    for name in graph:
        if stage_of(name, stages) is None:
            out[name] = users(name, {name})
    return out
