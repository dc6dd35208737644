"""A deck: one Markdown file of ``slides/`` (``NN-name.md``), read into slides of HTML.

The kit reads a small, strict Markdown of its own rather than a general one, so that every mistake is a
one-line error naming the deck's file and line, and so that math, figures and listings are known to the
builder (which typesets, renders and pulls them) instead of being guessed from free text:

- ``---`` on a line of its own starts a new slide; ``Note:`` starts the slide's speaker notes.
- ``#``/``##``/``###`` headings, paragraphs, ``-``/``1.`` lists (nested by indenting), ``|`` tables,
  ``**bold**``, ``*italic*``, `` `code` ``, ``[text](https://…)``.
- ``$…$`` inline math and ``$$ … $$`` display math (TeX, typeset by KaTeX in the browser).
- ``![caption](figure:NAME)`` on a line of its own: a figure rendered from the reference
  (``cs451/slides/figures.py``); ``![caption](file.png)`` an image beside the deck. ``{height=300}`` after
  either sets its height in pixels (the slide is 1280 × 720).
- a ``pseudo`` code block: pseudo-code in the kit's words; a line ending in ``[[text]]`` points at the line
  of the slide's ``reference`` listing that contains ``text`` (the first such line after the one the pointer
  before it found, else the first), and both get the same number.
- a ``reference`` code block: ``reference/<stage>/<file>.py::function`` and optionally ``from: text``,
  ``to: text`` and ``width: CHARACTERS`` (where long lines fold; 80, a whole slide, unless the listing sits
  in a column; see ``listing.py``).
- ``|||`` on a line of its own: what follows goes into the next column.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from html import escape
from pathlib import Path
from typing import Callable

from ..errors import KitError
from .listing import FOLD_WIDTH, Listing, read_listing
from .inline import inline_html

DECK_FILE = re.compile(r"^(\d\d)-([a-z][a-z0-9-]*)\.md$")
HEADING = re.compile(r"^(#{1,3})\s+(.*)$")
ITEM = re.compile(r"^(\s*)([-*]|\d+\.)\s+(.*)$")
IMAGE_LINE = re.compile(r"^!\[([^\]]*)\]\(([^)\s]+)\)(\{[^}]*\})?\s*$")
ATTRIBUTE = re.compile(r"^(height|width)=(\d+)(%?)$")
POINTER = re.compile(r"\s*\[\[(.+?)\]\]\s*$")
FENCE = "```"
CODE_LANGUAGES = {"", "python", "glsl", "c", "text", "sh", "json"}
LISTING_KEYS = {"from", "to", "width"}


@dataclass(frozen=True)
class FigureRef:
    """A figure a deck asks for, and where (``slides/02-whitted.md``, line)."""
    name: str
    file: str
    line: int


@dataclass
class Slide:
    line: int
    html: str = ""
    notes: str = ""
    classes: list[str] = field(default_factory=list)


@dataclass
class Deck:
    """One deck: ``name`` (``whitted``), its file relative to the kit, the title, slides and figures."""
    name: str
    order: int
    path: Path
    file: str
    title: str
    slides: list[Slide]
    figures: list[FigureRef]
    images: dict[str, Path]


@dataclass(frozen=True)
class Picture:
    """A figure's picture as the page gets it: a ``data:`` URL, its pixel size, and the size of the smallest
    text drawn in it (PNG pixels; None where it has no text or does not say)."""
    url: str
    width: int
    height: int
    text_px: float | None = None


#: How a figure's picture reaches the HTML: (``figure:NAME`` or a path, where) -> the picture.
Resolver = Callable[[str, str], Picture]


def deck_files(kit_root: Path) -> list[Path]:
    """The decks of ``slides/``, in their numbered order (README.md and other files are not decks)."""
    folder = kit_root / "slides"
    if not folder.is_dir():
        raise KitError(f"{folder}: no slides folder in this copy of the kit")
    return sorted(p for p in folder.iterdir() if p.is_file() and DECK_FILE.match(p.name))


def deck_name(path: Path) -> str:
    match = DECK_FILE.match(path.name)
    assert match, path
    return match.group(2)


# -- inline text -------------------------------------------------------------------------------------


# -- blocks ------------------------------------------------------------------------------------------

class _Reader:
    """Turns one slide's numbered lines into HTML blocks; knows the deck for figures and listings."""

    def __init__(self, deck: Deck, kit_root: Path, resolve: Resolver | None):
        self.deck, self.kit_root, self.resolve = deck, kit_root, resolve

    def where(self, line: int) -> str:
        return f"{self.deck.file}:{line}"

    def slide(self, lines: list[tuple[int, str]]) -> tuple[str, str]:
        notes_at = next((k for k, (_, t) in enumerate(lines) if t.startswith("Note:")), None)
        notes: list[tuple[int, str]] = []
        if notes_at is not None:
            first = lines[notes_at]
            notes = [(first[0], first[1][len("Note:"):].strip())] + lines[notes_at + 1:]
            lines = lines[:notes_at]
        self.listings: list[Listing] = []
        self.pointers = 0
        columns: list[list[tuple[int, str]]] = [[]]
        fenced = False
        for n, t in lines:
            if t.startswith(FENCE):
                fenced = not fenced
            if t.strip() == "|||" and not fenced:
                columns.append([])
            else:
                columns[-1].append((n, t))
        head: list[tuple[int, str]] = []
        if len(columns) > 1:          # the slide's heading spans the columns
            first = next((k for k, (_, t) in enumerate(columns[0]) if t.strip()), None)
            if first is not None and HEADING.match(columns[0][first][1]):
                head, columns[0] = [columns[0][first]], columns[0][first + 1:]
        for col in columns:          # listings first: the pseudo-code of any column may point into them
            self.blocks(col, listings_only=True)
        self.shown = 0
        rendered = [self.blocks(col) for col in columns]
        if len(rendered) == 1:
            body = rendered[0]
        else:
            body = (self.blocks(head) + '<div class="columns">'
                    + "".join(f'<div class="column">{c}</div>' for c in rendered) + "</div>")
        for k, listing in enumerate(self.listings):
            body = body.replace(f"\0listing{k}\0", self.listing_html(listing))
        notes_html = self.blocks(notes) if notes else ""
        return body, notes_html

    def blocks(self, lines: list[tuple[int, str]], listings_only: bool = False) -> str:
        out: list[str] = []
        k = 0
        while k < len(lines):
            n, t = lines[k]
            if not t.strip():
                k += 1
                continue
            if t.startswith(FENCE):
                end = next((j for j in range(k + 1, len(lines)) if lines[j][1].startswith(FENCE)), None)
                if end is None:
                    raise KitError(f"{self.where(n)}: a ``` block that no ``` closes")
                lang = t[len(FENCE):].strip()
                inner = lines[k + 1:end]
                if lang == "reference":
                    if listings_only:
                        self.listings.append(self.listing(n, inner))
                    elif self.shown >= len(self.listings):
                        raise KitError(f"{self.where(n)}: a reference listing goes on the slide, not in its notes")
                    else:       # a placeholder: the pseudo-code after it may still point into it
                        out.append(f"\0listing{self.shown}\0")
                        self.shown += 1
                elif not listings_only:
                    out.append(self.pseudo(n, inner) if lang == "pseudo" else self.code(n, lang, inner))
                k = end + 1
                continue
            if listings_only:
                k += 1
                continue
            if t.startswith("$$"):
                k = self.display_math(lines, k, out)
                continue
            heading = HEADING.match(t)
            if heading:
                level = len(heading.group(1))
                out.append(f"<h{level}>{inline_html(heading.group(2).strip(), self.where(n))}</h{level}>")
                k += 1
                continue
            image = IMAGE_LINE.match(t.strip())
            if image:
                out.append(self.figure(n, image.group(1), image.group(2), image.group(3)))
                k += 1
                continue
            if ITEM.match(t):
                k = self.list_block(lines, k, out)
                continue
            if t.lstrip().startswith("|"):
                k = self.table(lines, k, out)
                continue
            para = [t.strip()]
            k += 1
            while k < len(lines) and lines[k][1].strip() and not self._starts_block(lines[k][1]):
                para.append(lines[k][1].strip())
                k += 1
            out.append(f"<p>{inline_html(' '.join(para), self.where(n))}</p>")
        return "\n".join(out)

    @staticmethod
    def _starts_block(t: str) -> bool:
        return bool(t.startswith((FENCE, "$$", "#")) or ITEM.match(t) or t.lstrip().startswith("|")
                    or IMAGE_LINE.match(t.strip()))

    def display_math(self, lines: list[tuple[int, str]], k: int, out: list[str]) -> int:
        n, first = lines[k]
        body = first[2:]
        j = k
        while not body.rstrip().endswith("$$") or (j == k and not body.strip()):
            j += 1
            if j >= len(lines):
                raise KitError(f"{self.where(n)}: a $$ block that no $$ closes")
            body += "\n" + lines[j][1]
        tex = body.rstrip()[:-2].strip()
        if not tex:
            raise KitError(f"{self.where(n)}: an empty $$ block")
        out.append(f'<div class="math display" data-source="{escape(self.where(n))}">{escape(tex)}</div>')
        return j + 1

    def list_block(self, lines: list[tuple[int, str]], k: int, out: list[str]) -> int:
        items: list[tuple[int, bool, int, str]] = []   # indent, ordered, line, text
        while k < len(lines) and lines[k][1].strip():
            n, t = lines[k]
            item = ITEM.match(t)
            if item:
                items.append((len(item.group(1)), item.group(2)[0].isdigit(), n, item.group(3).strip()))
            elif t.startswith(" ") and items:
                indent, ordered, line, text = items[-1]
                items[-1] = (indent, ordered, line, text + " " + t.strip())
            else:
                break
            k += 1
        out.append(self._nest(items, 0, len(items)))
        return k

    def _nest(self, items: list[tuple[int, bool, int, str]], lo: int, hi: int) -> str:
        indent, ordered = items[lo][0], items[lo][1]
        tag = "ol" if ordered else "ul"
        html, j = [f"<{tag}>"], lo
        while j < hi:
            ind, ordd, n, text = items[j]
            if ind < indent:
                raise KitError(f"{self.where(n)}: this item is indented less than the list it is in")
            children_end = j + 1
            while children_end < hi and items[children_end][0] > indent:
                children_end += 1
            inner = self._nest(items, j + 1, children_end) if children_end > j + 1 else ""
            html.append(f"<li>{inline_html(text, self.where(n))}{inner}</li>")
            j = children_end
        html.append(f"</{tag}>")
        return "".join(html)

    def table(self, lines: list[tuple[int, str]], k: int, out: list[str]) -> int:
        n = lines[k][0]
        rows = []
        while k < len(lines) and lines[k][1].lstrip().startswith("|"):
            rows.append((lines[k][0], lines[k][1].strip()))
            k += 1
        if len(rows) < 2 or not re.fullmatch(r"\|(\s*:?-+:?\s*\|)+", rows[1][1].replace(" ", "")):
            raise KitError(f"{self.where(n)}: a table needs a header row and a |---| row below it")

        def cells(text: str) -> list[str]:
            return [c.strip().replace("\\|", "|") for c in re.split(r"(?<!\\)\|", text.strip().strip("|"))]
        aligns = ["center" if c.startswith(":") and c.endswith(":") else "right" if c.endswith(":") else ""
                  for c in cells(rows[1][1])]
        width = len(aligns)
        html = ["<table>"]
        for r, (line, text) in enumerate([rows[0]] + rows[2:]):
            row = cells(text)
            if len(row) != width:
                raise KitError(f"{self.where(line)}: this row has {len(row)} cells, the table {width}")
            tag = "th" if r == 0 else "td"
            styles = [f' style="text-align:{a}"' if a else "" for a in aligns]
            html.append("<tr>" + "".join(f"<{tag}{st}>{inline_html(c, self.where(line))}</{tag}>"
                                         for c, st in zip(row, styles)) + "</tr>")
        html.append("</table>")
        out.append("".join(html))
        return k

    def figure(self, n: int, caption: str, target: str, attributes: str | None) -> str:
        where = self.where(n)
        style = []
        for attr in (attributes or "{}")[1:-1].split():
            m = ATTRIBUTE.match(attr)
            if not m:
                raise KitError(f"{where}: {{{attr}}}: a figure takes {{height=PIXELS}} or {{width=PIXELS}} (or %)")
            style.append(f"{'max-' if m.group(3) == '' else ''}{m.group(1)}:{m.group(2)}{m.group(3) or 'px'}")
        if target.startswith("figure:"):
            name = target[len("figure:"):]
            self.deck.figures.append(FigureRef(name, self.deck.file, n))
        elif re.match(r"^[a-z][a-z0-9+.-]*:", target) or target.startswith("//"):
            raise KitError(f"{where}: {target}: a deck shows figures (figure:NAME) or files beside it, never a "
                           "remote image (a built deck must open offline)")
        else:
            path = (self.deck.path.parent / target).resolve()
            if not path.is_file() or path.suffix.lower() not in (".png", ".jpg", ".jpeg", ".svg"):
                raise KitError(f"{where}: {target}: no such image beside the deck (.png, .jpg or .svg)")
            self.deck.images[target] = path
        picture = self.resolve(target, where) if self.resolve else Picture("", 0, 0)
        if picture.width:           # drawn at twice the slide's pixels: shown at half its size, or smaller
            style.append(f"max-width:min(100%,{picture.width / 2:g}px)")   # height and width auto: never squashed
        style_attr = f' style="{";".join(style)}"' if style else ""
        text = f' data-text-px="{picture.text_px:g}"' if picture.text_px is not None else ""
        cap = f"<figcaption>{inline_html(caption, where)}</figcaption>" if caption else ""
        return (f'<figure class="figure" data-figure="{escape(target)}"><img src="{picture.url}" '
                f'alt="{escape(caption)}"{text}{style_attr}>{cap}</figure>')

    def code(self, n: int, lang: str, inner: list[tuple[int, str]]) -> str:
        if lang not in CODE_LANGUAGES:
            raise KitError(f"{self.where(n)}: ```{lang}: a code block is one of "
                           f"{', '.join(sorted(CODE_LANGUAGES - {''}))}, pseudo or reference")
        text = "\n".join(t for _, t in inner)
        return f'<pre class="code"><code>{escape(text)}</code></pre>'

    def listing(self, n: int, inner: list[tuple[int, str]]) -> Listing:
        spec = [(m, t.strip()) for m, t in inner if t.strip()]
        if not spec:
            raise KitError(f"{self.where(n)}: a reference block names a function: reference/<stage>/<file>.py::name")
        options: dict[str, str] = {}
        for m, t in spec[1:]:
            key, sep, value = t.partition(":")
            if not sep or key.strip() not in LISTING_KEYS or not value.strip():
                raise KitError(f"{self.where(m)}: {t!r}: a reference block takes `from: text`, `to: text` and "
                               "`width: CHARACTERS` only")
            options[key.strip()] = value.strip()
        width = options.get("width", str(FOLD_WIDTH))
        if not width.isdigit() or not 30 <= int(width) <= FOLD_WIDTH:
            raise KitError(f"{self.where(spec[0][0])}: width: {width}: a listing is 30 to {FOLD_WIDTH} characters wide")
        return read_listing(self.kit_root, spec[0][1], options.get("from"), options.get("to"), self.where(spec[0][0]),
                            int(width))

    def listing_html(self, listing: Listing) -> str:
        rows = []
        for entry in listing.lines:
            if entry is None:
                rows.append('<span class="line gap"><span class="ln"></span>⋯</span>')
                continue
            number, parts = entry
            marks = "".join(f'<span class="pointer">{p}</span>' for p in self.marks.get((id(listing), number), []))
            cls = "line linked" if marks else "line"
            for k, html in enumerate(parts):      # a folded line: its first row has the number and the marks
                rows.append(f'<span class="{cls}{" cont" if k else ""}" data-line="{number}"><span class="ln">'
                            f'{number}</span>{html or " "}{"" if k else marks}</span>')
        caption = (f"<code>{escape(listing.path)}</code> · <code>{escape(listing.function)}</code> · "
                   f"{listing.span}")
        return (f'<figure class="listing"><figcaption>{caption}</figcaption>'
                f'<pre><code>{"".join(rows)}</code></pre></figure>')

    def pseudo(self, n: int, inner: list[tuple[int, str]]) -> str:
        rows = []
        for m, t in inner:
            if not t.strip():
                rows.append('<div class="step blank"></div>')
                continue
            indent = len(t) - len(t.lstrip(" "))
            text, marks = t.strip(), []
            while True:
                pointer = POINTER.search(text)
                if not pointer:
                    break
                marks.insert(0, self.point(m, pointer.group(1)))
                text = text[:pointer.start()].rstrip()
            badges = "".join(f'<span class="pointer">{p}</span>' for p in marks)
            rows.append(f'<div class="step" style="padding-left:{indent * 0.6:.1f}em">'
                        f"{inline_html(text, self.where(m))}{badges}</div>")
        return f'<div class="pseudo">{"".join(rows)}</div>'

    def point(self, line: int, snippet: str) -> int:
        for listing in self.listings:
            number = listing.find(snippet, after=self.last.get(id(listing), 0))
            if number is not None:
                self.pointers += 1
                self.last[id(listing)] = number
                self.marks.setdefault((id(listing), number), []).append(self.pointers)
                return self.pointers
        shown = ", ".join(f"{li.path}::{li.function}" for li in self.listings) or "no listing"
        raise KitError(f"{self.where(line)}: [[{snippet}]] is in no line of the reference this slide shows ({shown})")


