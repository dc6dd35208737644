"""W6, W7: local shading at a point under one light, and how much of a light reaches a point."""
from __future__ import annotations

import numpy as np

from cs451.tracescene import TraceScene


def local_shading(normals, to_eye, to_light, light_diffuse, light_specular, diffuse, specular, shininess) -> np.ndarray:
    """The light one light reflects toward the eye: diffuse (Lambert) plus specular (Blinn-Phong), (n, 3).

    ``normals``, ``to_eye``, ``to_light``: (n, 3) unit vectors from the surface point;
    ``light_diffuse``, ``light_specular``: (n, 3) light arriving at the point;
    ``diffuse``, ``specular``: (n, 3) the material's kd and ks; ``shininess``: (n,).
    c = kd·Ld·max(n·l, 0) + ks·Ls·max(n·h, 0)^shininess with h = norm(l + v), and the
    specular term only where n·l > 0.
    """
    # BEGIN SOLUTION W6: Lambert plus Blinn-Phong, as OpenGL 1.x's lighting equation (handout §W6)
    n, v, l = (np.asarray(a, dtype=np.float64) for a in (normals, to_eye, to_light))
    n_dot_l = np.einsum("ij,ij->i", n, l)
    h = l + v
    h /= np.maximum(np.linalg.norm(h, axis=1, keepdims=True), 1e-300)
    n_dot_h = np.maximum(np.einsum("ij,ij->i", n, h), 0.0)
    lit = n_dot_l > 0
    spec = np.where(lit, n_dot_h ** np.asarray(shininess, dtype=np.float64), 0.0)
    return (np.asarray(diffuse) * np.asarray(light_diffuse) * np.maximum(n_dot_l, 0.0)[:, None]
            + np.asarray(specular) * np.asarray(light_specular) * spec[:, None])
    # END SOLUTION


def shadow_transmission(scene: TraceScene, origins: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """How much light gets from each target (a light) to each origin (n, 3): an RGB factor (n, 3) in [0, 1].

    Shadow rays run from ``origins`` (already moved off their surface) toward ``targets``.
    Every surface crossed strictly between them multiplies the factor by the ``transmittance``
    of the material at the crossing point (``scene.material_at``: a checkerboard's squares
    differ): an opaque one (transmittance 0) blocks the light, a glass one only dims it (a
    sphere is crossed twice). Any hit ends the search for an opaque blocker:
    no need for the closest one. Adds the rays to ``scene.counters["shadow"]``.
    """
    # BEGIN SOLUTION W7: any-hit traversal that multiplies transmittances and stops at an opaque blocker (handout §W7)
    from .wavefront import transmission as transmission_numpy
    o = np.ascontiguousarray(origins, dtype=np.float64)
    seg = np.asarray(targets, dtype=np.float64) - o
    dist = np.linalg.norm(seg, axis=1)
    d = np.ascontiguousarray(seg / np.where(dist > 0, dist, 1.0)[:, None])
    out, nodes, tests = transmission_numpy(scene, o, d, dist)
    scene.counters["shadow"] += len(o)
    scene.counters["nodes_visited"] += int(nodes)
    scene.counters["tests"] += int(tests)
    return out
    # END SOLUTION
