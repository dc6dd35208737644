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
from html import escape, unescape
from pathlib import Path

from .. import SPEED_LAYER
from ..errors import KitError

#: More lines than this do not fit a slide (code is set at 22 px): the build asks for a ``from:``/``to:`` range.
MAX_LINES = 16
#: Characters a listing line may hold across a whole slide at 22 px; longer lines are folded where Python
#: allows (after a comma or before an operator inside brackets), never wrapped by the browser. A ``width:``
#: line in the reference block narrows it for a listing in a column.
FOLD_WIDTH = 80
MARKER = re.compile(r"^\s*# (BEGIN|END) SOLUTION\b")


@dataclass(frozen=True)
class Listing:
    """Lines of one function of the reference: ``(line number in the file, html of its rows)``; None is a gap.

    A line longer than the slide is folded into rows as a formatter would fold it (``fold_line``); the rows
    after the first continue it and carry no number."""
    path: str
    function: str
    lines: tuple[tuple[int, tuple[str, ...]] | None, ...]
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


Spans = dict[int, list[tuple[int, int, str]]]


def _spans(source: str) -> tuple[Spans, dict[tuple[int, int], int]]:
    """Per line, the (start, end, kind) of keywords, comments, strings and numbers; and where a line may be
    folded: {(line, column): bracket depth} after each comma and before each binary operator inside brackets."""
    lines = source.splitlines()
    spans: Spans = {}
    breaks: dict[tuple[int, int], int] = {}
    depth = 0
    try:
        for tok in tokenize.generate_tokens(io.StringIO(source).readline):
            if tok.type == tokenize.OP:
                if tok.string in "([{":
                    depth += 1
                elif tok.string in ")]}":
                    depth -= 1
                elif tok.string == ",":
                    breaks[(tok.end[0], tok.end[1] + 1)] = depth
                elif tok.string in BREAK_BEFORE:
                    breaks[tok.start] = depth
            if tok.type == tokenize.NAME and tok.string in ("and", "or") or (
                    tok.type == tokenize.NAME and depth > 0 and tok.string in ("if", "else", "for")):
                breaks[tok.start] = depth
            if tok.type == tokenize.STRING and tok.start[0] != tok.end[0]:      # shader source: free-form text
                for r in range(tok.start[0] + 1, tok.end[0]):
                    for col, ch in enumerate(lines[r - 1]):
                        if ch == " " and col > 0 and lines[r - 1][col - 1] != " ":
                            breaks[(r, col + 1)] = 1
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
        spans, breaks = {}, {}
    return spans, breaks


BREAK_BEFORE = {"+", "-", "*", "/", "//", "@", "==", "!=", "<", "<=", ">", ">=", "if", "else"}


def _html(text: str, spans: list[tuple[int, int, str]], lo: int, hi: int) -> str:
    """Columns ``lo``..``hi`` of one line as HTML, highlighted."""
    html, at = [], lo
    for start, end, kind in sorted(spans):
        start, end = max(start, lo), min(end, hi)
        if start >= end or start < at:
            continue
        html.append(escape(text[at:start]))
        html.append(f'<span class="{kind}">{escape(text[start:end])}</span>')
        at = end
    html.append(escape(text[at:hi]))
    return "".join(html)


