"""Every handout (assignments/*/README.md) is checked against the code, so it cannot rot.

The paths and ``cs451`` commands it names exist, its task headings are the stage's tasks (with the
anchors the starter's hints link to), the signatures it shows are the interface's, its in-page
links resolve, and its rubric's points are the autograder's.
"""
from __future__ import annotations

import ast
import functools
import re
import shlex
from dataclasses import dataclass
from pathlib import Path

import pytest

from cs451 import KIT_ROOT
from cs451.packaging.handout import for_kit
from cs451.cli import build_parser
from cs451.grading.runner import load_tests
from cs451.stages import get_stage, stage_names

HANDOUTS = sorted((KIT_ROOT / "assignments").glob("*/README.md"))
PATH_PREFIXES = ("cs451/", "reference/", "starter/", "autograder/", "assignments/", "tests/", "bench/")
TASK_HEADING = re.compile(r"^### ([A-Z]\d+) (.+?)\s*$")
COMMAND = re.compile(r"(?:^|[\s/(])cs451\s+(\S+)(.*)")
TEST_COUNT = re.compile(r"^(\d+)\s*\((\d+(?:\.\d+)?)\s*pts?\)$")


@dataclass(frozen=True)
class Handout:
    path: Path
    prose: list[str]                       # lines outside fenced code blocks
    blocks: list[tuple[int, str, str]]     # (line number, info string, content) of fenced code blocks
    spans: list[str]                       # inline code spans of the prose

    @property
    def code(self) -> list[str]:
        """Everything between backticks: inline spans and fenced blocks."""
        return self.spans + [content for _, _, content in self.blocks]


@functools.lru_cache(maxsize=None)
def parse(path: Path) -> Handout:
    prose, blocks, fence, start, info, body = [], [], None, 0, "", []
    for number, line in enumerate(for_kit(path.read_text()).splitlines(), 1):
        opening = re.match(r"^\s*(```+|~~~+)(.*)$", line)
        if fence is None and opening:
            fence, start, info, body = opening.group(1), number, opening.group(2).strip(), []
            prose.append("")                       # keep line numbers aligned
        elif fence is not None and line.strip().startswith(fence) and not line.strip().strip(fence[0]):
            blocks.append((start, info, "\n".join(body)))
            fence = None
            prose.append("")
        elif fence is not None:
            body.append(line)
            prose.append("")
        else:
            prose.append(line)
    assert fence is None, f"{path}: the code block opened at line {start} is never closed"
    spans = [m.group(2) for m in re.finditer(r"(`+)(.+?)\1", "\n".join(prose))]
    return Handout(path, prose, blocks, spans)


def stage_of(handout: Path):
    stages = {get_stage(n).handout: get_stage(n) for n in stage_names()}
    folder = handout.parent.name
    assert folder in stages, f"{handout}: no stage has its handout in assignments/{folder}/ (stages: {list(stages)})"
    return stages[folder]


def github_anchor(heading: str) -> str:
    """The anchor GitHub (and most Markdown renderers) gives a heading."""
    text = re.sub(r"[`*_]", "", heading.strip().lower())
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


def headings(handout: Handout) -> list[tuple[int, int, str]]:
    """(line index, level, text) of every Markdown heading outside code blocks."""
    out = []
    for i, line in enumerate(handout.prose):
        m = re.match(r"^(#{1,6}) (.+?)\s*$", line)
        if m:
            out.append((i, len(m.group(1)), m.group(2)))
    return out


def table_rows(handout: Handout, first_columns: list[str]) -> tuple[list[str], list[list[str]]]:
    """The header and body rows of the first table whose header starts with ``first_columns``."""
    def cells(line: str) -> list[str]:
        parts = re.split(r"(?<!\\)\|", line.strip()[1:-1] if line.strip().endswith("|") else line.strip()[1:])
        return [re.sub(r"[*`]", "", p).strip() for p in parts]

    lines = handout.prose
    for i, line in enumerate(lines):
        if line.lstrip().startswith("|") and i + 1 < len(lines) and re.match(r"^\s*\|[\s:|-]+\|\s*$", lines[i + 1]):
            header = cells(line)
            if header[:len(first_columns)] == first_columns:
                rows = []
                for row in lines[i + 2:]:
                    if not row.lstrip().startswith("|"):
                        break
                    rows.append(cells(row))
                return header, rows
    raise AssertionError(f"{handout.path}: no Markdown table with columns {' | '.join(first_columns)} | …")


handouts = pytest.mark.parametrize("path", HANDOUTS, ids=[p.parent.name for p in HANDOUTS])


def test01_every_stage_has_a_handout():
    for name in stage_names():
        stage = get_stage(name)
        assert (KIT_ROOT / "assignments" / stage.handout / "README.md").is_file(), \
            f"stage {name!r} has no handout at assignments/{stage.handout}/README.md"


@handouts
def test02_repository_paths_exist(path):
    missing = []
    for code in parse(path).code:
        for token in code.split():
            token = token.strip("\"'(),;:[]").rstrip(".")
            if "/" not in token or not token.startswith(PATH_PREFIXES):
                continue
            target = token.split("#", 1)[0]
            found = list(KIT_ROOT.glob(target)) if "*" in target else [KIT_ROOT / target] if (KIT_ROOT / target).exists() else []
            if not found:
                missing.append(token)
    assert not missing, f"{path}: these paths do not exist in the kit: {sorted(set(missing))}"


def _subcommands() -> dict:
    parser = build_parser()
    action = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")  # argparse keeps them private
    return action.choices


