"""Stage 4's explanatory pictures for its handout (:mod:`cs451.packaging.diagrams` writes and checks them).

The glossy box (``cs451/scenes/glossy-box.json``) drawn from one solve twice: the Gouraud display alone, and with
the direct surface reflection of notes §2.3 added (:mod:`cs451.stages.radiosity.highlight`), so the handout shows what the option
adds and that the radiosity under it is the same.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from ... import KIT_ROOT
from ...demos.frames import captioned
from ...imageio import to_uint8
from ...scene import load_scene

#: each panel's size: small enough that ``cs451 figures --check`` redraws it in about a second
PANEL = (240, 240)


def _reference(stage: str):
    from ...impl import load_impl
    return load_impl(KIT_ROOT / "reference" / stage, stage)


def glossy_box() -> np.ndarray:
    """The glossy box without and with the highlight, side by side, captioned."""
    from .. import radiosity as R

    scene = load_scene("glossy-box")
    impl = _reference("radiosity")
    opts = R.STAGE.options(scene)
    patches = R.make_patches(scene, impl, opts.patch_size)
    sol = R.solve(patches, impl, opts)
    shine = R.glossy.highlight(scene, patches, opts.specular_samples)
    panels = []
    for gloss, caption in ((None, "specular: false (B/pi alone)"),
                           (shine, f"specular: true (+ Phong, n = {shine.coefficients[:, 3].max():g})")):
        image = R.draw_solution(scene, impl, patches, sol.display, PANEL, opts.exposure, highlight=gloss)
        panels.append(captioned(to_uint8(image, scene.image.exposure, scene.image.srgb), caption))
    gap = np.full((panels[0].shape[0], 6, 3), 255, dtype=np.uint8)
    return np.hstack([panels[0], gap, panels[1]])


PICTURES: dict[str, Callable[[], np.ndarray]] = {"glossy-box.png": glossy_box}