def fold_line(text: str, width: int, breaks: dict[int, int], comment_at: int | None = None) -> list[tuple[int, int, int]]:
    """Where to fold one source line of more than ``width`` characters: rows as (start column, end column,
    indent), each row at most ``width`` wide where a fold point allows it.

    ``breaks`` maps the columns where the line may continue to their bracket depth: inside brackets (depth
    1 and more) Python joins the rows by itself, and the shallowest fold that fits is taken, the last of them
    (as black and PEP 8 fold); outside brackets (depth 0) only where nothing inside fits, and the row then ends
    in a backslash. A trailing comment that does not fit goes to a row of its own; a continuation row is
    indented 8 more than the line.
    """
    indent = len(text) - len(text.lstrip(" "))
    rows: list[tuple[int, int, int]] = []
    start, row_indent = 0, 0
    end_of_code = len(text) if comment_at is None else len(text[:comment_at].rstrip())
    while end_of_code - start > width - row_indent:
        room = width - row_indent
        fits = [(d, c) for c, d in breaks.items() if start < c < end_of_code and (
            c - start <= room if d > 0 else len(text[:c].rstrip()) - start + 2 <= room)]
        inside = [(d, c) for d, c in fits if d > 0]
        chosen = inside or fits
        if not chosen:
            break
        shallow = min(d for d, _ in chosen)
        cut = max(c for d, c in chosen if d == shallow)
        rows.append((start, len(text[:cut].rstrip()), row_indent if shallow > 0 else -1 - row_indent))
        start, row_indent = cut, indent + 8
        while start < len(text) and text[start] == " ":
            start += 1
    if comment_at is not None and len(text) - start + row_indent > width and end_of_code > start:
        rows.append((start, end_of_code, row_indent))
        rows.append((comment_at, len(text), indent if not rows[:-1] else indent + 8))
    else:
        rows.append((start, len(text), row_indent))
    return rows


def _rows(number: int, text: str, spans: Spans, breaks: dict[tuple[int, int], int], width: int) -> tuple[str, ...]:
    """One source line as the HTML of its rows on the slide: itself, or folded (code at its fold points, a
    comment at its words, each further comment row starting with ``#`` again)."""
    if len(text) <= width:
        return (_html(text, spans.get(number, []), 0, len(text)),)
    line_spans = spans.get(number, [])
    comment = next((c0 for c0, _, kind in sorted(line_spans) if kind == "com"), None)
    cols = {c: d for (n, c), d in breaks.items() if n == number}
    out: list[str] = []
    rows = ([(comment, len(text), comment)] if comment is not None and not text[:comment].strip()
            else fold_line(text, width, cols, comment))
    for lo, hi, indent in rows:
        backslash = indent < 0                      # folded outside brackets: Python needs the backslash
        indent = -1 - indent if backslash else indent
        if comment is not None and lo >= comment and hi - lo + indent > width:
            words, row = text[lo:hi].lstrip("# ").split(), "#"
            for word in words:
                if len(row) + 1 + len(word) + indent > width and row != "#":
                    out.append(" " * indent + f'<span class="com">{escape(row)}</span>')
                    row = "#"
                row += " " + word
            out.append(" " * indent + f'<span class="com">{escape(row)}</span>')
        else:
            out.append(" " * indent + _html(text, line_spans, lo, hi) + (" \\" if backslash else ""))
    return tuple(out)


def read_listing(kit_root: Path, target: str, start: str | None, stop: str | None, where: str,
                 width: int = FOLD_WIDTH) -> Listing:
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
    spans, breaks = _spans(source)
    shown: list[tuple[int, tuple[str, ...]] | None] = []
    previous = None
    for n in signature + body:
        skipped_markers_only = previous is not None and all(MARKER.match(texts[m]) for m in range(previous + 1, n))
        if previous is not None and n != previous + 1 and not skipped_markers_only:
            shown.append(None)          # lines left out (the docstring, a from: range): a visible gap
        shown.append((n, _rows(n, texts[n], spans, breaks, width)))
        previous = n
    rows = sum(len(s[1]) for s in shown if s)
    if rows > MAX_LINES:
        raise KitError(f"{where}: {target} shows {rows} rows of code, more than a slide holds at a size the back "
                       f"row reads ({MAX_LINES}): choose a shorter range with from: and to:")
    too_wide = [(e[0], len(row)) for e in shown if e for row in (unescape(re.sub(r"<[^>]+>", "", r)) for r in e[1])
                if len(row) > width]
    if too_wide:
        n, chars = too_wide[0]
        raise KitError(f"{where}: {path_text}:{n} is {chars} characters with nowhere Python lets it fold, wider than a "
                       f"slide shows ({width}): shorten that line of the reference or choose a range without it")
    return Listing(path=path_text, function=qualname, lines=tuple(shown), texts=texts)
