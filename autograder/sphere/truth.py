"""Independent truths for stage 1, computed on the grader's side only.

Nothing here comes from reference/: projections come from pyrender, the view
matrix from inverting a camera pose, the sphere from freeglut's formula, key
handling from the handout's table.
"""
from __future__ import annotations

import numpy as np
import trimesh

from cs451.pyrender_shim import pyrender
from cs451.scene import Camera


def perspective(params: dict) -> np.ndarray:
    """pyrender's projection for the same field of view, aspect ratio and clipping planes."""
    cam = pyrender.PerspectiveCamera(yfov=np.radians(params["fovy"]), znear=params["near"], zfar=params["far"],
                                     aspectRatio=params["aspect"])
    return cam.get_projection_matrix(1, 1)


def look_at(params: dict) -> np.ndarray:
    """The inverse of the camera-to-world pose whose -z axis looks from eye to center (pyrender's convention)."""
    eye, center, up = (np.asarray(params[k], dtype=float) for k in ("eye", "center", "up"))
    z = eye - center
    z /= np.linalg.norm(z)
    x = np.cross(up, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2], pose[:3, 3] = x, y, z, eye
    return np.linalg.inv(pose)


def freeglut_sphere_vertices(radius: float, slices: int, stacks: int) -> np.ndarray:
    """fghGenerateSphere's vertex positions (freeglut 3.x, fg_geometry.c)."""
    verts = [(0.0, 0.0, radius)]
    for i in range(1, stacks):
        t = np.pi * i / stacks
        for j in range(slices):
            p = -2 * np.pi * j / slices
            verts.append((radius * np.cos(p) * np.sin(t), radius * np.sin(p) * np.sin(t), radius * np.cos(t)))
    verts.append((0.0, 0.0, -radius))
    return np.array(verts)


def _match(a: np.ndarray, b: np.ndarray, tol: float) -> int:
    """How many points of ``a`` have no point of ``b`` within ``tol``."""
    missing = 0
    for start in range(0, len(a), 512):
        d = np.linalg.norm(a[start:start + 512, None, :] - b[None, :, :], axis=2)
        missing += int((d.min(axis=1) > tol).sum())
    return missing


def mesh_checks() -> list:
    def counts(out, p):
        n, m = p["slices"] * (p["stacks"] - 1) + 2, 2 * p["slices"] * (p["stacks"] - 1)
        got_n, got_m = len(out["positions"]), len(out["triangles"])
        if (got_n, got_m) != (n, m):
            return f"{got_n} vertices and {got_m} triangles, expected {n} and {m}"

    def normals(out, p):
        nrm, pos = np.asarray(out["normals"], float), np.asarray(out["positions"], float)
        length = np.linalg.norm(nrm, axis=1)
        if not np.allclose(length, 1.0, atol=1e-5):
            return f"normals must have unit length (found lengths from {length.min():.4g} to {length.max():.4g})"
        if not np.allclose(nrm, pos / p["radius"], atol=1e-5):
            return "normals must point straight out of the sphere (position / radius)"

    def tessellation(out, p):
        want = freeglut_sphere_vertices(p["radius"], p["slices"], p["stacks"])
        got = np.asarray(out["positions"], float)
        tol = 1e-6 * p["radius"]
        missing, extra = _match(want, got, tol), _match(got, want, tol)
        if missing or extra:
            return (f"{missing} of glutSolidSphere's vertices are missing and {extra} vertices are not on its "
                    f"rings (poles on ±z, θ = πi/stacks, φ = -2πj/slices)")

    def closed_and_outward(out, p):
        mesh = trimesh.Trimesh(np.asarray(out["positions"], float), np.asarray(out["triangles"], int), process=False)
        if not mesh.is_watertight:
            return "the surface has holes or duplicated edges (not watertight)"
        if not mesh.is_winding_consistent:
            return "triangles are not wound consistently"
        if mesh.volume <= 0:
            return "triangles are wound clockwise seen from outside (they must be counter-clockwise)"

    def no_degenerate(out, p):
        pos, tri = np.asarray(out["positions"], float), np.asarray(out["triangles"], int)
        area = 0.5 * np.linalg.norm(np.cross(pos[tri[:, 1]] - pos[tri[:, 0]], pos[tri[:, 2]] - pos[tri[:, 0]]), axis=1)
        tiny = int((area <= 1e-12 * p["radius"] ** 2).sum())
        if tiny:
            return f"{tiny} triangles have zero area"

    return [("vertex and triangle counts", counts), ("unit outward normals", normals),
            ("glutSolidSphere's vertices", tessellation), ("closed, counter-clockwise surface", closed_and_outward),
            ("no zero-area triangles", no_degenerate)]


def reshape_checks() -> list:
    def viewport(out, p):
        got = tuple(int(v) for v in out["viewport"])
        w, h = p["width"], p["height"]
        allowed = {(0, 0, w, h), (0, 0, w, max(h, 1))}
        if got not in allowed:
            return f"viewport is {got}, expected (0, 0, {w}, {max(h, 1)}) to cover the window"

    def aspect(out, p):
        proj = np.asarray(out["projection"], float)
        if not np.isfinite(proj).all():
            return "the projection has NaN or infinite entries (a division by a zero height?)"
        want = p["width"] / max(p["height"], 1)
        got = proj[1, 1] / proj[0, 0] if proj[0, 0] else np.inf
        if not np.isclose(got, want, rtol=1e-6):
            return f"the projection's aspect ratio (P[1,1]/P[0,0]) is {got:.6g}, expected width/height = {want:.6g}"

    def fovy(out, p):
        proj = np.asarray(out["projection"], float)
        want = 1 / np.tan(np.radians(Camera(**_camera(p)).fovy) / 2)
        if not np.isclose(proj[1, 1], want, rtol=1e-6):
            return f"P[1,1] is {proj[1, 1]:.6g}: the vertical field of view must stay {p['camera']['fovy']}° whatever the width"

    return [("viewport covers the window", viewport), ("aspect ratio kept", aspect), ("vertical field of view kept", fovy)]


def _camera(p: dict) -> dict:
    c = dict(p["camera"])
    return {k: tuple(v) if isinstance(v, list) else v for k, v in c.items()}


def key_truth(key: str, state: dict) -> dict:
    """The handout's table of keys (§S7)."""
    s = dict(state)
    if key in ("q", "Q", "escape"):
        s["running"] = False
    elif key == "s":
        s["shading"] = "phong" if s["shading"] == "gouraud" else "gouraud"
    elif key == "+":
        s["slices"], s["stacks"] = min(s["slices"] * 2, 256), min(s["stacks"] * 2, 256)
    elif key == "-":
        s["slices"], s["stacks"] = max(s["slices"] // 2, 4), max(s["stacks"] // 2, 4)
    return s


def key_checks() -> list:
    def make(field: str):
        def sub(out, p):
            wrong = []
            for i, (key, state) in enumerate(p["presses"]):
                want = key_truth(key, state)[field]
                got = out[field][i].item()
                if got != want:
                    wrong.append(f"key {key!r} from {field}={state[field]!r} gave {got!r}, expected {want!r}")
            return "; ".join(wrong[:3]) or None
        return sub
    return [(f"{f}", make(f)) for f in ("running", "shading", "slices", "stacks")]
