"""The sphere deck's figures: Gouraud beside Phong at growing tessellations, and the scenes of the handout's two
diagrams (where the light is, the modelview order), drawn again here through the figures' panels so that their
captions are measured text (the handout keeps its own pictures, :mod:`cs451.stages.sphere.diagrams`).
"""
from __future__ import annotations

import copy

import numpy as np

from cs451.progress import Progress
from cs451.scene import parse_scene
from cs451.stages import get_stage
from cs451.slides.registry import Drawn, slide_figure
from cs451.slides.canvas import Panel, encoded, panel_grid, reference_impl, scene_data


SPHERE_KIT = ("cs451.stages.sphere", "cs451.stages.base", "cs451.scene", "cs451.gl", "cs451.imageio")
SPHERE_DIAGRAMS = (*SPHERE_KIT, "cs451.stages.sphere.diagrams")


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


def _render(data: dict, size: int) -> np.ndarray:
    """A scene drawn by the reference through stage 1's render, encoded as the scene asks."""
    scene = parse_scene(data, "<figure>")
    return encoded(get_stage("sphere").render(scene, reference_impl("sphere"), (size, size)), scene)


@slide_figure("sphere-light-spaces",
         "The notes' sphere with its light set after gluLookAt (fixed in the world, as the notes do) and before "
         "it (fixed to the camera), and their difference: the handout diagram's scenes, drawn by the reference",
         full={"size": 400}, quick={"size": 64},
         stages=("sphere",), kit=SPHERE_DIAGRAMS, scenes=("sphere.json",), steps=2)
def _light_spaces(bar: Progress, size: int) -> Drawn:
    world = scene_data("sphere.json")
    eye = copy.deepcopy(world)
    eye["lights"][0]["space"] = "eye"
    notes, before = _render(world, size), _render(eye, size)
    bar.advance(note="rendered")
    difference = np.abs(notes.astype(int) - before.astype(int))
    light = world["lights"][0]["position"]
    panels = [Panel(notes, f"set after gluLookAt (the notes):\nfixed in the world at {tuple(light)}"),
              Panel(before, f"set before gluLookAt:\n{tuple(light)} fixed to the camera"),
              Panel(np.clip(difference * 8, 0, 255).astype(np.uint8),
                    f"difference × 8\n(at most {int(difference.max())}/255)")]
    grid = panel_grid([panels], "Where the light is depends on when it is set")
    bar.advance(note="panels")
    return Drawn(grid, {"max_difference": int(difference.max()), "light": light})


@slide_figure("sphere-modelview",
         "The modelview composition: translate, rotate and scale called in three orders on one sphere (the call "
         "made last acts first): the handout diagram's scenes, drawn by the reference",
         full={"size": 400}, quick={"size": 64},
         stages=("sphere",), kit=SPHERE_DIAGRAMS, steps=3)
def _modelview(bar: Progress, size: int) -> Drawn:
    from .diagrams import _order_scene
    t = {"type": "translate", "offset": [2, 0, 0]}
    r = {"type": "rotate", "angle": 45, "axis": [0, 0, 1]}
    sc = {"type": "scale", "factors": [0.9, 0.3, 0.3]}
    orders = [([t, r, sc], "translate; rotate; scale", "scaled, turned, then moved"),
              ([r, t, sc], "rotate; translate; scale", "moved along x, then turned"),
              ([sc, r, t], "scale; rotate; translate", "moved, turned, then squashed")]
    panels = []
    for transform, calls, effect in orders:
        panels.append(Panel(_render(_order_scene(transform), size), f"{calls}\n{effect}"))
        bar.advance(note=calls)
    return Drawn(panel_grid([panels], "The call made last moves the sphere first"), {"orders": [o[1] for o in orders]})
