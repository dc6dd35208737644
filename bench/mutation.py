"""``cs451 bench mutation``: does the grading tell right from wrong? Small mistakes planted in the reference's task
regions, one at a time, each graded on its own task's tests (public and hidden).

A mutant is the reference with one change inside a ``# BEGIN SOLUTION <task>`` region, of the kinds a student
makes: a comparison flipped (< and <=, == and !=), an operator swapped (+ and -, * and /), a constant changed
(0 and 1, n to n + 1, x to 2x), a sign or a term dropped, ``and`` for ``or``, a statement left out; in GLSL text
(stage 1's shaders) the same, token by token. A mutant is killed when its task scores below full marks. One
that survives is either a gap in the tests or equivalent (no program input can tell it from the reference):
``bench/mutation_equivalent.json`` lists those, each with its reason. The score per stage is killed /
(mutants − equivalent − not graded); a mutant the grader wrote no results for (a fault of the kit or the machine,
not a verdict) is listed as not graded, never as killed. ``--quick`` grades one seeded mutant of each stage (to
show the bench runs: the fast suite does), ``--sample=N`` a sample of N (12 is a quick look worth reading).

Changes are spliced into the source text at the AST's positions, so comments and regions stay as they are.
"""
from __future__ import annotations

import ast
import json
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path

from cs451 import KIT_ROOT

#: The keys of each row of mutation.json that the docs read (tests/test_benches.py checks a quick run writes them).
KEYS = ("stage", "mutants", "killed", "errors")

REGION = re.compile(r"#\s*BEGIN SOLUTION\s+([A-Z]\d+)?")
SWAPS = {ast.Lt: "<=", ast.LtE: "<", ast.Gt: ">=", ast.GtE: ">", ast.Eq: "!=", ast.NotEq: "==",
         ast.Add: "-", ast.Sub: "+", ast.Mult: "/", ast.Div: "*", ast.And: "or", ast.Or: "and",
         ast.In: "not in", ast.NotIn: "in"}
SYMBOL = {ast.Lt: "<", ast.LtE: "<=", ast.Gt: ">", ast.GtE: ">=", ast.Eq: "==", ast.NotEq: "!=", ast.In: "in",
          ast.NotIn: "not in",
          ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.And: "and", ast.Or: "or"}
GLSL_SWAPS = [(" + ", " - "), (" - ", " + "), (" * ", " / "), (" / ", " * "), (" < ", " <= "), (" > ", " >= "),
              ("max(", "min("), ("min(", "max("), ("0.0", "1.0"), ("1.0", "0.0")]
EQUIVALENT = Path(__file__).with_name("mutation_equivalent.json")


@dataclass(frozen=True)
class Mutant:
    stage: str
    task: str
    file: str            # relative to reference/<stage>
    line: int
    col: int
    kind: str
    before: str
    after: str
    start: int           # character offsets of the change in the file
    end: int

    @property
    def key(self) -> str:
        return f"{self.stage}/{self.file}:{self.line}:{self.col}:{self.kind}:{self.before}->{self.after}"


def regions(source: str) -> list[tuple[int, int, str]]:
    """(first line, last line, task) of each solution region with a task ID (1-based, inclusive)."""
    out, start, task = [], None, ""
    for number, text in enumerate(source.splitlines(), 1):
        m = REGION.search(text)
        if m:
            start, task = number, m.group(1) or ""
        elif "END SOLUTION" in text and start is not None:
            if task:
                out.append((start, number, task))
            start = None
    return out


def _offsets(source: str) -> list[int]:
    starts, total = [], 0
    for line in source.splitlines(keepends=True):
        starts.append(total)
        total += len(line)
    return starts


