"""Can the back row read it? A built deck measured as a projector shows it, in headless Chromium.

Each slide is shown at each screen size (1920 × 1080 and 1280 × 720 by default) and measured on the rendered
page, not in the source: the size of every run of text on screen, whether a line of code wraps or is cut,
how many pixels each figure has for each pixel it covers, how large the smallest text inside a figure comes
out, and whether anything lies under reveal.js's navigation arrows or the slide number. The floors are
:data:`FLOORS`; ``cs451 slides check`` prints what breaks them, ``tests/test_slides_readability.py`` fails on it.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .chromium import Chromium

#: Screen sizes (CSS pixels) a deck is checked at: a 1080p projector and a 720p one (or a small laptop).
SCREENS = ((1920, 1080), (1280, 720))


@dataclass(frozen=True)
class Floors:
    """The smallest sizes allowed on screen, in screen (CSS) pixels."""
    body_px: float = 24.0            # any text that is not code
    code_px: float = 20.0            # code: listings, code blocks, inline code
    figure_text_px: float = 16.0     # text drawn inside a figure, as shown
    figure_density: float = 2.0      # figure pixels per slide pixel (1.33 per screen pixel at 1080p)


FLOORS = Floors()

#: Reads the slide on screen: every text run's size (from its element's computed font size and the slide's
#: scale on screen), code rows that wrap and code blocks cut on the right, each image's pixels against its
#: shown size, and every text or image box that meets the navigation controls or the slide number.
MEASURE = r"""(() => {
  const slide = Reveal.getCurrentSlide(), cfg = Reveal.getConfig();
  const box = slide.getBoundingClientRect(), scale = box.width / cfg.width;
  const skip = e => e.closest('aside.notes, .katex-mathml, .controls, .slide-number, .progress');
  const hidden = e => { const st = getComputedStyle(e); return st.display === 'none' || st.visibility === 'hidden'; };
  const runs = [];
  const walker = document.createTreeWalker(slide, NodeFilter.SHOW_TEXT);
  for (let node = walker.nextNode(); node; node = walker.nextNode()) {
    const el = node.parentElement;
    if (!node.textContent.trim() || skip(el) || hidden(el)) continue;
    const math = el.closest('.katex');        // a formula is measured at its base size, not its sub- and superscripts
    const sized = math || el;
    const range = document.createRange(); range.selectNodeContents(node);
    const rects = [...range.getClientRects()].filter(r => r.width > 0 && r.height > 0);
    if (!rects.length) continue;
    runs.push({text: node.textContent.trim().slice(0, 60), code: !!el.closest('pre, code'), math: !!math,
               px: parseFloat(getComputedStyle(sized).fontSize) * scale,
               rects: rects.map(r => [r.left, r.top, r.right, r.bottom])});
  }
  const wrapped = [...slide.querySelectorAll('.listing .line, pre.code code')].flatMap(e => {
    const lh = parseFloat(getComputedStyle(e).lineHeight) * scale;
    const rows = e.matches('.line') ? 1 : e.textContent.split('\n').length;
    const cut = e.scrollWidth > e.clientWidth + 1 || e.closest('pre').scrollWidth > e.closest('pre').clientWidth + 1;
    return (e.getBoundingClientRect().height > rows * lh * 1.5 || cut) ? [e.textContent.trim().slice(0, 60)] : [];
  });
  const images = [...slide.querySelectorAll('img')].filter(i => !hidden(i)).map(i => {
    const r = i.getBoundingClientRect();
    return {figure: (i.closest('figure') || i).dataset.figure || i.alt, natural: [i.naturalWidth, i.naturalHeight],
            shown: [r.width, r.height], slidePx: r.width / scale, textPx: parseFloat(i.dataset.textPx || 'NaN'),
            rect: [r.left, r.top, r.right, r.bottom]};
  });
  // the left and right arrows (drawn on every slide of a flat deck, faint where disabled, fading in and out) and
  // the slide number; the up and down arrows of vertical decks are never shown
  const chrome = [...document.querySelectorAll('.reveal .controls .navigate-left, .reveal .controls .navigate-right,'
                                               + ' .reveal .slide-number')].filter(e => !hidden(e))
    .map(e => e.getBoundingClientRect()).filter(r => r.width > 0 && r.height > 0)
    .map(r => [r.left, r.top, r.right, r.bottom]);
  const inner = [...slide.querySelectorAll('*')].filter(e => !skip(e) && !e.ownerSVGElement)
    .map(e => e.getBoundingClientRect()).filter(r => r.width > 0 && r.height > 0);
  const overflow = [Math.max(0, ...inner.map(r => (r.right - box.left) / scale - cfg.width)),
                    Math.max(0, ...inner.map(r => (r.bottom - box.top) / scale - cfg.height))];
  return {source: slide.dataset.source, scale: scale, runs: runs, wrapped: wrapped, images: images, chrome: chrome,
          overflow: overflow};
})()"""


@dataclass
class Measured:
    """What one deck measured at one screen size: the smallest sizes found, and every breach of the floors."""
    screen: tuple[int, int]
    slides: int = 0
    body_px: float = float("inf")
    code_px: float = float("inf")
    figure_text_px: float = float("inf")
    figure_density: float = float("inf")
    problems: list[str] = field(default_factory=list)


def _meets(a: list[float], b: list[float]) -> bool:
    return a[0] < b[2] - 0.5 and b[0] < a[2] - 0.5 and a[1] < b[3] - 0.5 and b[1] < a[3] - 0.5


def judge(state: dict[str, Any], screen: tuple[int, int], floors: Floors, out: Measured) -> None:
    """Add one slide's measurements to ``out``, with a line for each breach (``slides/x.md:12 (1280×720): …``)."""
    where = f"{state['source']} ({screen[0]}×{screen[1]})"
    out.slides += 1
    for run in state["runs"]:
        floor = floors.code_px if run["code"] else floors.body_px
        if run["code"]:
            out.code_px = min(out.code_px, run["px"])
        else:
            out.body_px = min(out.body_px, run["px"])
        if run["px"] < floor - 0.05:
            kind = "code" if run["code"] else "math" if run["math"] else "text"
            out.problems.append(f"{where}: {kind} at {run['px']:.1f} px, under {floor:g}: {run['text']!r}")
        for box in run["rects"]:
            if any(_meets(box, c) for c in state["chrome"]):
                out.problems.append(f"{where}: text under the navigation controls: {run['text']!r}")
                break
    right, below = state.get("overflow", (0, 0))
    if right > 1 or below > 1:
        out.problems.append(f"{where}: the slide overflows its 1280×720 box by {right:.0f} px on the right and "
                            f"{below:.0f} px at the bottom")
    for text in state["wrapped"]:
        out.problems.append(f"{where}: a line of code wraps or is cut off: {text!r}")
    for image in state["images"]:
        (nw, nh), (sw, sh) = image["natural"], image["shown"]
        if nw and nh and sw and sh and abs((sw / sh) / (nw / nh) - 1) > 0.02:
            out.problems.append(f"{where}: {image['figure']}: shown {sw:.0f}×{sh:.0f}, squashed from its "
                                f"{nw}×{nh} pixels")
        density = image["natural"][0] / max(image["slidePx"], 1e-9)
        out.figure_density = min(out.figure_density, density)
        if density < floors.figure_density - 0.01:
            out.problems.append(f"{where}: {image['figure']}: {image['natural'][0]} pixels shown {image['slidePx']:.0f} "
                                f"slide pixels wide ({density:.2f} per pixel, under {floors.figure_density:g})")
        if image["textPx"] is None:                      # NaN in the page: the picture does not say
            out.problems.append(f"{where}: {image['figure']}: does not say how small its text is (the kit's "
                                "figures write it in their PNG; a picture of text made another way cannot be checked)")
        elif image["textPx"] > 0:                        # 0: the figure has no text
            shown = image["textPx"] * image["shown"][0] / max(image["natural"][0], 1)
            out.figure_text_px = min(out.figure_text_px, shown)
            if shown < floors.figure_text_px - 0.05:
                out.problems.append(f"{where}: {image['figure']}: its smallest text shows at {shown:.1f} px, under "
                                    f"{floors.figure_text_px:g}")
        if any(_meets(image["rect"], c) for c in state["chrome"]):
            out.problems.append(f"{where}: {image['figure']} lies under the navigation controls")


