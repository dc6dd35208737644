"""Every ray Whitted's recursion casts for a few pixels, recorded from the reference as the grader records it:
the ray trees the deck draws.
"""
from __future__ import annotations

from typing import Any, Callable

import numpy as np

from ...errors import KitError
from ...scene import parse_scene
from ...slides.canvas import numpy_path, reference_impl
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
                calls[task].append((args[1:], out))
                return out
            return recorded
        return wrap

    with numpy_path(impl), functions_replaced(stage, impl, {task: recording(task) for task in calls}):
        stage.probes["render"](impl, data, [len(picked), 1], origins=origins[picked], directions=directions[picked],
                               **options)
    arrays = build(scene)
    rays: list[dict[str, Any]] = []
    for depth, ((o, d), (t, prim, normals)) in enumerate(calls["W5"]):
        for k in range(len(o)):
            parent, kind = None, "camera"
            if depth:
                parent = nearest_hit(rays, o[k], depth - 1)
                p = rays[parent]
                facing = p["normal"] if p["direction"] @ p["normal"] < 0 else -p["normal"]
                kind = "reflection" if d[k] @ facing > 0 else "refraction"
            hit = bool(prim[k] >= 0)
            end = o[k] + (t[k] if hit else MISS_LENGTH) * d[k]
            material = arrays.material_names[int(arrays.material_at(prim[k:k + 1], end[None])[0])] if hit else None
            rays.append({"kind": kind, "origin": o[k], "direction": d[k], "end": end, "hit": hit, "normal": normals[k],
                         "parent": parent, "depth": depth, "material": material})
    for (o, targets), through in calls["W7"]:
        for k in range(len(o)):
            parent = nearest_hit(rays, o[k])
            rays.append({"kind": "shadow", "origin": o[k], "end": np.asarray(targets[k], dtype=np.float64),
                         "hit": False, "parent": parent, "depth": rays[parent]["depth"] + 1, "material": None,
                         "through": np.asarray(through[k], dtype=np.float64)})
    return rays


def nearest_hit(rays: list[dict[str, Any]], point: np.ndarray, depth: int | None = None) -> int:
    """The ray (of ``depth``) whose hit a spawned ray starts from: the nearest hit point (spawn moves it by 1e-9)."""
    found = [(float(np.linalg.norm(r["end"] - point)), i) for i, r in enumerate(rays)
             if r["hit"] and r["kind"] != "shadow" and (depth is None or r["depth"] == depth)]
    if not found:
        raise KitError("ray tree: a spawned ray starts from no recorded hit")
    return min(found)[1]
