"""The reference's own source lines on a slide, pulled by function name when the deck is built.

A deck names a function (``reference/radiosity/shooting.py::shoot``) and optionally a range inside it
(``from:`` and ``to:``, text that the first and last lines shown contain); the listing is read from the
file at build time, so a slide can never show code the reference no longer has. A name or a range that
no longer matches fails the build with the deck's file and line. The docstring and the solution markers
are left out (the handout has the words; the markers are the starter's business), and so is the signature
when a range is chosen (the slide's caption names the function).
"""
from __future__ import annotations

import ast
import io
import keyword
import re
import tokenize
from dataclasses import dataclass
from html import escape
from pathlib import Path

from .. import SPEED_LAYER
from ..errors import KitError

#: More lines than this do not fit a slide beside pseudo-code: the build asks for a ``from:``/``to:`` range.
MAX_LINES = 30
MARKER = re.compile(r"^\s*# (BEGIN|END) SOLUTION\b")


@dataclass(frozen=True)
class Listing:
    """Lines of one function of the reference: ``(line number in the file, html of the line)``; None is a gap."""
    path: str
    function: str
    lines: tuple[tuple[int, str] | None, ...]
    texts: dict[int, str]

    def find(self, snippet: str, after: int = 0) -> int | None:
        """The first shown line whose source contains ``snippet`` (how pseudo-code points at the reference):
        the first after line ``after`` if there is one (pseudo-code mostly runs in the code's order), else the
        first of all."""
        found = [e[0] for e in self.lines if e is not None and snippet in self.texts[e[0]]]
        return next((n for n in found if n > after), found[0] if found else None)

    @property
    def span(self) -> str:
        numbers = [e[0] for e in self.lines if e is not None]
        return f"lines {numbers[0]}–{numbers[-1]}" if len(numbers) > 1 else f"line {numbers[0]}"


def _function_node(tree: ast.Module, qualname: str) -> ast.FunctionDef | ast.AsyncFunctionDef | None:
    scope: list[ast.stmt] = tree.body
    node = None
    for part in qualname.split("."):
        node = next((n for n in scope if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef))
                     and n.name == part), None)
        if node is None:
            return None
        scope = node.body
    return node if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) else None


def _highlighted(source: str) -> dict[int, str]:
    """Every line of ``source`` as HTML, with keywords, comments, strings and numbers in classes of their own."""
    lines = source.splitlines()
    spans: dict[int, list[tuple[int, int, str]]] = {}
    try:
        for tok in tokenize.generate_tokens(io.StringIO(source).readline):
            kind = ("kw" if tok.type == tokenize.NAME and keyword.iskeyword(tok.string) else
                    "com" if tok.type == tokenize.COMMENT else "str" if tok.type == tokenize.STRING else
                    "num" if tok.type == tokenize.NUMBER else None)
            if kind is None:
                continue
            (r0, c0), (r1, c1) = tok.start, tok.end
            for r in range(r0, r1 + 1):
                start = c0 if r == r0 else 0
                end = c1 if r == r1 else len(lines[r - 1])
                spans.setdefault(r, []).append((start, end, kind))
    except (tokenize.TokenError, SyntaxError, IndexError):
        spans = {}
    out: dict[int, str] = {}
    for number, text in enumerate(lines, 1):
        html, at = [], 0
        for start, end, kind in sorted(spans.get(number, [])):
            if start < at:
                continue
            html.append(escape(text[at:start]))
            html.append(f'<span class="{kind}">{escape(text[start:end])}</span>')
            at = end
        html.append(escape(text[at:]))
        out[number] = "".join(html)
    return out


def read_listing(kit_root: Path, target: str, start: str | None, stop: str | None, where: str) -> Listing:
    """The lines of ``target`` (``reference/<stage>/<file>.py::function``, or a file of a stage's speed layer,
    ``cs451/stages/<stage>/accel/<file>.py``) from ``start`` to ``stop``.

    ``where`` (``slides/x.md:12``) prefixes every error, so a stale slide names itself.
    """
    path_text, sep, qualname = target.partition("::")
    if not sep or not qualname:
        raise KitError(f"{where}: a reference listing names `reference/<stage>/<file>.py::function`, not {target!r}")
    parts = Path(path_text).parts
    speed_layer = len(parts) == 5 and parts[:2] == ("cs451", "stages") and parts[3] == SPEED_LAYER
    if not (path_text.startswith("reference/") or speed_layer) or ".." in parts or not path_text.endswith(".py"):
        raise KitError(f"{where}: {path_text}: a listing shows a file of reference/ (reference/<stage>/<file>.py) "
                       f"or of a stage's speed layer (cs451/stages/<stage>/{SPEED_LAYER}/<file>.py)")
    file = kit_root / path_text
    if not file.is_file():
        raise KitError(f"{where}: {path_text}: no such file")
    source = file.read_text(encoding="utf-8")
    try:
        node = _function_node(ast.parse(source), qualname)
    except SyntaxError as err:
        raise KitError(f"{where}: {path_text}:{err.lineno}: does not parse ({err.msg})") from None
    if node is None:
        raise KitError(f"{where}: {path_text} has no function {qualname!r}")
    first = min([node.lineno] + [d.lineno for d in node.decorator_list])
    last = node.end_lineno or node.lineno
    body_start = node.body[0].lineno
    doc = node.body[0] if (isinstance(node.body[0], ast.Expr) and isinstance(node.body[0].value, ast.Constant)
                           and isinstance(node.body[0].value.value, str)) else None
    skipped = set(range(doc.lineno, (doc.end_lineno or doc.lineno) + 1)) if doc else set()
    raw = source.splitlines()
    texts = {n: raw[n - 1] for n in range(first, last + 1)}
    skipped |= {n for n, t in texts.items() if MARKER.match(t)}
    signature = [n for n in range(first, body_start) if n not in skipped]
    body = [n for n in range(body_start, last + 1) if n not in skipped]
    if start is not None or stop is not None:
        lo = 0
        if start is not None:
            lo = next((k for k, n in enumerate(body) if start in texts[n]), -1)
            if lo < 0:
                raise KitError(f"{where}: from: {start!r} is in no line of {target}")
        hi = len(body) - 1
        if stop is not None:
            hi = next((k for k, n in enumerate(body) if k >= lo and stop in texts[n]), -1)
            if hi < 0:
                raise KitError(f"{where}: to: {stop!r} is in no line of {target} after its from: line")
        body = body[lo:hi + 1]
        signature = []                  # a range stands alone: the caption names the function
    html = _highlighted(source)
    shown: list[tuple[int, str] | None] = []
    previous = None
    for n in signature + body:
        skipped_markers_only = previous is not None and all(MARKER.match(texts[m]) for m in range(previous + 1, n))
        if previous is not None and n != previous + 1 and not skipped_markers_only:
            shown.append(None)          # lines left out (the docstring, a from: range): a visible gap
        shown.append((n, html[n]))
        previous = n
    if len([s for s in shown if s]) > MAX_LINES:
        raise KitError(f"{where}: {target} shows {len([s for s in shown if s])} lines, more than a slide holds "
                       f"({MAX_LINES}): choose a range with from: and to:")
    return Listing(path=path_text, function=qualname, lines=tuple(shown), texts=texts)
