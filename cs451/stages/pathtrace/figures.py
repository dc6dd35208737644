"""The path tracing deck's figure: the Cornell box converging, by the reference through the stage's render."""
from __future__ import annotations

import numpy as np

from ...progress import Progress
from ...scene import parse_scene
from .. import get_stage
from ...slides.registry import Drawn, slide_figure
from ...slides.canvas import Panel, encoded, panel_grid, reference_impl, scene_data

PATHTRACE_KIT = ("cs451.stages.pathtrace", "cs451.stages.pathtrace.paths", "cs451.stages.base", "cs451.patching",
                 "cs451.patches", "cs451.scene", "cs451.imageio", "cs451.tracescene")


@slide_figure("pathtrace-convergence",
              "The Cornell box path traced by the reference (render_traced, the stage's render) at 1, 4, 16 and 64 "
              "samples per pixel, and the direct light alone at 64: the noise falls as 1/√N, and the bounces add "
              "the colour bleeding",
              full={"spps": [1, 4, 16, 64], "size": [160, 160]},
              quick={"spps": [1, 4], "size": [32, 32]},
              stages=("pathtrace",), kit=PATHTRACE_KIT, scenes=("cornell-box.json",), steps=5)
def _convergence(bar: Progress, spps: list[int], size: list[int]) -> Drawn:
    stage, impl = get_stage("pathtrace"), reference_impl("pathtrace")
    scene = parse_scene(scene_data("cornell-box.json"), "cornell-box.json")
    render = stage.render.__globals__["render_traced"]
    panels, facts = [], {"spps": spps, "bounces_per_path": {}}
    for spp in spps:
        image, counters = render(scene, impl, tuple(size), spp=spp)
        facts["bounces_per_path"][str(spp)] = counters["bounce"] / counters["camera"]
        panels.append(Panel(encoded(image, scene), f"{spp} sample{'s' * (spp > 1)} per pixel"))
        bar.advance(note=f"{spp} spp")
    direct, _ = render(scene, impl, tuple(size), spp=spps[-1], max_depth=1)
    panels.append(Panel(encoded(direct, scene), f"direct light only, {spps[-1]} per pixel"))
    bar.advance(note="direct")
    grid = panel_grid([panels], "Path tracing the Cornell box: one path per pixel a pass")
    return Drawn(np.asarray(grid), facts)
