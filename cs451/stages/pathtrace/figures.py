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
              "samples per pixel (the passes of one render), and the direct light alone at 64: the noise falls as "
              "1/√N, and the bounces add the colour bleeding",
              full={"spps": [1, 4, 16, 64], "size": [208, 208], "per_row": 5},
              quick={"spps": [1, 4], "size": [32, 32]},
              stages=("pathtrace",), kit=PATHTRACE_KIT, scenes=("cornell-box.json",), steps=2)
def _convergence(bar: Progress, spps: list[int], size: list[int], per_row: int = 3) -> Drawn:
    stage, impl = get_stage("pathtrace"), reference_impl("pathtrace")
    scene = parse_scene(scene_data("cornell-box.json"), "cornell-box.json")
    render = stage.render.__globals__["render_traced"]
    means: dict[int, np.ndarray] = {}

    def keep(k: int, mean: np.ndarray) -> None:     # the first k passes of the render are its k-sample image
        if k in spps:
            means[k] = mean.copy()
    _, counters = render(scene, impl, tuple(size), spp=max(spps), on_pass=keep)
    bar.advance(note=f"{max(spps)} spp")
    panels = [Panel(encoded(means[spp], scene), f"{spp} spp") for spp in spps]
    direct, _ = render(scene, impl, tuple(size), spp=spps[-1], max_depth=1)
    panels.append(Panel(encoded(direct, scene), f"direct only, {spps[-1]}"))
    bar.advance(note="direct")
    rows = [panels[k:k + per_row] for k in range(0, len(panels), per_row)]
    grid = panel_grid(rows, pad=8, min_width=0)
    facts = {"spps": spps, "bounces_per_path": counters["bounce"] / counters["camera"]}
    return Drawn(np.asarray(grid), facts)