def read_deck(path: Path, kit_root: Path, resolve: Resolver | None = None) -> Deck:
    """Read a deck; with ``resolve`` None, only check it and collect its figures (no pictures needed)."""
    match = DECK_FILE.match(path.name)
    if not match:
        raise KitError(f"{path}: a deck's file is named NN-name.md (e.g. 02-whitted.md)")
    try:
        rel = path.resolve().relative_to(kit_root.resolve()).as_posix()
    except ValueError:
        rel = str(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise KitError(f"{rel}: cannot be read ({err})") from None
    deck = Deck(name=match.group(2), order=int(match.group(1)), path=path, file=rel, title="", slides=[],
                figures=[], images={})
    chunks: list[list[tuple[int, str]]] = [[]]
    fenced = False
    for number, line in enumerate(text.splitlines(), 1):
        line = line.rstrip()
        if line.startswith(FENCE):
            fenced = not fenced
        if line == "---" and not fenced:
            chunks.append([])
        else:
            chunks[-1].append((number, line))
    reader = _Reader(deck, kit_root, resolve)
    for chunk in chunks:
        content = [(n, t) for n, t in chunk if t.strip()]
        if not content:
            where = chunk[0][0] if chunk else 1
            raise KitError(f"{rel}:{where}: an empty slide (two --- lines with nothing between them)")
        slide = Slide(line=content[0][0])
        reader.marks, reader.last = {}, {}
        slide.html, slide.notes = reader.slide(chunk)
        if not deck.title:
            title = next((HEADING.match(t) for _, t in content if HEADING.match(t)), None)
            if title is None or len(title.group(1)) != 1:
                raise KitError(f"{rel}:{content[0][0]}: a deck's first slide starts with its title (# Title)")
            deck.title = re.sub(r"[`*$]", "", title.group(2)).strip()
            slide.classes.append("title-slide")
        deck.slides.append(slide)
    return deck
