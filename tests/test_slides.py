"""The lecture decks: every deck builds into one HTML file, opens offline in a browser, and shows the reference.

The builder is tested with figures from a stub (``StubFigures``, in this file), so these tests are fast and do
not depend on how the figures are drawn; ``cs451/slides/figures.py`` keeps its own side of the contract
(every name the decks use, a cache key that changes with the reference) in the tests marked ``figures``.

The browser tests drive headless Chromium through the DevTools protocol on a pipe (``--remote-debugging-pipe``:
no websocket, no extra package), with the network unreachable (a proxy on a closed port, every host name
unresolvable); they fail on any request that is not a ``data:`` or ``file:`` URL, on any console error or
uncaught exception, on a slide that overflows, an image that does not load, or math left untypeset. They skip,
saying why, where Chromium is missing (``.ci/run`` installs it from Debian's packages).
"""
from __future__ import annotations

import base64
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import types
from pathlib import Path

import numpy as np
import pytest
from markupsafe import escape
from PIL import Image, PngImagePlugin

import cs451.slides
from cs451 import KIT_ROOT
from cs451.cli import main
from cs451.errors import KitError
from cs451.slides.build import CSP, assets, build_slides, versions
from cs451.slides.chromium import Chromium, Page, find_chromium
from cs451.slides import figures as real_figures
from cs451.slides.deck import deck_files, read_deck, deck_name
from cs451.stages import stage_names

#: The decks: the course's overview, then one per registered stage, in the registry's order (test01 fails where a
#: stage has none).
DECKS = ("overview", *stage_names())
#: The figures the decks use: every figure the stages declare (each in its own package's figures; test01 fails on a
#: declared figure no deck shows, and on a deck showing one nobody declares).
FIGURE_NAMES = tuple(sorted(real_figures.FIGURES))
#: The reference function each stub figure pretends to be drawn with (its source enters the stub's key).
STUB_SOURCES = {"hemicube-delta-weights": ("reference/hemicube/tables.py", "delta_form_factors"),
                "radiosity-progress": ("reference/radiosity/shooting.py", "shoot")}
CHROMIUM = find_chromium()
needs_chromium = pytest.mark.skipif(CHROMIUM is None, reason="no Chromium here (apt-get install chromium; .ci/run "
                                                             "installs it): the decks are not opened in a browser")


# --- figures from a stub --------------------------------------------------------------------------------

