"""Stage 1's explanatory pictures for its handout (:mod:`cs451.packaging.diagrams` writes and checks them).

Where the light is (notes §1: glLightfv after gluLookAt, or before it), and in which order the
modelview calls act (S3); both drawn by the reference through the stage's own renderer.
"""
from __future__ import annotations

import copy
import json
from typing import Callable

import numpy as np

from ... import KIT_ROOT
from ...demos.frames import captioned
from ...imageio import to_uint8
from ...scene import BUNDLED_DIR, parse_scene


def _reference(stage: str):
    from ...impl import load_impl
    return load_impl(KIT_ROOT / "reference" / stage, stage)


def _panel(scene: dict, size: tuple[int, int], caption: list[str]) -> np.ndarray:
    from .. import sphere as s1
    sc = parse_scene(scene, "<diagram>")
    image = to_uint8(s1.render(sc, _reference("sphere"), size), sc.image.exposure, sc.image.srgb)
    for line in caption:
        image = captioned(image, line)
    return image


def _side_by_side(panels: list[np.ndarray], gap: int = 6) -> np.ndarray:
    height = max(p.shape[0] for p in panels)
    padded = [np.pad(p, ((0, height - p.shape[0]), (0, gap), (0, 0)), constant_values=255) for p in panels]
    return np.hstack(padded)[:, :-gap]


def light_spaces() -> np.ndarray:
    """The notes' sphere with its light set after gluLookAt (world space) beside the same light set before it."""
    scene = json.loads((BUNDLED_DIR / "sphere.json").read_text())
    eye = copy.deepcopy(scene)
    eye["lights"][0]["space"] = "eye"
    size = (300, 300)
    notes = _panel(scene, size, ["set after gluLookAt (the notes):", "world (10, 5, 20) = eye (10, 5, 12)"])
    before = _panel(eye, size, ["set before gluLookAt:", "eye (10, 5, 20), fixed to the camera"])
    difference = np.clip(np.abs(notes.astype(int) - before.astype(int)) * 8, 0, 255).astype(np.uint8)
    difference[size[1]:] = notes[size[1]:]   # keep a caption strip, then write its own caption over it
    difference = captioned(captioned(difference[:size[1]], "difference x 8"), "(up to 29/255 at 500 x 500)")
    return _side_by_side([notes, before, difference])


def _order_scene(transform: list[dict]) -> dict:
    """A stretched sphere placed by ``transform``, a small white sphere at the origin, and the x axis drawn in dots."""
    dots = [{"type": "sphere", "radius": 0.06, "center": [x, 0, 0], "material": "mark", "slices": 8, "stacks": 6}
            for x in np.arange(0.5, 3.01, 0.5).tolist()]
    return {
        "image": {"width": 300, "height": 300},
        "camera": {"eye": [1.2, 0.6, 9], "center": [1.2, 0.6, 0], "fovy": 36, "near": 1, "far": 50},
        "ambient": [0.25, 0.25, 0.25],
        "lights": [{"type": "point", "position": [4, 6, 10], "diffuse": [0.9, 0.9, 0.9], "specular": [0.4, 0.4, 0.4]}],
        "materials": {"body": {"diffuse": [0.3, 0.9, 0.5], "specular": [0.3, 0.3, 0.3], "shininess": 30},
                      "mark": {"diffuse": [0.95, 0.95, 0.95]}},
        "objects": [{"type": "sphere", "radius": 0.15, "material": "mark", "slices": 16, "stacks": 12}, *dots,
                    {"type": "group", "transform": transform,
                     "objects": [{"type": "sphere", "radius": 1, "material": "body"}]}],
    }


def modelview_order() -> np.ndarray:
    """The same three calls in three orders: the call made last is the first applied to the sphere."""
    t = {"type": "translate", "offset": [2, 0, 0]}
    r = {"type": "rotate", "angle": 45, "axis": [0, 0, 1]}
    s = {"type": "scale", "factors": [0.9, 0.3, 0.3]}
    size = (300, 300)
    return _side_by_side([
        _panel(_order_scene([t, r, s]), size, ["translate; rotate; scale", "scaled, turned, then moved"]),
        _panel(_order_scene([r, t, s]), size, ["rotate; translate; scale", "moved along x, then all turned"]),
        _panel(_order_scene([s, r, t]), size, ["scale; rotate; translate", "moved, turned, then squashed"]),
    ])


PICTURES: dict[str, Callable[[], np.ndarray]] = {"light-spaces.png": light_spaces,
                                                  "modelview-order.png": modelview_order}