@handouts
def test03_cs451_commands_exist(path):
    subcommands = _subcommands()
    problems, seen = [], 0
    for code in parse(path).code:
        for line in code.splitlines():
            for m in COMMAND.finditer(line):
                seen += 1
                name, rest = m.group(1), m.group(2).split(" #", 1)[0]
                if name not in subcommands:
                    problems.append(f"`cs451 {name}`: no such subcommand (known: {', '.join(subcommands)})")
                    continue
                options = subcommands[name]._option_string_actions
                try:
                    tokens = shlex.split(rest)
                except ValueError:
                    tokens = rest.split()
                for token in tokens:
                    for flag in token.strip("[]").split("|"):
                        flag = flag.split("=", 1)[0]
                        if flag.startswith("-") and flag not in options:
                            problems.append(f"`cs451 {name} … {flag}`: `cs451 {name}` has no option {flag}")
    assert seen, f"{path}: names no `cs451` command at all (how does a student run anything?)"
    assert not problems, f"{path}:\n" + "\n".join(problems)


@handouts
def test04_task_headings_are_the_stage_tasks(path):
    handout, stage = parse(path), stage_of(path)
    found = {}
    for _, level, text in headings(handout):
        m = TASK_HEADING.match("#" * level + " " + text)
        if m:
            assert m.group(1) not in found, f"{path}: two headings for task {m.group(1)}"
            found[m.group(1)] = m.group(2)
    tasks = {t.id: t for t in stage.tasks}
    extra = sorted(set(found) - set(tasks))
    assert not extra, f"{path}: headings for tasks the stage {stage.name!r} does not declare: {extra}"
    for task in stage.tasks:
        assert task.id in found, f"{path}: no heading `### {task.id} {task.title}`"
        assert found[task.id] == task.title, \
            f"{path}: heading `### {task.id} {found[task.id]}` should be `### {task.id} {task.title}`"
        link = stage.handout_link(task)
        assert link.endswith("#" + github_anchor(f"{task.id} {task.title}")), \
            f"the code's hint link {link} does not match the heading's anchor"


@handouts
def test05_task_sections_show_the_interface_signature(path):
    handout, stage = parse(path), stage_of(path)
    marks = headings(handout)
    for task in stage.tasks:
        start = next((i for i, level, text in marks if text.startswith(f"{task.id} ") and level == 3), None)
        assert start is not None, f"{path}: no section `### {task.id} …` (see test04)"
        end = next((i for i, level, _ in marks if i > start and level <= 3), len(handout.prose))
        defs = [content for line, info, content in handout.blocks
                if start < line - 1 < end and info.startswith("python") and f"def {task.function}(" in content]
        assert defs, f"{path}: section {task.id} shows no ```python block with `def {task.function}(…)`"
        tree = ast.parse(defs[0].strip() + "\n    ...\n")
        fn = next(n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef) and n.name == task.function)
        params = tuple(a.arg for a in fn.args.args)
        assert params == task.params, f"{path}: section {task.id} shows {task.function}{params}, the interface says {task.params}"


@handouts
def test06_in_page_links_resolve(path):
    handout = parse(path)
    anchors = {github_anchor(text) for _, _, text in headings(handout)}
    links = re.findall(r"\]\(#([^)\s]+)\)", "\n".join(handout.prose))
    broken = sorted({a for a in links if a not in anchors})
    assert not broken, f"{path}: links to headings that do not exist: {broken}"


@handouts
def test07_rubric_points_are_the_autograder_points(path):
    handout, stage = parse(path), stage_of(path)
    header, rows = table_rows(handout, ["Task", "Function", "Points"])
    tests = load_tests(stage.name)
    columns = {name: header.index(name) for name in ("Public tests", "Hidden tests") if name in header}

    def expected(selected) -> dict[str, float]:
        return {"points": sum(t.points for t in selected),
                "Public tests": (sum(1 for t in selected if not t.hidden), sum(t.points for t in selected if not t.hidden)),
                "Hidden tests": (sum(1 for t in selected if t.hidden), sum(t.points for t in selected if t.hidden))}

    seen = []
    for row in rows:
        label = row[0]
        if label.lower() == "total":
            selected = [t for t in tests if not t.extension]    # an optional extension's points are not in the grade
        else:
            assert label in {t.id for t in stage.tasks}, f"{path}: rubric row {label!r} is not a task of stage {stage.name!r}"
            task = stage.task(label)
            assert row[1] == task.function, f"{path}: rubric row {label} names {row[1]!r}, the function is {task.function!r}"
            selected = [t for t in tests if t.task == label]
            seen.append(label)
            assert not task.optional or "optional" in " ".join(row).lower(), \
                f"{path}: rubric row {label} must say that the task is an optional extension, outside the total"
        want = expected(selected)
        assert float(row[2]) == want["points"], \
            f"{path}: rubric gives {label} {row[2]} points, its tests are worth {want['points']:g}"
        for name, col in columns.items():
            m = TEST_COUNT.match(row[col])
            assert m, f"{path}: rubric cell {label} / {name} is {row[col]!r}, expected 'N (P pts)'"
            count, points = want[name]
            assert (int(m.group(1)), float(m.group(2))) == (count, points), \
                f"{path}: rubric says {label} has {row[col]} {name.lower()}, the autograder has {count} ({points:g} pts)"
    assert sorted(seen) == sorted(t.id for t in stage.tasks), \
        f"{path}: the rubric must have one row per task {[t.id for t in stage.tasks]}, it has {seen}"
