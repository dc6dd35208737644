"""``cs451 slides build``: every deck of ``slides/`` as one HTML file that opens offline.

Everything a deck needs is inside its one file: reveal.js (the slides, keyboard navigation, speaker notes,
``?print-pdf``) and KaTeX (the math, with its fonts) from ``vendor/``, the kit's style and script, and every
figure as a ``data:`` URL. A Content-Security-Policy in the page allows only inline code and ``data:`` URLs,
so even a browser that could reach the network fetches nothing. Figures come from ``figures.py``
(``render_figure``), which caches them by a hash of what made them; the cache is ``.cs451-cache/slides`` in
the kit, beside the grader's answers, or ``$XDG_CACHE_HOME/cs451/slides`` where the kit is read-only.
"""
from __future__ import annotations

import base64
import functools
import json
import os
import re
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from jinja2 import Environment, FileSystemLoader, StrictUndefined

from .. import KIT_ROOT, __version__
from ..caches import kit_cache
from ..errors import KitError
from ..progress import Progress
from .deck import Deck, Picture, deck_files, deck_name, read_deck

HERE = Path(__file__).resolve().parent
VENDOR = HERE / "vendor"
TEMPLATES = HERE / "templates"
#: The page may run its own inline code and show data: URLs; it may fetch nothing (frames: the speaker view
#: shows the same file in two frames).
CSP = ("default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; img-src data:; "
       "font-src data:; frame-src 'self' file:")
MIME = {".png": "image/png", ".jpg": "image/jpeg", ".jpeg": "image/jpeg", ".svg": "image/svg+xml"}


@dataclass(frozen=True)
class Built:
    """One deck written: where, and what it holds."""
    deck: str
    path: Path
    slides: int
    figures: int
    bytes: int


def default_cache() -> Path:
    """Where figures are cached: ``$CS451_SLIDES_CACHE``, else the kit's ``.cs451-cache/slides`` (ignored by git,
    hidden from submissions), else the user's cache folder where the kit cannot be written (an installed wheel)."""
    if os.environ.get("CS451_SLIDES_CACHE"):
        return Path(os.environ["CS451_SLIDES_CACHE"])
    return kit_cache("slides")


def _vendored(rel: str) -> str:
    path = VENDOR / rel
    if not path.is_file():
        raise KitError(f"{path}: missing (the vendored copy is incomplete: see cs451/slides/vendor/README.md)")
    return path.read_text(encoding="utf-8")


def _script(text: str) -> str:
    """JavaScript safe inside an inline <script>: no ``</script`` may end it early."""
    return re.sub(r"</(script)", r"<\\/\1", text, flags=re.I)


def _data_url(data: bytes, mime: str) -> str:
    return f"data:{mime};base64,{base64.b64encode(data).decode('ascii')}"


def _katex_css() -> str:
    """KaTeX's style with its fonts inside it (woff2, which every current browser reads), nothing to fetch."""
    css = _vendored("katex/katex.min.css")

    def inline(m: re.Match) -> str:
        font = VENDOR / "katex" / "fonts" / f"{m.group(1)}.woff2"
        if not font.is_file():
            raise KitError(f"{font}: missing (see cs451/slides/vendor/README.md)")
        return f'src:url({_data_url(font.read_bytes(), "font/woff2")}) format("woff2")'
    return re.sub(r'src:url\(fonts/([\w-]+)\.woff2\) format\("woff2"\)(?:,url\([^)]*\) format\("[^"]*"\))*',
                  inline, css)


@functools.lru_cache(maxsize=1)
def assets() -> dict[str, str]:
    """The vendored and the kit's own CSS and JavaScript, ready to inline; checked to fetch nothing."""
    out = {
        "reveal_css": _vendored("reveal.js/reveal.css"),
        "theme_css": _vendored("reveal.js/theme/white.css"),
        "katex_css": _katex_css(),
        "kit_css": (TEMPLATES / "deck.css").read_text(encoding="utf-8"),
        "reveal_js": _script(_vendored("reveal.js/reveal.js")),
        "notes_js": _script(_vendored("reveal.js/plugin/notes.js")),
        "katex_js": _script(_vendored("katex/katex.min.js")),
        "kit_js": _script((TEMPLATES / "deck.js").read_text(encoding="utf-8")),
    }
    for key in ("reveal_css", "theme_css", "katex_css", "kit_css"):
        remote = re.search(r"@import|url\((?!\s*['\"]?data:)", out[key])
        if remote:
            raise KitError(f"{key}: {out[key][remote.start():remote.start() + 60]!r}: a vendored style would fetch "
                           "a file; the deck must open offline")
    return out


def versions() -> dict[str, str]:
    """The vendored packages' versions (their package.json, kept beside them)."""
    out = {}
    for name in ("reveal.js", "katex"):
        out[name] = json.loads(_vendored(f"{name}/package.json"))["version"]
    return out


def select_decks(deck: str | None, kit_root: Path) -> list[Path]:
    """The deck files to build: all, or the one named (``whitted`` or ``02-whitted.md``)."""
    files = deck_files(kit_root)
    if deck is None:
        if not files:
            raise KitError(f"{kit_root / 'slides'}: holds no deck (NN-name.md)")
        return files
    chosen = [f for f in files if deck_name(f) == deck or f.name == deck]
    if not chosen:
        raise KitError(f"deck {deck!r}: no such deck; the decks are {', '.join(deck_name(f) for f in files)}")
    return chosen


