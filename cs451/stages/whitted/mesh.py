"""The bundled 50k-triangle mesh (``cs451/scenes/rippled-torus.obj``), made by code, never downloaded.

A torus from ``trimesh.creation.torus`` (192 × 144 sections: 55,296 triangles) whose
tube radius ripples with the angles, so the surface has detail at every scale.
``python -m cs451.stages.whitted.mesh`` rewrites the OBJ; a test checks the
committed file is what this code makes.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ...scene import BUNDLED_DIR

TORUS_OBJ = BUNDLED_DIR / "rippled-torus.obj"
MAJOR, MINOR, SECTIONS = 1.0, 0.38, (192, 144)


def rippled_torus():
    """The mesh as a trimesh.Trimesh (z is the torus's axis)."""
    import trimesh
    mesh = trimesh.creation.torus(major_radius=MAJOR, minor_radius=MINOR, major_sections=SECTIONS[0],
                                  minor_sections=SECTIONS[1])
    v = np.asarray(mesh.vertices, dtype=np.float64)
    phi = np.arctan2(v[:, 1], v[:, 0])                       # around the axis
    ring = np.column_stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)]) * MAJOR
    tube = v - ring
    theta = np.arctan2(tube[:, 2], np.einsum("ij,ij->i", tube, ring / MAJOR))
    scale = 1.0 + 0.18 * np.sin(7 * phi) * np.cos(3 * theta) + 0.05 * np.sin(23 * phi + 5 * theta)
    return trimesh.Trimesh(ring + tube * scale[:, None], mesh.faces, process=False)


def obj_text() -> str:
    """The mesh as OBJ text, six decimals a coordinate: what ``rippled-torus.obj`` must hold (a test compares the
    committed file with it)."""
    mesh = rippled_torus()
    lines = ["# rippled torus made by cs451/stages/whitted/mesh.py (do not edit)"]
    lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in mesh.vertices]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in mesh.faces]
    return "\n".join(lines) + "\n"


def write(path: Path = TORUS_OBJ) -> Path:
    """Write :func:`obj_text` to ``path`` (the bundled OBJ unless told) and return the path."""
    path.write_text(obj_text())
    return path


if __name__ == "__main__":
    print(f"wrote {write()}")