def mutants_of(source: str, stage: str, file: str) -> list[Mutant]:
    """Every mutant of the task regions of one file's source."""
    spans = regions(source)
    if not spans:
        return []
    tree, starts = ast.parse(source), _offsets(source)
    at = lambda line, col: starts[line - 1] + col
    out: list[Mutant] = []

    def task_of(node: ast.AST) -> str | None:
        line = getattr(node, "lineno", 0)
        return next((t for a, b, t in spans if a < line < b), None)

    def add(node: ast.AST, kind: str, start: int, end: int, after: str) -> None:
        task = task_of(node)
        if task:
            out.append(Mutant(stage, task, file, node.lineno, node.col_offset, kind, source[start:end], after, start, end))

    def between(left: ast.AST, right: ast.AST, symbol: str) -> tuple[int, int] | None:
        lo, hi = at(left.end_lineno, left.end_col_offset), at(right.lineno, right.col_offset)
        k = source.find(symbol, lo, hi)
        return (k, k + len(symbol)) if k >= 0 else None

    for node in ast.walk(tree):
        if isinstance(node, ast.Compare) and len(node.ops) == 1 and type(node.ops[0]) in SWAPS:
            span = between(node.left, node.comparators[0], SYMBOL[type(node.ops[0])])
            if span:
                add(node, "comparison", *span, SWAPS[type(node.ops[0])])
        elif isinstance(node, ast.BinOp) and type(node.op) in SWAPS:
            span = between(node.left, node.right, SYMBOL[type(node.op)])
            if span:
                add(node, "operator", *span, SWAPS[type(node.op)])
                if isinstance(node.op, (ast.Add, ast.Sub)):   # the term after the operator dropped
                    add(node, "term dropped", at(node.left.end_lineno, node.left.end_col_offset),
                        at(node.end_lineno, node.end_col_offset), "")
        elif isinstance(node, ast.BoolOp) and len(node.values) == 2:
            span = between(node.values[0], node.values[1], SYMBOL[type(node.op)])
            if span:
                add(node, "boolean", *span, SWAPS[type(node.op)])
        elif isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
            add(node, "sign dropped", at(node.lineno, node.col_offset), at(node.lineno, node.col_offset) + 1, "")
        elif isinstance(node, ast.Constant) and type(node.value) in (int, float):
            v = node.value
            new = 1 if v == 0 else 0 if v == 1 else v + 1 if isinstance(v, int) else v * 2
            add(node, "constant", at(node.lineno, node.col_offset), at(node.end_lineno, node.end_col_offset), repr(new))
        elif isinstance(node, ast.Constant) and isinstance(node.value, str) and "\n" in node.value:
            base = at(node.lineno, node.col_offset)
            text = source[base:at(node.end_lineno, node.end_col_offset)]
            for old, new in GLSL_SWAPS:
                for m in re.finditer(re.escape(old), text):
                    add(node, "glsl", base + m.start(), base + m.end(), new)
        elif (isinstance(node, (ast.Expr, ast.AugAssign)) and not isinstance(getattr(node, "value", None), ast.Constant)
              or isinstance(node, ast.Assign) and all(isinstance(t, (ast.Subscript, ast.Attribute)) for t in node.targets)):
            # a call, an update, or a store into an array or a dict left out (a plain name assigned is not: NameError)
            add(node, "statement dropped", at(node.lineno, node.col_offset), at(node.end_lineno, node.end_col_offset),
                "pass")
    return out


def stage_mutants(stage: str) -> list[Mutant]:
    folder = KIT_ROOT / "reference" / stage
    return [m for path in sorted(folder.glob("*.py")) for m in mutants_of(path.read_text(), stage, path.name)]


def apply(mutant: Mutant, into: Path) -> Path:
    """A copy of the stage's reference with the mutant applied, as a submission folder; returns the folder."""
    package = into / mutant.stage
    shutil.copytree(KIT_ROOT / "reference" / mutant.stage, package, ignore=shutil.ignore_patterns("__pycache__"))
    path = package / mutant.file
    source = path.read_text()
    path.write_text(source[:mutant.start] + mutant.after + source[mutant.end:])
    return into


class GraderFailed(RuntimeError):
    """The grader wrote no results: a fault of the kit (or of the machine), never a verdict on the mutant."""


