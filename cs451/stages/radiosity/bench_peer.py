"""The truth the radiosity benchmarks measure against: Mitsuba 3's path tracer on the same scene, and which pixels
show which wall of the Cornell box (each wall's pixels away from its edges), so that an image's error is read wall
by wall. Shared by ``cs451 bench radiosity``, ``cs451 bench walkthrough`` and the adaptive mesh's measurement;
Mitsuba is an optional peer (``pip install -e '.[peers]'``), imported only when a render is asked for.
"""
from __future__ import annotations

import functools
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from cs451 import patching as P
from cs451.scene import load_scene
from cs451.stages import radiosity as R
from cs451.stages.radiosity import display as D

WALLS = {"floor": [0], "ceiling": [1], "back": [2], "left (red)": [4], "right (green)": [3],
         "short block": [5, 6, 7, 8, 9], "tall block": [10, 11, 12, 13, 14]}


def polygon_ids(scene: Any, size: tuple[int, int], quads: np.ndarray | None = None, drawer: Any = None) -> np.ndarray:
    """Which polygon (or which of ``quads``) each pixel shows (-1: none), drawn with the kit's Gouraud drawer from the scene camera."""
    if quads is None:
        quads, _, _, _ = P.radiosity_surfaces(scene)
    if drawer is not None:
        from cs451.gl import make_current
        make_current(drawer.ctx)                   # other engines may have made their context current
    ids = np.arange(len(quads), dtype=np.float64)
    positions = quads.reshape(-1, 3)
    colors = np.repeat(np.column_stack([ids + 1, np.zeros((len(ids), 2))]), 4, axis=0)
    corners = np.arange(4 * len(quads)).reshape(-1, 4)
    image = (drawer or D.GouraudDrawer()).draw(positions, colors, corners,
                                               D.camera_matrix(scene, *size, R.camera_view(scene)), *size)
    return np.round(image[..., 0]).astype(int) - 1


def mitsuba_cornell(scene: Any, size: tuple[int, int], spp: int, max_depth: int, seed: int = 0) -> np.ndarray:
    """The scene rendered by Mitsuba 3's path tracer (scalar_rgb), linear radiance (h, w, 3); ``seed`` its sampler's."""
    import tempfile

    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    quads, reflectance, radiosity, _ = P.radiosity_surfaces(scene)
    cam = scene.camera
    objects: dict[str, Any] = {"type": "scene", "integrator": {"type": "path", "max_depth": max_depth},
                               "sensor": {"type": "perspective", "fov_axis": "y", "fov": cam.fovy,
                                          "near_clip": cam.near, "far_clip": cam.far,
                                          "to_world": mi.ScalarTransform4f().look_at(origin=list(cam.eye),
                                                                                      target=list(cam.center),
                                                                                      up=list(cam.up)),
                                          "film": {"type": "hdrfilm", "width": size[0], "height": size[1],
                                                   "rfilter": {"type": "box"}},
                                          "sampler": {"type": "independent", "sample_count": spp}}}
    folder = Path(tempfile.mkdtemp(prefix="cs451-mitsuba-"))
    for k, quad in enumerate(quads):
        path = folder / f"p{k}.obj"
        lines = [f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in quad] + ["f 1 2 3", "f 1 3 4"]
        path.write_text("\n".join(lines) + "\n")
        shape: dict[str, Any] = {"type": "obj", "filename": str(path), "face_normals": True,
                                 "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": list(reflectance[k])}}}
        if radiosity[k].max() > 0:
            shape["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": list(radiosity[k] / math.pi)}}
        objects[f"polygon{k}"] = shape
    image = mi.render(mi.load_dict(objects), seed=seed)
    return np.asarray(image, dtype=np.float64)[..., :3]


def wall_masks(ids: np.ndarray) -> dict[str, np.ndarray]:
    """Each wall's pixels away from its polygons' edges (each polygon eroded by 2 pixels on its own), for the walls shown.

    A block's faces are eroded one by one, not as their union: the union keeps the pixels along the crease between
    the lit top and a dark side, where one pixel's coverage (the kit's pixel centres against Mitsuba's box filter)
    moved a dark face's mean by 9% in the walkthrough."""
    out = {}
    for wall, polys in WALLS.items():
        eroded = np.zeros(ids.shape, dtype=bool)
        for poly in polys:
            inside = ids == poly
            kept = inside.copy()
            for dy in (-2, -1, 0, 1, 2):
                for dx in (-2, -1, 0, 1, 2):
                    kept &= np.roll(np.roll(inside, dy, axis=0), dx, axis=1)
            eroded |= kept
        if eroded.any():
            out[wall] = eroded
    return out


def wall_means(image: np.ndarray, ids: np.ndarray) -> dict[str, list[float]]:
    """Mean RGB per wall over its pixels, away from its edges (a 2-pixel erosion)."""
    return {wall: image[mask].mean(axis=0).tolist() for wall, mask in wall_masks(ids).items()}


@functools.lru_cache(maxsize=4)
def mitsuba_reference(scene_name: str, size: tuple[int, int], spp: int, max_depth: int = 64,
                      camera: tuple[tuple[str, Any], ...] = ()) -> dict[str, Any]:
    """Mitsuba's render of a bundled scene, once per run: two halves of ``spp // 2`` samples (seeds 0 and 1).

    ``image`` is their mean (``spp`` samples); ``halves`` let a comparison say how noisy it still is (their
    difference is twice the mean's noise, in the mean). ``seconds``: both renders. ``camera``: (field, value)
    pairs that replace the scene camera's (another view of the same scene).
    """
    import dataclasses

    start = time.perf_counter()
    scene = load_scene(scene_name)
    if camera:
        scene = dataclasses.replace(scene, camera=dataclasses.replace(scene.camera, **dict(camera)))
    halves = tuple(mitsuba_cornell(scene, size, max(spp // 2, 1), max_depth, seed=seed) for seed in (0, 1))
    return {"image": 0.5 * (halves[0] + halves[1]), "halves": halves, "spp": 2 * max(spp // 2, 1),
            "seconds": time.perf_counter() - start}