def measure_deck(browser: Chromium, html: Path, screens: tuple[tuple[int, int], ...] = SCREENS,
                 floors: Floors = FLOORS) -> list[Measured]:
    """Open a built deck at each screen size, show every slide, and measure it (:data:`MEASURE`)."""
    results = []
    for screen in screens:
        page = browser.page()
        try:
            page.viewport(*screen)
            page.open(html.as_uri())
            total = page.eval("Reveal.getTotalSlides()")
            out = Measured(screen)
            for k in range(total):
                page.eval(f"Reveal.slide({k}, 0)")
                page.eval("new Promise(done => requestAnimationFrame(() => requestAnimationFrame(() => done(true))))")
                judge(page.eval(MEASURE), screen, floors, out)
            problems = page.problems()
            out.problems += [f"{html.name} ({screen[0]}×{screen[1]}): {p}" for p in problems]
            results.append(out)
        finally:
            page.call("Page.close")
    return results


def summary(deck: str, results: list[Measured]) -> str:
    """One line per screen size: the smallest body text, code, figure text and figure density found."""
    def px(v: float) -> str:
        return "—" if v == float("inf") else f"{v:.1f}"
    return "\n".join(f"{deck} at {m.screen[0]}×{m.screen[1]}: {m.slides} slides; smallest text {px(m.body_px)} px, "
                     f"code {px(m.code_px)} px, figure text {px(m.figure_text_px)} px; figures at "
                     f"{px(m.figure_density)} pixels per slide pixel; {len(m.problems)} problems" for m in results)


def as_json(deck: str, results: list[Measured]) -> str:
    def num(v: float) -> float | None:
        return None if v == float("inf") else round(v, 2)
    return json.dumps([{"deck": deck, "screen": list(m.screen), "slides": m.slides, "body_px": num(m.body_px),
                        "code_px": num(m.code_px), "figure_text_px": num(m.figure_text_px),
                        "figure_density": num(m.figure_density), "problems": m.problems} for m in results], indent=1)