def _figures_module() -> Any:
    try:
        from . import figures
    except ImportError as err:
        raise KitError(f"cs451/slides/figures.py cannot be imported ({err}): the decks' figures cannot be "
                       "rendered") from None
    return figures


def picture(path: Path) -> Picture:
    """A PNG (or another image) as the page shows it: inlined, with its size and, for the kit's figures, the
    smallest text drawn in it (the ``cs451:text_px`` chunk ``figures.py`` writes)."""
    from PIL import Image

    data = path.read_bytes()
    text_px = None
    try:
        with Image.open(path) as image:
            width, height = image.size
            chunk = getattr(image, "text", {}).get("cs451:text_px")
            text_px = float(chunk) if chunk is not None else None
    except (OSError, ValueError):
        width = height = 0                      # an SVG: the browser sizes it
    return Picture(_data_url(data, MIME[path.suffix.lower()]), width, height, text_px)


def render_figures(decks: list[Deck], cache: Path, quick: bool) -> dict[str, Picture]:
    """Every figure the decks name, as a picture; unknown names fail with the deck's file and line."""
    needed = [ref for d in decks for ref in d.figures]
    urls: dict[str, Picture] = {}
    for d in decks:
        for rel, path in d.images.items():
            urls[rel] = picture(path)
    if not needed:
        return urls
    module = _figures_module()
    known = module.FIGURES
    for ref in needed:
        if ref.name not in known:
            raise KitError(f"{ref.file}:{ref.line}: unknown figure {ref.name!r} "
                           f"(the figures: {', '.join(sorted(known))})")
    names = list(dict.fromkeys(ref.name for ref in needed))
    first = {ref.name: ref for ref in reversed(needed)}
    try:
        cache.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise KitError(f"--cache {cache}: cannot make the figures' cache there ({err.strerror or err})") from None
    bar = Progress("slides: figures", len(names), unit="figure")
    try:
        for name in names:
            bar.advance(0, note=name)
            try:
                png = Path(module.render_figure(name, cache, quick=quick))
            except KitError:
                raise
            except Exception as err:   # the figure's own bug: say which figure and which slide asked for it
                ref = first[name]
                raise KitError(f"{ref.file}:{ref.line}: figure {name!r} failed: {type(err).__name__}: {err}") from err
            if not png.is_file():
                raise KitError(f"figure {name!r}: render_figure returned {png}, which is not a file")
            urls[f"figure:{name}"] = picture(png)
            bar.advance(1, note=name)
    finally:
        bar.close()
    return urls


@functools.lru_cache(maxsize=1)
def _template():
    env = Environment(loader=FileSystemLoader(str(TEMPLATES)), autoescape=True, undefined=StrictUndefined,
                      keep_trailing_newline=True)
    return env.get_template("deck.html.j2")


def deck_html(deck: Deck) -> str:
    """The whole page of one read deck (figures already resolved)."""
    return _template().render(deck=deck, csp=CSP, assets=assets(), versions=versions(), kit_version=__version__)


def build_slides(*, output: str | Path, deck: str | None = None, cache: str | Path | None = None,
                 quick: bool = False, kit_root: Path | None = None) -> list[Built]:
    """Build one deck (``deck``: ``whitted``) or all of them into ``output``/<name>.html.

    Every deck is read and checked before any figure renders, so a typo fails in a second, not after the
    figures. ``quick`` asks the figures for their draft versions. ``kit_root`` is the kit whose slides and
    reference are read (a copy, in the tests).
    """
    root = Path(kit_root) if kit_root is not None else KIT_ROOT
    out = Path(output)
    if out.exists() and not out.is_dir():
        raise KitError(f"-o {out}: is a file, not a folder")
    folder = Path(cache) if cache is not None else default_cache()
    if folder.exists() and not folder.is_dir():
        raise KitError(f"--cache {folder}: is a file, not a folder")
    files = select_decks(deck, root)
    checked = [read_deck(f, root) for f in files]
    urls = render_figures(checked, folder, quick)
    built = []
    try:
        out.mkdir(parents=True, exist_ok=True)
        for f, first in zip(files, checked):
            read = read_deck(f, root, lambda target, where: urls[target])
            page = deck_html(read)
            path = out / f"{read.name}.html"
            path.write_text(page, encoding="utf-8")
            built.append(Built(read.name, path, len(read.slides), len(first.figures), len(page.encode("utf-8"))))
    except OSError as err:
        raise KitError(f"-o {out}: cannot write there ({err.strerror or err})") from None
    return built


def build_summary(built: list[Built], seconds: float) -> str:
    """One line for the terminal: how many decks and slides, how big, how long."""
    total = sum(b.bytes for b in built)
    return (f"built {len(built)} deck{'s' if len(built) != 1 else ''} ({sum(b.slides for b in built)} slides, "
            f"{total / 1e6:.1f} MB) in {seconds:.1f} s")


def timed_build(**kwargs: Any) -> tuple[list[Built], float]:
    """``build_slides`` and its wall-clock time (the command prints it: a warm cache should make it short)."""
    start = time.perf_counter()
    built = build_slides(**kwargs)
    return built, time.perf_counter() - start