def task_score(stage: str, submission: Path, task: str) -> tuple[float, float]:
    """(points, out of) for one task's tests, public and hidden, graded as an instructor grades (sandboxed), by the
    copy of the kit this module belongs to (so a snapshot of the kit can be measured while its checkout changes)."""
    with tempfile.TemporaryDirectory() as tmp:
        results = Path(tmp) / "results.json"
        done = subprocess.run([sys.executable, "-m", "cs451", "grade", stage, "--submission", str(submission),
                               "--tasks", task, "--results", str(results)], capture_output=True, text=True,
                              timeout=900, cwd=KIT_ROOT, env={**os.environ, "PYTHONPATH": str(KIT_ROOT)})
        if not results.exists():
            raise GraderFailed(f"exit {done.returncode}: {(done.stderr or done.stdout).strip()[-300:]}")
        data = json.loads(results.read_text())
    tests = [t.get("extra_data") if (t.get("extra_data") or {}).get("extension") else t   # an extension's points
             for t in data.get("tests", [])]                                                # travel in extra_data
    return sum(t.get("score", 0) for t in tests), sum(t.get("max_score", 0) for t in tests)


def run(stage: str, sample: int | None = None, seed: int = 0, progress=print) -> dict:
    """Grade every mutant of a stage (or a seeded sample): each mutant with its verdict, and the stage's score."""
    mutants = stage_mutants(stage)
    if sample is not None and sample < len(mutants):
        mutants = sorted(random.Random(seed).sample(mutants, sample), key=lambda m: (m.file, m.start))
    equivalent = json.loads(EQUIVALENT.read_text()) if EQUIVALENT.exists() else {}
    rows = []
    for k, m in enumerate(mutants, 1):
        t0 = time.perf_counter()
        with tempfile.TemporaryDirectory() as tmp:
            try:
                got, full = task_score(stage, apply(m, Path(tmp)), m.task)
                killed, error = got < full - 1e-9, None
            except (GraderFailed, subprocess.TimeoutExpired) as err:
                got, full, killed, error = 0.0, 0.0, False, str(err)
        rows.append({**asdict(m), "key": m.key, "points": got, "out_of": full, "killed": killed, "error": error,
                     "equivalent": equivalent.get(m.key), "seconds": time.perf_counter() - t0})
        verdict = f"ERROR ({error})" if error else f"{'killed' if killed else 'SURVIVED'} ({got:g}/{full:g})"
        progress(f"  {stage} {k}/{len(mutants)} {m.task} {m.file}:{m.line} {m.kind} {m.before!r}->{m.after!r}: {verdict}")
    graded = [r for r in rows if not r["error"]]
    counted = [r for r in graded if not (r["equivalent"] and not r["killed"])]
    killed = sum(r["killed"] for r in counted)
    return {"stage": stage, "mutants": len(rows), "killed": killed, "errors": len(rows) - len(graded),
            "equivalent": sum(1 for r in graded if r["equivalent"] and not r["killed"]),
            "score": killed / len(counted) if counted else 1.0, "rows": rows}


def main(output: Path, quick: bool = False, stages: list[str] | None = None, sample: int | None = None) -> None:
    """``sample``: grade a seeded sample of that many mutants per stage (``quick``: one, to show it runs; a sample
    worth reading is ``python -m bench.mutation OUT --sample=12``); else every mutant."""
    from cs451.stages import stage_names
    output = Path(output)
    output.mkdir(parents=True, exist_ok=True)
    reports = [run(s, sample=sample or (1 if quick else None)) for s in (stages or stage_names())]
    print(f"\n{'stage':10s} {'mutants':>8s} {'killed':>7s} {'equiv.':>7s} {'errors':>7s} {'score':>7s}")
    for r in reports:
        print(f"{r['stage']:10s} {r['mutants']:8d} {r['killed']:7d} {r['equivalent']:7d} {r['errors']:7d} "
              f"{r['score']:7.1%}")
    for r in reports:
        for row in r["rows"]:
            if row["error"]:
                print(f"  not graded: {row['key']} (task {row['task']}): {row['error']}")
            elif not row["killed"] and not row["equivalent"]:
                print(f"  survived: {row['key']} (task {row['task']})")
    (output / "mutation.json").write_text(json.dumps(reports, indent=1))
    print(f"\nwrote {output / 'mutation.json'}")


if __name__ == "__main__":
    sampled = next((int(a.split("=", 1)[1]) for a in sys.argv if a.startswith("--sample=")), None)
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "bench-results"), quick="--quick" in sys.argv,
         stages=[a for a in sys.argv[2:] if not a.startswith("-")] or None, sample=sampled)