class StubFigures(types.ModuleType):
    """``cs451.slides.figures`` as the builder sees it: FIGURES and render_figure(name, cache, quick).

    Each figure is a distinct picture (stripes whose colours come from its key), cached by a key that holds
    the source of the reference function named in STUB_SOURCES, read from ``root``: what the real module
    promises, in small.
    """

    def __init__(self, root: Path = KIT_ROOT):
        super().__init__("cs451.slides.figures")
        self.FIGURES = {name: f"a stub of {name}" for name in FIGURE_NAMES}
        self.root = root
        self.drawn: list[str] = []

    def key(self, name: str, quick: bool) -> str:
        digest = hashlib.sha256(f"{name} {quick}".encode())
        if name in STUB_SOURCES:
            file, function = STUB_SOURCES[name]
            text = (self.root / file).read_text()
            body = re.search(rf"^def {function}\(.*?(?=^\S|\Z)", text, flags=re.S | re.M)
            digest.update(body.group(0).encode())
        return digest.hexdigest()[:16]

    def render_figure(self, name: str, cache: Path, quick: bool = False) -> Path:
        if name not in self.FIGURES:
            raise KitError(f"unknown figure {name!r}")
        key = self.key(name, quick)
        path = Path(cache) / f"{name}-{key}.png"
        if not path.is_file():
            self.drawn.append(name)
            palette = np.frombuffer(bytes.fromhex(key), dtype=np.uint8)[:6].reshape(2, 3).astype(np.float64)
            width, height = (640, 400) if not quick else (320, 200)
            y, x = np.mgrid[0:height, 0:width]
            stripes = ((x // 40 + y // 40) % 2)[..., None]               # a checkerboard in the key's colours
            ramp = np.stack([x * 255 / width, y * 255 / height, np.full(x.shape, 128.0)], axis=-1)
            image = np.where(stripes == 1, palette[1], palette[0]) * 0.7 + ramp * 0.3
            info = PngImagePlugin.PngInfo()
            # a stub says it holds no text: its shape is not the real figure's, so the size its text would show
            # at says nothing (test 18 measures the real figures' text)
            info.add_text("cs451:text_px", "0")
            Image.fromarray(image.astype(np.uint8)).save(path, pnginfo=info)
        return path


def install_stub(patch: pytest.MonkeyPatch, root: Path = KIT_ROOT) -> StubFigures:
    stub = StubFigures(root)
    patch.setitem(sys.modules, "cs451.slides.figures", stub)
    patch.setattr(cs451.slides, "figures", stub, raising=False)
    return stub


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> dict[str, Path]:
    """Every deck of the repository as it is, built once with the stub's figures."""
    out = tmp_path_factory.mktemp("decks")
    with pytest.MonkeyPatch.context() as patch:
        install_stub(patch)
        decks = build_slides(output=out / "html", cache=out / "cache")
    return {d.deck: d.path for d in decks}


def kit_copy(top: Path) -> Path:
    """The parts of the kit a build reads: slides/ and reference/ (the builder takes ``kit_root``)."""
    kit = top / "kit"
    for part in ("slides", "reference"):
        shutil.copytree(KIT_ROOT / part, kit / part, ignore=shutil.ignore_patterns("__pycache__"))
    return kit


# --- building -------------------------------------------------------------------------------------------

def test01_every_deck_builds_into_one_file_that_fetches_nothing(built):
    assert tuple(built) == DECKS
    for name, path in built.items():
        page = path.read_text()
        assert f'content="{escape(CSP)}"' in page, name        # the browser itself refuses any fetch
        # nothing the page loads by itself points outside it: its markup (scripts aside) and its styles name
        # data: URLs only, and it has no <link>, no <script src> and no @import
        markup = re.sub(r"<script>.*?</script>", "<script></script>", page, flags=re.S)
        assert markup.count("<script></script>") == 4 and "<script " not in markup, name
        links = re.findall(r"""\b(?:src|srcset|poster|href)\s*=\s*["']([^"']*)["']""", markup)
        assert links and not [u for u in links if not u.startswith(("data:", "#", "https://", "http://"))], name
        assert not re.findall(r"<(?:link|iframe|object|embed|video|audio)\b", markup, re.I), name
        styles = "".join(re.findall(r"<style>(.*?)</style>", page, flags=re.S)) + "".join(
            re.findall(r'style="([^"]*)"', markup))
        assert "@import" not in styles and not re.findall(r"""url\(\s*['"]?(?!data:)""", styles), name
        assert page.count("<section ") == len(read_deck(deck_files(KIT_ROOT)[DECKS.index(name)], KIT_ROOT).slides)
    used = {ref.name for f in deck_files(KIT_ROOT) for ref in read_deck(f, KIT_ROOT).figures}
    assert used == set(FIGURE_NAMES), "every declared figure is shown, and no other"


def test01_every_stage_s_deck_shows_a_figure_of_its_own():
    """A stage's deck (``slides/NN-<stage>.md``) shows at least one figure its own package draws."""
    shown = {deck_name(f): {ref.name for ref in read_deck(f, KIT_ROOT).figures} for f in deck_files(KIT_ROOT)}
    for stage in stage_names():
        own = {name for name in FIGURE_NAMES
               if real_figures.spec_of(name).draw.__module__.startswith(f"cs451.stages.{stage}.")}
        assert own & shown.get(stage, set()), f"stage {stage}: no deck slides/NN-{stage}.md showing a figure of its own"


def test02_the_decks_typeset_the_notes_equations_and_cite_them():
    text = {f.stem.split("-", 1)[1]: f.read_text() for f in deck_files(KIT_ROOT)}
    tags = {int(t) for deck in ("hemicube", "radiosity") for t in re.findall(r"\\tag\{(\d+)\}", text[deck])}
    assert tags == set(range(1, 13)), sorted(tags)                       # radiosity eq. 1-12, the deltas 7-9
    assert "\\Delta\\mathrm{Rad} = \\rho_j\\, \\Delta B_i\\, F_{ij}" in text["radiosity"]   # the shooting update
    for deck, body in text.items():
        assert re.search(r"notes §\d", body), f"{deck} cites the notes by section"
        assert body.count("Note:") >= body.count("\n---\n") - 1, f"{deck}: speaker notes on (nearly) every slide"
    pseudo = {deck: body.count("```pseudo") for deck, body in text.items()}
    assert pseudo["whitted"] >= 2 and pseudo["hemicube"] >= 2 and pseudo["radiosity"] >= 3, pseudo


def test03_vendored_files_are_inlined_and_named_with_their_versions():
    got = versions()
    assert got == {"reveal.js": "6.0.2", "katex": "0.19.1"}
    readme = (KIT_ROOT / "cs451" / "slides" / "vendor" / "README.md").read_text()
    assert "reveal.js 6.0.2" in readme and "KaTeX 0.19.1" in readme
    for license_file in ("reveal.js/LICENSE", "katex/LICENSE", "reveal.js/theme/LICENSE-source-sans-pro"):
        assert (KIT_ROOT / "cs451" / "slides" / "vendor" / license_file).is_file(), license_file
    css = assets()["katex_css"]
    assert css.count("data:font/woff2;base64,") == 20 and "fonts/" not in css


def test04_the_wheel_and_the_package_data_hold_the_vendored_files_and_templates():
    import tomllib
    globs = tomllib.loads((KIT_ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]["cs451"]
    engine = KIT_ROOT / "cs451"
    needed = [p.relative_to(engine) for sub in ("slides/vendor", "slides/templates") for p in (engine / sub).rglob("*")
              if p.is_file()]
    matched = {p.relative_to(engine) for g in globs for p in engine.glob(g) if p.is_file()}
    assert set(needed) <= matched, sorted(set(needed) - matched)
    setup = (KIT_ROOT / "setup.py").read_text()
    assert re.search(r'KIT_PARTS = \([^)]*"slides"', setup), "an installed kit carries the decks"


@pytest.mark.spawns
def test05_a_release_for_students_has_no_slides(tmp_path, monkeypatch):
    from cs451.packaging import release
    monkeypatch.setattr(release, "export_answers", lambda *a, **k: None)   # what is copied, not the answers
    out = release.build_release("sphere", tmp_path / "repo")
    assert not (out / "slides").exists() and not (out / "cs451" / "slides").exists()
    assert not [p for p in out.rglob("*") if "reveal" in p.name.lower() or p.suffix == ".j2" and "deck" in p.name]
    assert (out / "cs451" / "cli.py").is_file()
    done = subprocess.run([sys.executable, "-m", "cs451", "--help"], cwd=out, capture_output=True, text=True,
                          env={**os.environ, "PYTHONPATH": str(out)}, timeout=120)
    assert done.returncode == 0 and "slides" not in done.stdout, done.stdout + done.stderr


def test06_listings_are_read_from_the_reference_when_the_deck_is_built(tmp_path, monkeypatch):
    install_stub(monkeypatch)
    kit = kit_copy(tmp_path)
    shooting = kit / "reference" / "radiosity" / "shooting.py"
    text = shooting.read_text()
    assert "    received *= reflectance\n" in text
    shooting.write_text(text.replace("    received *= reflectance\n", "    received *= reflectance   # changed\n"))
    page = build_slides(output=tmp_path / "out", deck="radiosity", cache=tmp_path / "cache", kit_root=kit)[0].path
    assert "# changed" in page.read_text()
    assert "# changed" not in (KIT_ROOT / "reference" / "radiosity" / "shooting.py").read_text()

    # a line the pseudo-code points at is gone: the build names the slide's line, it never shows stale code
    shooting.write_text(text.replace("received *= reflectance", "received = received * reflectance"))
    with pytest.raises(KitError, match=r"^slides/04-radiosity\.md:\d+: \[\[received \*= reflectance\]\] is in no "
                                       r"line of the reference this slide shows"):
        build_slides(output=tmp_path / "out2", deck="radiosity", cache=tmp_path / "cache", kit_root=kit)
    shooting.write_text(text.replace("def shoot(", "def shoot_one("))
    with pytest.raises(KitError, match=r"^slides/04-radiosity\.md:\d+: reference/radiosity/shooting\.py has no "
                                       r"function 'shoot'"):
        build_slides(output=tmp_path / "out3", deck="radiosity", cache=tmp_path / "cache", kit_root=kit)


def test07_a_changed_reference_function_changes_its_figure_in_the_deck(tmp_path, monkeypatch):
    kit = kit_copy(tmp_path)
    stub = install_stub(monkeypatch, root=kit)
    first = build_slides(output=tmp_path / "a", deck="hemicube", cache=tmp_path / "cache", kit_root=kit)[0].path
    assert "hemicube-delta-weights" in stub.drawn
    stub.drawn.clear()
    again = build_slides(output=tmp_path / "b", deck="hemicube", cache=tmp_path / "cache", kit_root=kit)[0].path
    assert stub.drawn == [] and again.read_text() == first.read_text()     # a warm cache draws nothing
    tables = kit / "reference" / "hemicube" / "tables.py"
    tables.write_text(tables.read_text().replace("h = 2.0 / r", "h = 2.0 / r * 1.0"))
    changed = build_slides(output=tmp_path / "c", deck="hemicube", cache=tmp_path / "cache", kit_root=kit)[0].path
    assert stub.drawn == ["hemicube-delta-weights"]

    def figure_urls(page: Path) -> dict[str, str]:
        return dict(re.findall(r'data-figure="figure:([\w-]+)"><img src="(data:[^"]+)"', page.read_text()))
    before, after = figure_urls(first), figure_urls(changed)
    assert before["hemicube-delta-weights"] != after["hemicube-delta-weights"]
    assert {k: v for k, v in before.items() if k != "hemicube-delta-weights"} == \
           {k: v for k, v in after.items() if k != "hemicube-delta-weights"}


BAD_DECKS = [
    ("# T\n\n![x](figure:no-such-figure)\n", r"01-bad\.md:3: unknown figure 'no-such-figure'"),
    ("# T\n\n```reference\nreference/radiosity/shooting.py::nope\n```\n", r"01-bad\.md:4: .*has no function 'nope'"),
    ("# T\n\n```reference\nreference/radiosity/shooting.py::shoot\nfrom: nowhere at all\n```\n",
     r"01-bad\.md:4: from: 'nowhere at all' is in no line"),
    ("# T\n\n```reference\nreference/radiosity/shooting.py::shoot\nstart: x\n```\n",
     r"01-bad\.md:5: 'start: x': a reference block takes"),
    ("# T\n\n```reference\ncs451/cli.py::main\n```\n",
     r"01-bad\.md:4: cs451/cli\.py: a listing shows a file of reference/"),
    ("# T\n\nsome $x + 1 math\n", r"01-bad\.md:3: a \$ opens math that no \$ closes"),
    ("# T\n\n```python\nx = 1\n", r"01-bad\.md:3: a ``` block that no ``` closes"),
    ("# T\n\n```pseudo\nshoot [[not in any listing]]\n```\n",
     r"01-bad\.md:4: \[\[not in any listing\]\] is in no line"),
    ("# T\n\n![x](https://example.org/x.png)\n", r"01-bad\.md:3: https://example.org/x\.png: .*never a remote image"),
    ("# T\n\n| a | b |\n|---|---|\n| 1 |\n", r"01-bad\.md:5: this row has 1 cells, the table 2"),
    ("# T\n\n$$\nx\n", r"01-bad\.md:3: a \$\$ block that no \$\$ closes"),
    ("## not a title\n", r"01-bad\.md:1: a deck's first slide starts with its title"),
    ("# T\n\n---\n\n---\n\nx\n", r"01-bad\.md:\d: an empty slide"),
    ("# T\n\n![x](figure:hemicube-row){size=3}\n", r"01-bad\.md:3: \{size=3\}: a figure takes"),
]


@pytest.mark.parametrize("text,message", BAD_DECKS, ids=[m.split(": ", 1)[1][:40] for _, m in BAD_DECKS])
def test08_a_bad_deck_fails_with_one_line_naming_its_file_and_line(tmp_path, monkeypatch, text, message):
    install_stub(monkeypatch)
    kit = tmp_path / "kit"
    (kit / "slides").mkdir(parents=True)
    shutil.copytree(KIT_ROOT / "reference", kit / "reference", ignore=shutil.ignore_patterns("__pycache__"))
    (kit / "slides" / "01-bad.md").write_text(text)
    with pytest.raises(KitError) as err:
        build_slides(output=tmp_path / "out", cache=tmp_path / "cache", kit_root=kit)
    assert re.search(message, str(err.value)) and "\n" not in str(err.value), str(err.value)
    assert str(err.value).startswith("slides/01-bad.md:")


def test08b_the_example_deck_of_the_slides_readme_builds(tmp_path, monkeypatch):
    install_stub(monkeypatch)
    example = re.search(r"````markdown\n(.*?)````", (KIT_ROOT / "slides" / "README.md").read_text(), re.S).group(1)
    kit = tmp_path / "kit"
    (kit / "slides").mkdir(parents=True)
    shutil.copytree(KIT_ROOT / "reference", kit / "reference", ignore=shutil.ignore_patterns("__pycache__"))
    (kit / "slides" / "01-example.md").write_text(example)
    built = build_slides(output=tmp_path / "out", cache=tmp_path / "cache", kit_root=kit)
    assert [b.slides for b in built] == [2] and 'class="pointer">1<' in built[0].path.read_text()


def test09_the_command_builds_a_deck_and_refuses_bad_input_in_one_line(tmp_path, monkeypatch, capsys):
    install_stub(monkeypatch)
    assert main(["slides", "build", "sphere", "-o", str(tmp_path / "out"), "--cache", str(tmp_path / "c")]) == 0
    said = capsys.readouterr()
    assert (tmp_path / "out" / "sphere.html").is_file() and "wrote" in said.out and "sphere.html" in said.out
    assert main(["slides", "build", "nosuch", "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "deck 'nosuch': no such deck; the decks are overview, sphere" in err
    (tmp_path / "file").write_text("")
    assert main(["slides", "build", "-o", str(tmp_path / "file")]) == 2
    assert "is a file, not a folder" in capsys.readouterr().err


# --- the real figures module's side of the contract ------------------------------------------------------

def _real_figures():
    from cs451.slides import figures
    return figures


def test10_the_figures_module_knows_every_figure_the_decks_show():
    figures = _real_figures()
    assert set(FIGURE_NAMES) <= set(figures.FIGURES), sorted(set(FIGURE_NAMES) - set(figures.FIGURES))
    assert all(isinstance(v, str) and v and "\n" not in v for v in figures.FIGURES.values())


def test11_a_changed_reference_function_changes_a_real_figures_cache_key(tmp_path, monkeypatch):
    from cs451.slides import registry
    figures = _real_figures()
    reference = tmp_path / "reference"
    shutil.copytree(KIT_ROOT / "reference", reference, ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr(registry, "REFERENCE", reference)
    before = {name: figures.figure_key(name) for name in ("hemicube-delta-weights", "sphere-gouraud-vs-phong")}
    tables = reference / "hemicube" / "tables.py"
    tables.write_text(tables.read_text().replace("h = 2.0 / r", "h = 2.0 / r * 1.0"))
    after = {name: figures.figure_key(name) for name in before}
    assert after["hemicube-delta-weights"] != before["hemicube-delta-weights"]
    assert after["sphere-gouraud-vs-phong"] == before["sphere-gouraud-vs-phong"]


# --- a browser, offline -----------------------------------------------------------------------------------

#: What the walk reads of the slide on screen (reveal.js's own state and the DOM).
SLIDE_STATE = """(() => {
  const s = Reveal.getCurrentSlide(), box = s.getBoundingClientRect();
  const scale = Reveal.getScale(), cfg = Reveal.getConfig();
  const inner = [...s.children].filter(e => !e.matches('aside.notes'));
  const bottom = Math.max(...inner.map(e => e.getBoundingClientRect().bottom));
  const shown = [...s.querySelectorAll('*')]
                 .filter(e => !e.closest('aside.notes, .katex-mathml') && !(e.ownerSVGElement))
                 .map(e => e.getBoundingClientRect()).filter(r => r.width > 0 && r.height > 0);
  const right = Math.max(box.left, ...shown.map(r => r.right));
  const spill = [...s.querySelectorAll('.column')].map(c => {
    const edge = c.getBoundingClientRect().right;
    const inside = [...c.querySelectorAll('*')].filter(e => !e.closest('.katex-mathml') && !e.ownerSVGElement)
                   .map(e => e.getBoundingClientRect()).filter(r => r.width > 0 && r.height > 0);
    return Math.max(0, ...inside.map(r => r.right - edge)) / scale; });
  return {index: Reveal.getIndices().h, source: s.dataset.source, present: s.classList.contains('present'),
          visible: box.width > 0 && box.height > 0 && getComputedStyle(s).display !== 'none',
          overflowY: (bottom - box.top) / scale - cfg.height, overflowX: (right - box.left) / scale - cfg.width,
          columnOverflow: Math.max(0, ...spill),
          text: s.innerText.trim().length,
          images: [...s.querySelectorAll('img')].map(i => ({figure: i.closest('figure').dataset.figure,
                    loaded: i.complete && i.naturalWidth > 0, rect: [i.getBoundingClientRect().x,
                    i.getBoundingClientRect().y, i.getBoundingClientRect().width, i.getBoundingClientRect().height],
                    natural: [i.naturalWidth, i.naturalHeight]})),
          math: s.querySelectorAll('.math').length,
          typeset: s.querySelectorAll('.math > .katex, .math > .katex-display').length,
          mathErrors: s.querySelectorAll('.math-error').length,
          notes: s.querySelectorAll('aside.notes').length};
})()"""


@pytest.fixture(scope="module")
def browser():
    if CHROMIUM is None:
        pytest.skip("no Chromium here (apt-get install chromium; .ci/run installs it)")
    chromium = Chromium()
    yield chromium
    chromium.close()


def walk(page: Page, url: str) -> list[dict]:
    """Open a deck and step through every slide with the keyboard (→), reading each slide's state."""
    page.open(url)
    total = page.eval("Reveal.getTotalSlides()")
    states = []
    for k in range(total):
        state = page.eval(SLIDE_STATE)
        assert state["index"] == k, (url, state)
        states.append(state)
        if k + 1 < total:
            page.key("ArrowRight", 39)
            page.eval(f"new Promise(done => {{ (function wait() {{ Reveal.getIndices().h === {k + 1} ? done(true)"
                      f" : setTimeout(wait, 10); }})(); }})")
    return states


def check_deck(browser: Chromium, name: str, path: Path) -> None:
    """Every slide of a built deck, stepped through with the keyboard: shown, within the slide and its columns,
    images loaded, math typeset, notes where the deck has them; nothing fetched, nothing logged as an error."""
    page = browser.page()
    states = walk(page, path.as_uri())
    deck = read_deck(deck_files(KIT_ROOT)[DECKS.index(name)], KIT_ROOT)
    assert len(states) == len(deck.slides), name
    for state, slide in zip(states, deck.slides):
        where = state["source"]
        assert where == f"{deck.file}:{slide.line}"
        assert state["present"] and state["visible"] and state["text"] > 0, where
        assert state["overflowY"] <= 1 and state["overflowX"] <= 1, (where, state["overflowY"], state["overflowX"])
        assert state["columnOverflow"] <= 1, (where, "something is wider than its column", state["columnOverflow"])
        assert all(i["loaded"] for i in state["images"]), (where, state["images"])
        assert state["typeset"] == state["math"] and state["mathErrors"] == 0, (where, state)
        assert state["notes"] == (1 if slide.notes else 0), where
    assert sum(s["math"] for s in states) > 0 or name == "overview"
    assert page.eval("Reveal.hasPlugin('notes') && Reveal.isReady()")
    page.key("ArrowLeft", 37)                                        # and back, with the keyboard
    assert page.eval("new Promise(done => setTimeout(() => done(Reveal.getIndices().h), 100))") == len(states) - 2
    assert page.problems() == [], (name, page.problems())
    page.call("Page.close")


@pytest.mark.spawns
@needs_chromium
def test13_every_deck_opens_offline_and_every_slide_renders(built, browser):
    for name, path in built.items():
        check_deck(browser, name, path)


def show_slide(page: Page, selector: str) -> dict:
    """Go to the slide holding ``selector`` (a figure, a heading) and read it once it is drawn."""
    slide = page.eval(f"""(() => {{ const f = document.querySelector({json.dumps(selector)});
      return [...document.querySelectorAll('.slides > section')].indexOf(f.closest('section')); }})()""")
    assert slide >= 0, selector
    page.eval(f"Reveal.slide({slide}, 0)")
    page.eval("new Promise(done => requestAnimationFrame(() => requestAnimationFrame(() => done(true))))")
    return page.eval(SLIDE_STATE)


def figure_on_screen(page: Page, figure: str, png: Path, other: Path) -> Image.Image:
    """Show the slide of ``figure`` and check that the screenshot's pixels where it is shown are its PNG's,
    scaled to the shown size, and not those of ``other``; returns the screenshot."""
    state = show_slide(page, f'figure[data-figure="figure:{figure}"]')
    image = next(i for i in state["images"] if i["figure"] == f"figure:{figure}")
    shot = page.screenshot()
    x, y, w, h = (round(v) for v in image["rect"])
    assert w > 100 and h > 60, image
    # as the kit's image tests judge a render: each pixel against the figure's 3 × 3 neighbourhood, since the
    # figure's box lies on fractional pixels (every sharp edge moves by a part of one) and the browser's
    # resampling is not Pillow's; 3 pixels in from the box's edges
    inset = 3
    shown = np.asarray(shot.crop((x + inset, y + inset, x + w - inset, y + h - inset)), dtype=np.float64)

    def off(path: Path) -> np.ndarray:
        picture = np.asarray(Image.open(path).convert("RGB").resize((w, h), Image.LANCZOS), dtype=np.float64)
        best = np.full(shown.shape, np.inf)
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                moved = picture[inset + dy:h - inset + dy, inset + dx:w - inset + dx]
                best = np.minimum(best, np.abs(shown - moved))
        return best.max(axis=2)
    diff = off(png)
    assert diff.mean() < 3.0 and (diff > 64).mean() < 0.02, (figure, diff.mean(), (diff > 64).mean())
    assert off(other).mean() > 4 * max(diff.mean(), 1.0), f"{figure} looks like {other.name}"
    return shot


@needs_chromium
def test14_a_slide_shows_the_figure_it_names(built, browser):
    """The screenshot's pixels where a figure is shown match the figure's PNG, scaled to the shown size."""
    cache = built["sphere"].parent.parent / "cache"
    for deck, figure in (("whitted", "whitted-ray-tree"), ("hemicube", "hemicube-delta-weights"),
                         ("radiosity", "radiosity-progress"), ("sphere", "sphere-modelview")):
        page = browser.page()
        page.open(built[deck].as_uri())
        figure_on_screen(page, figure, next(cache.glob(f"{figure}-*.png")), next(cache.glob("bench-radiosity-*.png")))
        assert page.problems() == []
        page.call("Page.close")


@needs_chromium
def test15_the_print_layout_gives_one_page_per_slide(built, browser):
    page = browser.page()
    page.open(built["radiosity"].as_uri() + "?print-pdf")
    assert page.eval("new Promise(done => { (function wait() { window.cs451Deck.printReady ? done(true)"
                     " : setTimeout(wait, 20); })(); })")
    assert page.eval("document.documentElement.classList.contains('print-pdf')")
    pdf = base64.b64decode(page.call("Page.printToPDF", {"preferCSSPageSize": True, "printBackground": True},
                                     timeout=120)["data"])
    pages = len(re.findall(rb"/Type\s*/Page[^s]", pdf))
    assert pages == len(read_deck(deck_files(KIT_ROOT)[DECKS.index("radiosity")], KIT_ROOT).slides), pages
    assert page.problems() == []
    page.call("Page.close")


@needs_chromium
def test16_the_speaker_view_opens_offline_with_the_slide_notes(built, browser):
    browser.call("Target.setDiscoverTargets", {"discover": True})
    page = browser.page()
    page.open(built["hemicube"].as_uri())
    since = len(browser.events)
    page.call("Runtime.evaluate", {"expression": "Reveal.getPlugin('notes').open()", "userGesture": True})
    created = browser.wait_for("Target.targetCreated", since)
    while created["params"]["targetInfo"]["type"] != "page":
        since = browser.events.index(created) + 1
        created = browser.wait_for("Target.targetCreated", since)
    target = created["params"]["targetInfo"]["targetId"]
    notes = Page(browser, browser.call("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"])
    text = notes.eval("""new Promise((done, fail) => { const t0 = Date.now(); (function wait() {
        const n = document.querySelector('.speaker-controls-notes .value');
        if (n && n.textContent.trim()) done(n.textContent.trim());
        else if (Date.now() - t0 > 30000) fail(new Error('the speaker view shows no notes'));
        else setTimeout(wait, 50); })(); })""")
    assert "Cohen and Greenberg" in text                                  # the title slide's notes
    assert notes.eval("document.querySelectorAll('#current-slide iframe, #upcoming-slide iframe').length") == 2
    assert notes.eval("getComputedStyle(document.querySelector('#connection-status')).display") == "none"
    assert page.problems() == [] and notes.problems() == [], (page.problems(), notes.problems())


@needs_chromium
def test17_the_page_itself_refuses_to_fetch_anything(built, browser):
    """Beyond what the build writes: the page's Content-Security-Policy blocks a fetch even if a deck tried one."""
    page = browser.page()
    page.open(built["overview"].as_uri())
    blocked = page.eval("""new Promise(done => {
        document.addEventListener('securitypolicyviolation', e => done(e.blockedURI + ' ' + e.effectiveDirective));
        const img = document.createElement('img'); img.src = 'https://cdn.example.org/katex.min.css';
        document.body.appendChild(img); })""")
    assert blocked == "https://cdn.example.org/katex.min.css img-src", blocked
    asked = [e["params"]["requestId"] for e in browser.events[page.start:] if e["method"] == "Network.requestWillBeSent"
             and e["params"]["request"]["url"].startswith("https://")]
    page.eval("1")                      # one round trip more: the events sent before it have arrived
    failed = [e["params"] for e in browser.events[page.start:] if e["method"] == "Network.loadingFailed"]
    assert asked and all(any(f["requestId"] == r and f.get("blockedReason") == "csp" for f in failed) for r in asked)
    page.call("Page.close")


#: Slides shown in the README's screenshots: (deck, a figure shown, or a heading's text).
SCREENSHOTS = (("overview", "h2", "Five stages, one road"), ("overview", "figure", "radiosity-progress"),
               ("sphere", "figure", "sphere-modelview"), ("sphere", "figure", "sphere-gouraud-vs-phong"),
               ("whitted", "h2", "The notes' algorithm: one pixel"), ("whitted", "figure", "whitted-ray-tree"),
               ("hemicube", "h2", "H1 in the reference"), ("hemicube", "figure", "hemicube-row"),
               ("radiosity", "h2", "R3: the shooting loop, as the notes write it"),
               ("radiosity", "figure", "radiosity-progress"), ("radiosity", "figure", "bench-radiosity"))


@pytest.mark.spawns
@pytest.mark.slow
@needs_chromium
def test18_the_decks_with_the_real_figures_open_offline_and_show_them(tmp_path, browser):
    """From the repository as it is, through the command, with the figures the reference draws: every deck
    passes the browser checks, and the figures on screen are the PNGs the figures module made.

    ``CS451_SLIDE_SCREENSHOTS=docs/screenshots`` also writes the README's screenshots (SCREENSHOTS) there."""
    _real_figures()
    out = tmp_path / "out"
    cache = Path(os.environ.get("CS451_SLIDES_CACHE") or tmp_path / "cache")
    done = subprocess.run([sys.executable, "-m", "cs451", "slides", "build", "-o", str(out), "--cache", str(cache)],
                          cwd=KIT_ROOT, capture_output=True, text=True, timeout=1800)
    assert done.returncode == 0, done.stderr[-3000:]
    assert sorted(p.stem for p in out.glob("*.html")) == sorted(DECKS)
    from cs451.slides.readability import measure_deck
    for name in DECKS:
        check_deck(browser, name, out / f"{name}.html")
        # the back-row floors with the real figures: their text and their pixels as the decks show them
        problems = [p for m in measure_deck(browser, out / f"{name}.html") for p in m.problems]
        assert not problems, "\n".join(problems[:20])
    keep = Path(os.environ["CS451_SLIDE_SCREENSHOTS"]) if os.environ.get("CS451_SLIDE_SCREENSHOTS") else None
    other = next(cache.glob("bench-radiosity-*.png"))
    for deck, kind, what in SCREENSHOTS:
        page = browser.page()
        page.viewport(1920, 1080)                       # as a 1080p projector shows it
        page.open((out / f"{deck}.html").as_uri())
        if kind == "figure":
            shot = figure_on_screen(page, what, next(cache.glob(f"{what}-[0-9a-f]*.png")),
                                    other if what != "bench-radiosity" else next(cache.glob("hemicube-row-*.png")))
        else:
            heading = page.eval(f"""(() => {{ const h = [...document.querySelectorAll('.slides h2')]
                .find(h => h.textContent.startsWith({json.dumps(what)})); if (h) h.id = 'shot'; return !!h; }})()""")
            assert heading, (deck, what)
            show_slide(page, "#shot")
            shot = page.screenshot()
        if keep:
            keep.mkdir(parents=True, exist_ok=True)
            slug = re.sub(r"[^a-z0-9]+", "-", what.lower()).strip("-")
            shot.quantize(256, method=Image.Quantize.MEDIANCUT).save(keep / f"slides-{deck}-{slug}.png", optimize=True)
        assert page.problems() == []
        page.call("Page.close")


def test_the_slides_code_is_in_no_sandbox_and_no_answers_version():
    """Lecturer-only code: a grading sandbox's engine copy leaves it out, and editing it keeps every cached answer."""
    import os
    from cs451 import ENGINE_DIR
    from cs451.grading.expected import tree_hash
    from cs451.grading.sandbox import _sandbox_litter
    assert "slides" in _sandbox_litter(str(ENGINE_DIR), os.listdir(ENGINE_DIR))
    assert "slides" not in _sandbox_litter(str(ENGINE_DIR / "stages"), ["slides"])   # only the engine's own folder
    before = tree_hash(ENGINE_DIR)
    probe = ENGINE_DIR / "slides" / "_test_probe_edit.py"
    try:
        probe.write_text("X = 1\n")
        assert tree_hash(ENGINE_DIR) == before
    finally:
        probe.unlink()
    other = ENGINE_DIR / "_test_probe_edit.py"
    try:
        other.write_text("X = 1\n")
        assert tree_hash(ENGINE_DIR) != before                # the rest of the engine still counts
    finally:
        other.unlink()
