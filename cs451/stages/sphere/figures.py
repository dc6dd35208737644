"""The sphere deck's figures: Gouraud beside Phong at growing tessellations, and the handout's two diagrams.
"""
from __future__ import annotations


import numpy as np

from cs451.progress import Progress
from cs451.scene import parse_scene
from cs451.stages import get_stage
from cs451.slides.registry import Drawn, slide_figure
from cs451.slides.canvas import Panel, encoded, panel_grid, reference_impl, scene_data


SPHERE_KIT = ("cs451.stages.sphere", "cs451.stages.base", "cs451.scene", "cs451.gl", "cs451.imageio")
SPHERE_DIAGRAMS = (*SPHERE_KIT, "cs451.stages.sphere.diagrams", "cs451.demos.frames")


@slide_figure("sphere-gouraud-vs-phong",
         "The notes' lit sphere shaded per vertex (Gouraud, S5) and per fragment (Phong, S6) at its 32 × 32 "
         "tessellation and at a coarse 12 × 8 one, with their difference",
         full={"size": 260, "tessellations": [[32, 32], [12, 8]]}, quick={"size": 64},
         stages=("sphere",), kit=SPHERE_KIT, scenes=("sphere.json",), steps=4)
def _gouraud_vs_phong(bar: Progress, size: int, tessellations: list[list[int]]) -> Drawn:
    stage, impl = get_stage("sphere"), reference_impl("sphere")
    rows, facts = [], {}
    for slices, stacks in tessellations:
        data = scene_data("sphere.json")
        data["objects"][0].update(slices=slices, stacks=stacks)
        scene = parse_scene(data, f"sphere {slices} x {stacks}")
        shaded = {}
        for shading in ("gouraud", "phong"):
            shaded[shading] = encoded(stage.render(scene, impl, (size, size), shading=shading), scene)
            bar.advance(note=f"{shading} {slices}x{stacks}")
        difference = np.abs(shaded["gouraud"].astype(int) - shaded["phong"].astype(int))
        facts[f"{slices}x{stacks}"] = {"max_difference": int(difference.max()),
                                       "mean_difference": float(difference.mean())}
        rows.append([Panel(shaded["gouraud"], f"Gouraud: lit per vertex (S5)\n{slices} × {stacks} sphere"),
                     Panel(shaded["phong"], f"Phong: lit per fragment (S6)\n{slices} × {stacks} sphere"),
                     Panel(np.clip(difference * 8, 0, 255).astype(np.uint8),
                           f"difference × 8\n(at most {int(difference.max())}/255)")])
    image = panel_grid(rows, "One sphere, one light: where the lighting equation is evaluated")
    return Drawn(image, facts)


def _sphere_diagram(file: str) -> Drawn:
    return Drawn(get_stage("sphere").diagrams()[file]())


@slide_figure("sphere-light-spaces",
         "The notes' sphere with its light set after gluLookAt (fixed in the world, as the notes do) and before "
         "it (fixed to the camera), and their difference: the stage's handout diagram",
         engine=("sphere",), kit=SPHERE_DIAGRAMS, scenes=("sphere.json",))
def _light_spaces(bar: Progress) -> Drawn:
    return _sphere_diagram("light-spaces.png")


@slide_figure("sphere-modelview",
         "The modelview composition: translate, rotate and scale called in three orders on one sphere (the call "
         "made last acts first): the stage's handout diagram",
         engine=("sphere",), kit=SPHERE_DIAGRAMS)
def _modelview(bar: Progress) -> Drawn:
    return _sphere_diagram("modelview-order.png")


