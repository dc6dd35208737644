"""Deriving starter/ from reference/: solution regions become stubs that say what to do.

A region inside a function::

    # BEGIN SOLUTION S1: build the matrix of gluPerspective row by row (handout §S1)
    ...solution...
    # END SOLUTION

becomes a TODO with the same ID and a ``raise NotImplementedError`` carrying the
hint. A region at module level (a shared helper) is removed, and a module left with nothing but its docstring
(the reference's speed-ups, all one region) is left out of the starter: a student gets no empty file to wonder
about. Nested or unbalanced markers are refused with the file and line, as otter-grader does.
"""
from __future__ import annotations

import ast
import re
import shutil
from dataclasses import dataclass
from pathlib import Path

from . import KIT_ROOT
from .errors import KitError

BEGIN = re.compile(r"^(?P<indent>\s*)# BEGIN SOLUTION(?:\s+(?P<id>[A-Z]+\d+[a-z]?)(?::\s*(?P<hint>.*))?)?\s*$")
END = re.compile(r"^\s*# END SOLUTION\s*$")
SKIP_NAMES = {"__pycache__"}


def replace_solutions(lines: list[str], source: str = "<string>") -> list[str]:
    """Replace every solution region in ``lines`` (no line endings) by its stub; pure, fails loudly."""
    out: list[str] = []
    inside: tuple[int, re.Match] | None = None
    for number, line in enumerate(lines, start=1):
        begin, end = BEGIN.match(line), END.match(line)
        if begin:
            if inside:
                raise KitError(f"{source}:{number}: BEGIN SOLUTION inside the region opened at line {inside[0]}")
            inside = (number, begin)
            continue
        if end:
            if not inside:
                raise KitError(f"{source}:{number}: END SOLUTION without a BEGIN SOLUTION")
            out.extend(_stub(inside[1], source, inside[0]))
            inside = None
            continue
        if not inside:
            out.append(line)
    if inside:
        raise KitError(f"{source}:{inside[0]}: BEGIN SOLUTION is never closed")
    return out


def _stub(begin: re.Match, source: str, number: int) -> list[str]:
    indent = begin["indent"]
    if not indent:
        return []  # a module-level helper of the reference: the student writes their own
    if not begin["id"] or not begin["hint"]:
        raise KitError(f"{source}:{number}: a solution region inside a function needs an ID and a hint "
                       f"('# BEGIN SOLUTION S1: what to do (handout §S1)')")
    task, hint = begin["id"], begin["hint"].strip()
    message = f"{task}: {hint}".replace("\\", "\\\\").replace('"', '\\"')
    return [f"{indent}# TODO {task}: {hint}", f'{indent}raise NotImplementedError("{message}")']


@dataclass(frozen=True)
class Drift:
    path: str
    reason: str


def _expected_files(reference: Path) -> dict[str, str]:
    files = {}
    for path in sorted(reference.rglob("*")):
        if path.is_dir() or any(part in SKIP_NAMES for part in path.parts) or path.suffix == ".pyc":
            continue
        rel = path.relative_to(reference).as_posix()
        text = path.read_text()
        if path.suffix == ".py":
            text = "\n".join(replace_solutions(text.splitlines(), rel)) + "\n"
            if path.name != "__init__.py" and _docstring_only(text):
                continue
        files[rel] = text
    return files


def _docstring_only(source: str) -> bool:
    """Whether a module holds nothing a program could use: at most a docstring (and ``__future__`` imports)."""
    try:
        body = ast.parse(source).body
    except SyntaxError:
        return False
    return all(isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant) and isinstance(node.value.value, str)
               or isinstance(node, ast.ImportFrom) and node.module == "__future__" for node in body)


def _existing_files(starter: Path) -> dict[str, str]:
    if not starter.exists():
        return {}
    return {p.relative_to(starter).as_posix(): p.read_text() for p in sorted(starter.rglob("*"))
            if p.is_file() and not any(part in SKIP_NAMES for part in p.parts) and p.suffix != ".pyc"}


def _require_reference(reference: Path) -> None:
    if not reference.is_dir():
        raise KitError(f"{reference}: no reference solutions here; `cs451 starter` runs in the instructor's kit")


def check_starter(reference: Path = KIT_ROOT / "reference", starter: Path = KIT_ROOT / "starter") -> list[Drift]:
    """Where starter/ differs from what reference/ generates (empty when in step)."""
    _require_reference(reference)
    want, have = _expected_files(reference), _existing_files(starter)
    drift = [Drift(p, "missing") for p in want if p not in have]
    drift += [Drift(p, "not generated from reference/ (remove it or add it to reference/)") for p in have if p not in want]
    drift += [Drift(p, "differs from its reference/ source (edited by hand, or reference/ changed)")
              for p in want if p in have and have[p] != want[p]]
    return drift


def generate_starter(reference: Path = KIT_ROOT / "reference", starter: Path = KIT_ROOT / "starter") -> list[str]:
    """Rewrite starter/ from reference/; returns the files written."""
    _require_reference(reference)
    files = _expected_files(reference)  # parse everything first: a bad marker leaves starter/ untouched
    if starter.exists():
        shutil.rmtree(starter)
    for rel, text in files.items():
        dest = starter / rel
        dest.parent.mkdir(parents=True, exist_ok=True)
        dest.write_text(text)
    return list(files)
