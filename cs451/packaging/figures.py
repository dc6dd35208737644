"""The handouts' target images: the reference's render for every public image test, as the test shows it.

``cs451 figures`` writes them beside each handout (``assignments/<handout>/figures/<test>.png``) and
the handout's block between ``<!-- figures -->`` and ``<!-- /figures -->`` that shows them; ``--check``
says where the committed figures have drifted from the reference (compared with the image tests'
own tolerance, so another Mesa or a GPU does not count as drift), as ``cs451 starter --check`` does.
A student's release ships the figures with its handout.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import KIT_ROOT
from ..compare import ImageTolerance, compare_images
from ..errors import KitError
from ..grading.checks import target_images
from ..grading.expected import ReferenceAnswers, TruthValues, expected_for
from ..grading.loader import load_tests
from ..grading.spec import Test
from ..imageio import load_png, save_png
from ..progress import Progress
from ..stages import get_stage

BLOCK = re.compile(r"(<!-- figures -->\n)(.*?)(<!-- /figures -->)", re.S)
INTRO = ("What the reference draws for each public image test (rendered from the reference solution by the kit; "
         "your render should match it within the test's tolerance). To see yours beside one, judged as the test "
         "judges it, draw the figure with your package and give both PNGs to the compare command (here {number}; "
         "for another figure, put its number in both places):\n\n"
         "```sh\n{recipe}\n```\n\n"
         "`--figure` draws the figure's own test as the grader does: the test's scene, size and settings, and the "
         "reference's answers to the earlier tasks the test gives your function. "
         "The compare command exits with 1 when the two differ by more than the test allows, and writes them "
         "side by side with the error maps.\n\n")


def recipe(number: str, handout: str) -> str:
    """The command line that draws a figure with the reader's package and compares it with the figure."""
    mine = f"{number}-mine.png"
    return (f"cs451 render --figure {number} -o {mine} --impl my-submission && "
            f"cs451 compare {mine} assignments/{handout}/figures/{number}.png -o {number}-compare.png")


@dataclass(frozen=True)
class Figure:
    test: Test
    image: np.ndarray           # uint8, as cs451 render writes it

    @property
    def name(self) -> str:
        return f"{self.test.number}.png"


def is_image_test(test: Test) -> bool:
    return test.check.name == "image_check" or "image_part" in test.check.args or "image_check" in test.check.args


def stage_figures(stage: str, show_progress: bool = True) -> list[Figure]:
    """The reference's target image of every public image test of a stage (from the answer cache)."""
    tests = [t for t in load_tests(stage, include_hidden=False) if is_image_test(t)]
    reference, truths = ReferenceAnswers(stage), TruthValues(stage)
    bar = Progress(f"figures for {stage}", len(tests)) if show_progress else None
    out = []
    for t in tests:
        _, expected = expected_for(t, reference, truths)
        images = target_images(expected, t.params)
        if images:
            out.append(Figure(t, images["reference"]))
        if bar:
            bar.advance(note=t.number)
    if bar:
        bar.close()
    return out


def block_text(figures: list[Figure], stage: str) -> str:
    if not figures:
        return ""
    rows = "".join(f"| ![{f.test.number}](figures/{f.name}) | **{f.test.number}** {f.test.name} |\n" for f in figures)
    first = figures[0].test.number
    intro = INTRO.format(number=first, recipe=recipe(first, get_stage(stage).handout))
    return intro + "| target | test |\n|---|---|\n" + rows + "\n"


def _handout(stage: str) -> Path:
    return KIT_ROOT / "assignments" / get_stage(stage).handout / "README.md"


def write_figures(stage: str) -> list[Path]:
    """Write a stage's figures and its handout's figures block; the files written."""
    handout = _handout(stage)
    text = handout.read_text()
    if not BLOCK.search(text):
        raise KitError(f"{handout.relative_to(KIT_ROOT)}: no <!-- figures --> … <!-- /figures --> block to fill")
    figures = stage_figures(stage)
    folder = handout.parent / "figures"
    folder.mkdir(exist_ok=True)
    for old in folder.glob("*.png"):
        if old.name not in {f.name for f in figures}:
            old.unlink()
    written = [save_png(folder / f.name, f.image) for f in figures]
    block = block_text(figures, stage)
    handout.write_text(BLOCK.sub(lambda m: m.group(1) + block + m.group(3), text))
    return written + [handout]


def check_figures(stage: str, tolerance: ImageTolerance = ImageTolerance()) -> list[str]:
    """Where the committed figures and block differ from what the reference draws now (empty when in step)."""
    handout = _handout(stage)
    figures = stage_figures(stage, show_progress=False)
    problems = []
    match = BLOCK.search(handout.read_text())
    if match is None or match.group(2) != block_text(figures, stage):
        problems.append(f"{handout.relative_to(KIT_ROOT)}: the figures block is not what `cs451 figures` writes")
    folder = handout.parent / "figures"
    for f in figures:
        path = folder / f.name
        if not path.exists():
            problems.append(f"{path.relative_to(KIT_ROOT)}: missing")
            continue
        have = load_png(path)
        want = f.image.astype(np.float64) / 255.0
        if have.shape != want.shape or not compare_images(want, have, tolerance).passed:
            problems.append(f"{path.relative_to(KIT_ROOT)}: differs from the reference's render")
    extra = {p.name for p in folder.glob("*.png")} - {f.name for f in figures} if folder.is_dir() else set()
    problems += [f"{(folder / n).relative_to(KIT_ROOT)}: not a figure of any public image test" for n in sorted(extra)]
    return problems
