"""The handouts' explanatory pictures: scenes drawn by the reference to show an idea, with captions.

Unlike the target images (:mod:`cs451.packaging.figures`), these belong to no test: they show what a
handout explains. A stage names its pictures (``Stage.diagrams``); ``cs451 figures`` writes them to
``assignments/<handout>/diagrams/`` beside the target images, and ``cs451 figures --check`` says
where they have drifted from what the reference draws now.
"""
from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np

from .. import KIT_ROOT
from ..compare import ImageTolerance, compare_images
from ..imageio import load_png, save_png
from ..stages import get_stage


def _pictures(stage: str) -> dict[str, Callable[[], np.ndarray]]:
    st = get_stage(stage)
    return st.diagrams() if st.diagrams is not None else {}


def _folder(stage: str) -> Path:
    return KIT_ROOT / "assignments" / get_stage(stage).handout / "diagrams"


def write_diagrams(stage: str) -> list[Path]:
    """Draw a stage's diagrams into its handout's diagrams/ folder; the files written."""
    return [save_png(_folder(stage) / name, draw()) for name, draw in _pictures(stage).items()]


def check_diagrams(stage: str, tolerance: ImageTolerance = ImageTolerance()) -> list[str]:
    """Where the committed diagrams differ from what the reference draws now (empty when in step)."""
    problems = []
    for name, draw in _pictures(stage).items():
        path = _folder(stage) / name
        where = path.relative_to(KIT_ROOT)
        if not path.exists():
            problems.append(f"{where}: missing")
            continue
        want = draw().astype(np.float64) / 255.0
        have = load_png(path)
        if have.shape != want.shape or not compare_images(want, have, tolerance).passed:
            problems.append(f"{where}: differs from the reference's render")
    return problems
