"""Every ray Whitted's recursion casts for a few pixels, recorded from the reference as the grader records it:
the ray trees the deck draws (built by ``ray_tree.build_tree``, as the demo's are).
"""
from __future__ import annotations

from typing import Any, Callable

import numpy as np

from ...errors import KitError
from ...scene import parse_scene
from ...slides.canvas import reference_impl
from .accel import forced
from .ray_tree import build_tree
from .. import get_stage
from ..base import functions_replaced

#: how far a ray that leaves the scene is drawn
MISS_LENGTH = 2.5


def ray_tree(data: dict[str, Any], pixels: list[tuple[int, int]], size: tuple[int, int],
             **options: Any) -> list[dict[str, Any]]:
    """Every ray Whitted's recursion casts for these pixels of an image of ``size``, with its hit.

    W11 (the reference's) traces the pixels' camera rays (W1) while its calls of W5 (closest hit) and W7 (shadow
    rays) are recorded, as the grader records the reference (``functions_replaced``). A ray is a dict: ``kind``
    (camera, reflection, refraction or shadow), ``origin``, ``end`` (its hit, the light, or MISS_LENGTH along a
    miss), ``hit`` (bool), ``parent`` (the index of the ray whose hit cast it), ``depth``, ``material`` at the
    hit, and for a shadow ray ``through`` (the RGB factor of light that gets through).
    """
    from ...tracescene import build
    stage, impl = get_stage("whitted"), reference_impl("whitted")
    scene = parse_scene(data, "<ray tree>")
    origins, directions = stage.call(impl, "W1", scene.camera, *size)
    picked = [y * size[0] + x for x, y in pixels]
    calls: dict[str, list] = {"W5": [], "W7": []}

    def recording(task: str) -> Callable[[Any], Any]:
        def wrap(own: Any) -> Any:
            def recorded(*args: Any) -> Any:
                out = own(*args)
                calls[task].append((*args[1:], *(out if task == "W5" else (out,))))
                return out
            return recorded
        return wrap

    with forced("numpy"), functions_replaced(stage, impl, {task: recording(task) for task in calls}):
        stage.probes["render"](impl, data, [len(picked), 1], origins=origins[picked], directions=directions[picked],
                               **options)
    arrays = build(scene)
    rays: list[dict[str, Any]] = []
    for ray in build_tree(calls["W5"], calls["W7"], MISS_LENGTH):
        if ray.kind == "ray" or (ray.kind == "shadow" and ray.parent is None):
            raise KitError("ray tree: a spawned ray starts from no recorded hit")
        material = None
        if ray.hit:
            material = arrays.material_names[int(arrays.material_at(np.array([ray.prim]), ray.end[None])[0])]
        rays.append({"kind": ray.kind, "origin": ray.start, "direction": ray.direction, "end": ray.end,
                     "hit": ray.hit, "normal": ray.normal, "parent": ray.parent, "depth": ray.depth,
                     "material": material, **({"through": ray.through} if ray.kind == "shadow" else {})})
    return rays
