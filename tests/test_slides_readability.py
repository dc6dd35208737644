"""Decks a lecturer can teach a whole course from (issue 37): lecture length, speaker notes that say what to say,
every task on a slide, and text the back row can read, measured on the rendered page in headless Chromium.

The readability floors are :data:`cs451.slides.readability.FLOORS` (text 24 px, code 20 px and never wrapped,
figure text 16 px, figures at 2 pixels per slide pixel, nothing under the navigation controls), at 1920×1080 and
1280×720. The fast tests build the decks with the stub figures of ``test_slides.py`` (the layout, text and code
are the decks' own); ``test_slides.py``'s slow test 18 measures them again with the figures the reference draws.
"""
from __future__ import annotations

import re

import numpy as np
import pytest

from cs451 import KIT_ROOT
from cs451.cli import main
from cs451.slides.build import build_slides
from cs451.slides.chromium import Chromium
from cs451.slides.deck import deck_files, read_deck
from cs451.slides.readability import FLOORS, SCREENS, Measured, judge, measure_deck
from cs451.stages import get_stage, stage_names
from test_slides import install_stub, needs_chromium

STAGE_DECKS = {f.stem.split("-", 1)[1]: f for f in deck_files(KIT_ROOT) if f.stem.split("-", 1)[1] in stage_names()}


def slide_texts(path):
    """Each slide's visible text and its speaker notes, as the deck's source writes them."""
    text = path.read_text()
    chunks, fenced, current = [], False, []
    for line in text.splitlines():
        if line.startswith("```"):
            fenced = not fenced
        if line.rstrip() == "---" and not fenced:
            chunks.append("\n".join(current))
            current = []
        else:
            current.append(line)
    chunks.append("\n".join(current))
    out = []
    for chunk in chunks:
        shown, _, notes = chunk.partition("\nNote:")
        if chunk.startswith("Note:"):
            shown, notes = "", chunk[len("Note:"):]
        out.append((shown, notes))
    return out


def test01_every_stage_deck_is_a_lecture_long():
    assert set(STAGE_DECKS) == set(stage_names())
    counts = {name: len(read_deck(path, KIT_ROOT).slides) for name, path in STAGE_DECKS.items()}
    assert all(25 <= n <= 35 for n in counts.values()), counts


@pytest.mark.parametrize("path", deck_files(KIT_ROOT), ids=lambda p: p.stem)
def test02_every_slide_has_speaker_notes_of_80_to_150_words(path):
    words = [len(re.findall(r"\S+", notes)) for _, notes in slide_texts(path)]
    short = [(k + 1, n) for k, n in enumerate(words) if not 80 <= n <= 150]
    assert not short, f"{path.name}: (slide, words of notes) outside 80–150: {short}"
    assert len(words) == len(read_deck(path, KIT_ROOT).slides)


@pytest.mark.parametrize("stage", sorted(STAGE_DECKS))
def test03_every_task_of_the_stage_is_named_on_a_slide(stage):
    shown = "\n".join(s for s, _ in slide_texts(STAGE_DECKS[stage]))
    missing = [t.id for t in get_stage(stage).tasks if not re.search(rf"\b{t.id}\b", shown)]
    assert not missing, f"{stage}: tasks named on no slide: {missing}"


def test04_the_topics_a_reviewer_found_missing_have_slides():
    shown = {name: "\n".join(s for s, _ in slide_texts(path)).lower() for name, path in STAGE_DECKS.items()}
    assert "normal matrix" in shown["sphere"]
    assert "offset" in shown["whitted"] or "epsilon" in shown["whitted"] or "ε" in shown["whitted"]
    assert "frust" in shown["hemicube"]
    assert "w/m" in shown["radiosity"].replace("\\,", "").replace(" ", "").replace("\\mathrm{", "").replace("}", "") \
        or "watt" in shown["radiosity"]


def test05_the_corrected_facts_stay_corrected():
    """The reviewer's factual errors (issue 37), each checked against the notes: a Gauss-Seidel sweep over a full
    matrix is O(N²), not O(N); a first sweep from B = E gathers all the direct light."""
    text = {name: path.read_text() for name, path in STAGE_DECKS.items()}
    for name, body in text.items():
        assert not re.search(r"Gauss[- ]Seidel[^.\n]{0,80}O\(N\)", body), name
        assert "gather almost nothing" not in body, name


# --- the floors, judged ------------------------------------------------------------------------------------------

def state(runs=(), wrapped=(), images=(), chrome=((1225, 690, 1272, 712),)):
    return {"source": "slides/x.md:3", "scale": 0.96, "runs": list(runs), "wrapped": list(wrapped),
            "images": list(images), "chrome": [list(c) for c in chrome]}


def run(px, code=False, rect=(10, 10, 200, 40)):
    return {"text": "some text", "code": code, "math": False, "px": px, "rects": [list(rect)]}


