"""Independent truths for stage 1, computed on the grader's side only; never shipped to students.

Nothing here comes from reference/: projections come from pyrender, the view
matrix from inverting a camera pose, modelview transforms from trimesh, the sphere from freeglut's formula, key
handling from the handout's table. Each truth takes a test's parameters and
returns arrays (a student copy gets those arrays for the public tests, not this code).
"""
from __future__ import annotations

import numpy as np

import trimesh.transformations as tf

from cs451.pyrender_shim import pyrender
from cs451.scene import Camera


def perspective(params: dict) -> np.ndarray:
    """pyrender's projection for the same field of view, aspect ratio and clipping planes."""
    cam = pyrender.PerspectiveCamera(yfov=np.radians(params["fovy"]), znear=params["near"], zfar=params["far"],
                                     aspectRatio=params["aspect"])
    return cam.get_projection_matrix(1, 1)


def stereo_pair(params: dict) -> dict[str, np.ndarray]:
    """Both eyes' matrices as pyrender's camera of given intrinsics builds them: the same focal lengths as the
    cyclops camera, its principal point slid by the eye's offset seen on the convergence plane (a 2 × 2 image)."""
    t = np.tan(np.radians(params["fovy"]) / 2)
    half_width = params["aspect"] * params["near"] * t
    out = []
    for eye in (-1, 1):
        shift = eye * params["separation"] / 2 * params["near"] / params["convergence"]
        cam = pyrender.IntrinsicsCamera(1 / (params["aspect"] * t), 1 / t, 1 + shift / half_width, 1.0,
                                        znear=params["near"], zfar=params["far"])
        out.append(cam.get_projection_matrix(2, 2))
    return {"value": np.array(out)}


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


def _gl_matrix(name: str, *args: float) -> np.ndarray:
    """glTranslate, glRotate and glScale's matrices, from trimesh's transformations (Gohlke's transformations.py)."""
    if name == "translate":
        return tf.translation_matrix(args)
    if name == "rotate":
        return tf.rotation_matrix(np.radians(args[0]), args[1:])
    if name == "scale":
        m = np.eye(4)
        for axis, factor in zip(np.eye(3), args):
            m = m @ tf.scale_matrix(factor, direction=axis)
        return m
    raise ValueError(f"unknown call {name!r}")


def model_view_matrices(params: dict) -> np.ndarray:
    """The modelview matrix at each draw: each call's matrix on the right of the current one, push and pop on a list."""
    current, saved, drawn = np.asarray(params["view"], dtype=float), [], []
    for name, *args in params["calls"]:
        if name == "push":
            saved.append(current)
        elif name == "pop":
            current = saved.pop()
        elif name == "draw":
            drawn.append(current)
        else:
            current = current @ _gl_matrix(name, *args)
    return np.array(drawn).reshape(-1, 4, 4)


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


def sphere_mesh(params: dict) -> dict[str, np.ndarray]:
    """glutSolidSphere's vertices, and how many vertices and triangles it has."""
    r, slices, stacks = params["radius"], params["slices"], params["stacks"]
    return {"vertices": freeglut_sphere_vertices(r, slices, stacks),
            "counts": np.array([slices * (stacks - 1) + 2, 2 * slices * (stacks - 1)])}


def reshape(params: dict) -> dict[str, np.ndarray]:
    """The viewport over the whole window (height 0 counts as 1), its aspect ratio and P[1,1] = cot(fovy/2)."""
    w, h = params["width"], max(params["height"], 1)
    fovy = Camera(**_camera(params)).fovy
    return {"viewport": np.array([0, 0, w, h]), "aspect": np.array(w / h), "p11": np.array(1 / np.tan(np.radians(fovy) / 2))}


def _camera(p: dict) -> dict:
    c = dict(p["camera"])
    return {k: tuple(v) if isinstance(v, list) else v for k, v in c.items()}


def key_truth(key: str, state: dict) -> dict:
    """The handout's table of keys (§S8)."""
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


def keys(params: dict) -> dict[str, np.ndarray]:
    """The state after each press, as parallel arrays (as the probe returns them)."""
    states = [key_truth(key, state) for key, state in params["presses"]]
    return {f: np.array([s[f] for s in states]) for f in ("running", "shading", "slices", "stacks")}
