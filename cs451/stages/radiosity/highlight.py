"""Direct surface reflection for the radiosity display (notes §2.3): a Phong highlight from the scene's area lights,
added per pixel on top of the Gouraud-shaded radiosity.

Radiosity solves for light between Lambertian surfaces only, so the patches' B carries the diffuse part of every
bounce and nothing that depends on where the viewer stands. The notes' pipeline adds the view-dependent part in the
display: the z-buffer pass that draws the Gouraud colours adds, for glossy materials, the light's direct reflection.
That is the kit's, not a task: the students' R1–R5 are untouched, and the highlight goes on top of their colours.

The lobe is the energy-normalised ("modified") Phong BRDF of Lafortune and Willems (1994),

    f_s(ω_i, ω_o) = k_s · (n + 2) / (2π) · cos^n α,    α: angle between ω_o and ω_i mirrored about the normal,

with k_s the material's ``specular`` and n its ``shininess``. The factor (n + 2)/(2π) makes the reflected
*radiance* come out in the same units as the radiosity image (B/π): at normal incidence the lobe reflects
exactly k_s of the incident power whatever n is, at other angles less, so a glossy material with
``diffuse + specular <= 1`` does not create energy, and a sharper lobe (larger n) gives a smaller, brighter
highlight of the same total. OpenGL's un-normalised cos^n (stage 1) has no such units: it is a colour.

An area light of radiance L is integrated over its quad with a fixed k × k grid of cell centres (no randomness:
the image is the same every run), each a point of radiance L over its share ΔA = |u × v| / k² of the area:

    L_spec(x, ω_o) = Σ_samples f_s · L · cos θ_x · cos θ_y · ΔA / r²

(θ_x at the surface, θ_y at the light, both clamped at 0: a light emits only on its front side, ``edge_u ×
edge_v``, and lights only surfaces in front of it).

What this first version leaves out, on purpose: **shadows** (a light sample hidden behind a block still lights the
highlight; the diffuse part, from the hemicube, does have shadows), glossy reflection of the lit walls (only the
lights are reflected), and any feedback into the solve (B is the same with or without the highlight; the diffuse
albedo is not lowered by k_s, so keep ``diffuse + specular <= 1`` for a physically meaningful material). A
material is glossy when its ``specular`` is non-zero and its ``shininess`` is above 0 (n = 0 would be a second,
flat diffuse term, which the radiosity already holds).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

#: light samples per edge of an area light by default: a 4 × 4 grid (16 points) per light
DEFAULT_SAMPLES = 4
#: the most samples per edge (a 16 × 16 grid); more cost time in every pixel and change little
MAX_SAMPLES = 16
#: the most light samples in all: they travel to the shader in one float texture, 1024 rows high at most
#: (the least GL_MAX_TEXTURE_SIZE OpenGL 3.3 promises)
MAX_TOTAL_SAMPLES = 1024


def check_samples(k: Any) -> str | None:
    """The schema check of ``options.radiosity.specular_samples``: a grid of 1 × 1 to 16 × 16 points per light."""
    return None if 1 <= k <= MAX_SAMPLES else f"must lie between 1 and {MAX_SAMPLES} (a k × k grid per light), got {k}"


@dataclass(frozen=True)
class Highlight:
    """What the display needs to add the highlight: one row per patch (or per vertex drawn), the light samples, the eye.

    ``normals`` (k, 3) unit front normals; ``coefficients`` (k, 4) k_s (red, green, blue) and n per row;
    ``lights`` (s, 3, 3) per sample its position, the unit normal of its emitting side and L·ΔA (radiance times its
    share of the light's area); ``eye`` (3,) the camera's position, in world coordinates like the rest.
    """
    normals: np.ndarray
    coefficients: np.ndarray
    lights: np.ndarray
    eye: np.ndarray

    def scaled(self, factor: float) -> "Highlight":
        """The same highlight, ``factor`` times as bright (the display's exposure)."""
        lights = self.lights.copy()
        lights[:, 2] *= factor
        return replace(self, lights=lights)

    def per_corner(self, corners_per_row: int = 4) -> "Highlight":
        """Each row repeated for the corners of its patch: one row per vertex drawn."""
        return replace(self, normals=np.repeat(self.normals, corners_per_row, axis=0),
                       coefficients=np.repeat(self.coefficients, corners_per_row, axis=0))


def light_samples(scene: Any, per_edge: int = DEFAULT_SAMPLES) -> np.ndarray:
    """(s, 3, 3): a ``per_edge`` × ``per_edge`` grid of cell centres over every area light, as :class:`Highlight`
    holds them."""
    from ...scene import AreaLight

    rows = []
    t = (np.arange(per_edge) + 0.5) / per_edge
    for light in scene.lights:
        if not isinstance(light, AreaLight):
            continue
        c, u, v = (np.asarray(x, dtype=np.float64) for x in (light.corner, light.edge_u, light.edge_v))
        normal = np.cross(u, v)
        area = float(np.linalg.norm(normal))
        points = c + t[:, None, None] * u + t[None, :, None] * v
        share = np.asarray(light.radiance, dtype=np.float64) * area / per_edge ** 2
        for p in points.reshape(-1, 3):
            rows.append([p, normal / area, share])
    return np.asarray(rows, dtype=np.float64).reshape(-1, 3, 3)


def patch_coefficients(scene: Any, parent: np.ndarray) -> np.ndarray:
    """(m, 4): each patch's k_s and n, from the material of the polygon it came from (0 where it is not glossy).

    Polygons come in the order of :func:`cs451.patches.scene_polygons`; area lights, last, reflect nothing.
    """
    from ...patches import scene_polygons

    _, names, _ = scene_polygons(scene)
    per_polygon = np.zeros((len(names), 4))
    for k, name in enumerate(names[:len(names) - _area_lights(scene)]):      # the lights' quads come last
        m = scene.material(name)
        if m.shininess > 0 and any(s > 0 for s in m.specular):
            per_polygon[k] = (*m.specular, m.shininess)
    return per_polygon[np.asarray(parent, dtype=np.int64)]


def _area_lights(scene: Any) -> int:
    from ...scene import AreaLight
    return sum(isinstance(light, AreaLight) for light in scene.lights)


def highlight(scene: Any, patches: Any, per_edge: int = DEFAULT_SAMPLES) -> Highlight | None:
    """The highlight of ``patches`` (from :func:`cs451.patching.make_patches`), or None where there is none to draw.

    None when no patch is glossy or the scene has no area light, so such a scene is drawn exactly as without
    the option.
    """
    from ...errors import InputError
    from ...patches import patch_normals

    coefficients = patch_coefficients(scene, patches.parent)
    if not (coefficients[:, 3] > 0).any():
        return None
    lights = light_samples(scene, per_edge)
    if not len(lights):
        return None
    if len(lights) > MAX_TOTAL_SAMPLES:
        raise InputError(scene.label, "options.radiosity.specular_samples",
                         f"{_area_lights(scene)} area lights × {per_edge}² samples = {len(lights)} light samples, "
                         f"more than the {MAX_TOTAL_SAMPLES} the display takes: use fewer samples per edge")
    return Highlight(patch_normals(patches.quads), coefficients, lights,
                     np.asarray(scene.camera.eye, dtype=np.float64))