def image(natural=640, slide_px=320, shown=307.2, text_px=40.0, rect=(10, 100, 317, 300)):
    return {"figure": "figure:x", "natural": [natural, natural // 2], "shown": [shown, shown / 2],
            "slidePx": slide_px, "textPx": text_px, "rect": list(rect)}


@pytest.mark.parametrize("measured,breach", [
    (state([run(23.9)]), "text at 23.9 px, under 24"),
    (state([run(19.9, code=True)]), "code at 19.9 px, under 20"),
    (state(wrapped=["x = 1"]), "wraps or is cut off"),
    (state(images=[image(natural=600)]), "600 pixels shown 320 slide pixels wide"),
    (state(images=[image(text_px=30.0)]), "smallest text shows at 14.4 px, under 16"),
    (state(images=[image(text_px=None)]), "does not say how small its text is"),
    (state([run(30, rect=(1200, 680, 1250, 700))]), "text under the navigation controls"),
    (state(images=[image(rect=(900, 500, 1240, 700))]), "lies under the navigation controls"),
    (state(images=[{**image(), "shown": [307.2, 100.0]}]), "squashed from its 640×320 pixels"),
    ({**state(), "overflow": [0, 6.9]}, "overflows its 1280×720 box by 0 px on the right and 7 px at the bottom"),
])
def test06_each_floor_is_judged_on_what_the_page_measured(measured, breach):
    out = Measured((1280, 720))
    judge(measured, (1280, 720), FLOORS, out)
    assert len(out.problems) == 1 and breach in out.problems[0], out.problems
    assert out.problems[0].startswith("slides/x.md:3 (1280×720): ")
    fine = Measured((1280, 720))
    judge(state([run(24.0), run(20.0, code=True)], images=[image()]), (1280, 720), FLOORS, fine)
    assert fine.problems == [] and fine.body_px == 24.0 and fine.code_px == 20.0 and fine.figure_density == 2.0


# --- the floors, measured in a browser ------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def stub_decks(tmp_path_factory):
    out = tmp_path_factory.mktemp("readable")
    with pytest.MonkeyPatch.context() as patch:
        install_stub(patch)
        built = build_slides(output=out / "html", cache=out / "cache")
    return {b.deck: b.path for b in built}


@pytest.fixture(scope="module")
def chromium():
    with Chromium() as browser:
        yield browser


@pytest.mark.spawns
@needs_chromium
def test07_every_deck_meets_the_floors_at_1080p_and_720p(stub_decks, chromium):
    report = {}
    for name, path in stub_decks.items():
        results = measure_deck(chromium, path)
        assert [m.screen for m in results] == list(SCREENS)
        problems = [p for m in results for p in m.problems]
        assert not problems, "\n".join(problems[:20])
        report[name] = {m.screen: (m.body_px, m.code_px) for m in results}
    for name, sizes in report.items():
        body, code = sizes[(1280, 720)]
        assert body >= FLOORS.body_px - 0.05 and code >= FLOORS.code_px - 0.05, (name, sizes)
        assert sizes[(1920, 1080)][0] == pytest.approx(1.5 * body, rel=0.02), "1080p shows the same slide 1.5× larger"


BAD_DECK = """# A deck that breaks the floors

Note: {notes}

---

## A code block too wide for any screen

```python
value = some_function(argument_one, argument_two, argument_three, argument_four, argument_five, argument_six_is_long)
```

Note: {notes}

---

## A slide filled to its bottom-right corner

{items}
- the last, a line that runs across the whole width of the slide and into the corner where the arrows are drawn

Note: {notes}
"""


@needs_chromium
def test08_a_deck_that_breaks_the_floors_is_caught_on_the_page(tmp_path, monkeypatch, chromium):
    install_stub(monkeypatch)
    kit = tmp_path / "kit"
    (kit / "slides").mkdir(parents=True)
    (kit / "reference").mkdir()
    (kit / "slides" / "01-bad.md").write_text(BAD_DECK.format(notes="words " * 90,
                                                              items="\n".join(f"- item {k} of a list whose lines run across the whole slide, corner to corner, "
                                                                        "and down under the arrows" for k in range(16))))
    built = build_slides(output=tmp_path / "out", kit_root=kit, cache=tmp_path / "cache")
    results = measure_deck(chromium, built[0].path)
    for m in results:
        assert any("01-bad.md:7" in p and "wraps or is cut off" in p for p in m.problems), m.problems
    # the arrows keep their screen size, so on a 720p screen they cover more of the slide's corner than at 1080p
    small = next(m for m in results if m.screen == (1280, 720))
    assert any("01-bad.md:17 (1280×720)" in p and "under the navigation controls" in p for p in small.problems)


@pytest.mark.spawns
@needs_chromium
def test09_slides_pdf_writes_a_real_pdf_with_a_page_per_slide_and_nothing_blank(tmp_path, monkeypatch, capsys):
    pdfium = pytest.importorskip("pypdfium2", reason="the dev extra installs pypdfium2 to read the PDF back")
    install_stub(monkeypatch)
    pdf = tmp_path / "radiosity.pdf"
    assert main(["slides", "pdf", "radiosity", "-o", str(pdf), "--cache", str(tmp_path / "cache")]) == 0
    assert f"wrote {pdf}" in capsys.readouterr().out
    document = pdfium.PdfDocument(str(pdf))
    slides = len(read_deck(STAGE_DECKS["radiosity"], KIT_ROOT).slides)
    assert len(document) == slides
    for index in (0, 1, slides // 2, slides - 1):
        pixels = np.asarray(document[index].render(scale=1).to_pil().convert("L"), dtype=np.float64)
        inked = (pixels < 128).mean()
        assert 0.002 < inked < 0.6 and pixels.std() > 10, (index, inked, pixels.std())   # text on it, not blank
    first = document[0]
    width, height = first.get_size()
    assert width / height == pytest.approx(16 / 9, rel=0.02)
    text = first.get_textpage().get_text_range()
    assert "radiosity" in text.lower(), text[:200]
    document.close()
    assert main(["slides", "pdf", "-o", str(tmp_path / "one.pdf"), "--cache", str(tmp_path / "cache")]) == 2
    assert "names one PDF, but 6 decks" in capsys.readouterr().err
