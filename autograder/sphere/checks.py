"""Stage 1's checks: they compare a submission's arrays with the truths' (``expected``) and compute no answer.

Shipped to students with the public tests; the answers themselves come from
``truth.py`` (never shipped) or, in a student copy, from its packaged arrays.
"""
from __future__ import annotations

import numpy as np
import trimesh

from cs451.grading.checks import output
from cs451.stages.sphere import tolerances as TOL


def _match(a: np.ndarray, b: np.ndarray, tol: float) -> int:
    """How many points of ``a`` have no point of ``b`` within ``tol``."""
    missing = 0
    for start in range(0, len(a), 512):
        d = np.linalg.norm(a[start:start + 512, None, :] - b[None, :, :], axis=2)
        missing += int((d.min(axis=1) > tol).sum()) if len(b) else len(d)
    return missing


def _mesh(out, expected):
    n, m = (int(c) for c in expected["counts"])
    pos = output(out, "positions", (None, 3))
    tri = output(out, "triangles", (None, 3))
    nrm = output(out, "normals", (len(pos), 3))
    return n, m, pos, nrm, tri


def mesh_counts(out, expected, p):
    n, m, pos, _, tri = _mesh(out, expected)
    if (len(pos), len(tri)) != (n, m):
        return f"{len(pos)} vertices and {len(tri)} triangles, expected {n} and {m}"


def mesh_normals(out, expected, p):
    _, _, pos, nrm, _ = _mesh(out, expected)
    length = np.linalg.norm(nrm, axis=1)
    if not np.allclose(length, 1.0, atol=TOL.UNIT):
        return f"normals must have unit length (found lengths from {length.min():.4g} to {length.max():.4g})"
    if not np.allclose(nrm, pos / p["radius"], atol=TOL.UNIT):
        return "normals must point straight out of the sphere (position / radius)"


def mesh_vertices(out, expected, p):
    n, _, pos, _, _ = _mesh(out, expected)
    if len(pos) > 4 * n:
        return f"{len(pos)} vertices, far more than glutSolidSphere's {n}"
    want = np.asarray(expected["vertices"], float)
    tol = TOL.POSITION * p["radius"]
    missing, extra = _match(want, pos, tol), _match(pos, want, tol)
    if missing or extra:
        return (f"{missing} of glutSolidSphere's vertices are missing and {extra} vertices are not on its "
                f"rings (poles on ±z, θ = πi/stacks, φ = -2πj/slices)")


def mesh_closed(out, expected, p):
    _, m, pos, _, tri = _mesh(out, expected)
    if len(tri) > 4 * m or (len(tri) and (tri.min() < 0 or tri.max() >= len(pos) or not np.all(tri == np.round(tri)))):
        return "triangles must index the vertices (0 .. n-1)"
    mesh = trimesh.Trimesh(pos, tri.astype(np.int64), process=False)
    if not mesh.is_watertight:
        return "the surface has holes or duplicated edges (not watertight)"
    if not mesh.is_winding_consistent:
        return "triangles are not wound consistently"
    if mesh.volume <= 0:
        return "triangles are wound clockwise seen from outside (they must be counter-clockwise)"


def mesh_no_degenerate(out, expected, p):
    _, m, pos, _, tri = _mesh(out, expected)
    if len(tri) > 4 * m or (len(tri) and (tri.min() < 0 or tri.max() >= len(pos))):
        return "triangles must index the vertices (0 .. n-1)"
    t = tri.astype(np.int64)
    area = 0.5 * np.linalg.norm(np.cross(pos[t[:, 1]] - pos[t[:, 0]], pos[t[:, 2]] - pos[t[:, 0]]), axis=1)
    tiny = int((area <= TOL.DEGENERATE * p["radius"] ** 2).sum())
    if tiny:
        return f"{tiny} triangles have zero area"


def reshape_viewport(out, expected, p):
    """The viewport covers the window; for a window of height 0 both ``(0, 0, w, 0)`` (what the notes' program
    passes to glViewport, legal GL) and ``(0, 0, w, 1)`` (the height the projection uses) do (handout §S7)."""
    got = tuple(int(v) for v in output(out, "viewport", (4,), "the viewport"))
    want = tuple(int(v) for v in expected["viewport"])
    allowed = [want]
    if int(p.get("height", -1)) == 0:
        allowed = [(*want[:3], 0), (*want[:3], 1)]
    if got not in allowed:
        return f"viewport is {got}, expected {' or '.join(map(str, allowed))} to cover the window"


def _projection(out):
    proj = output(out, "projection", (4, 4), "the projection")
    if not np.isfinite(proj).all():
        raise ValueError("the projection has NaN or infinite entries (a division by a zero height?)")
    return proj


def reshape_aspect(out, expected, p):
    proj = _projection(out)
    want = float(expected["aspect"])
    got = proj[1, 1] / proj[0, 0] if proj[0, 0] else np.inf
    if not np.isclose(got, want, rtol=TOL.PROJECTION):
        return f"the projection's aspect ratio (P[1,1]/P[0,0]) is {got:.6g}, expected width/height = {want:.6g}"


def reshape_fovy(out, expected, p):
    proj = _projection(out)
    want = float(expected["p11"])
    if not np.isclose(proj[1, 1], want, rtol=TOL.PROJECTION):
        return f"P[1,1] is {proj[1, 1]:.6g}: the vertical field of view must stay {p['camera']['fovy']}° whatever the width"


def key_press(out, expected, p, index: int):
    """Press ``index`` gives the state the handout's table says (every field)."""
    key, state = p["presses"][index]
    wrong = []
    for field in ("running", "shading", "slices", "stacks"):
        got = np.asarray(out[field])
        if got.shape != (len(p["presses"]),):
            return f"{field} has shape {got.shape}, expected one value per press"
        want = expected[field][index].item()
        if got[index].item() != want:
            wrong.append(f"{field}={got[index].item()!r}, expected {want!r}")
    if wrong:
        return f"key {key!r} from {state}: " + ", ".join(wrong)


def stereo_zero_parallax(out, expected, p):
    """Points on the convergence plane land on the same spot in both eyes' images; the eyes sit ∓separation/2
    along x, so a point's x in an eye's view space is its cyclops x minus the eye's offset (handout §S9)."""
    pair = output(out, "matrices", (2, 4, 4), "the two matrices")
    rng = np.random.default_rng(0)
    depth = float(p["convergence"])
    points = np.c_[rng.uniform(-1, 1, (16, 2)) * depth, np.full(16, -depth), np.ones(16)]
    ndc = []
    for matrix, eye in zip(pair, (-1, 1)):
        seen = points - [eye * float(p["separation"]) / 2, 0, 0, 0]
        clip = seen @ matrix.T
        ndc.append(clip[:, :2] / clip[:, 3:])
    worst = float(np.abs(ndc[0] - ndc[1]).max())
    if not worst <= TOL.MATRIX_RTOL:
        return (f"a point on the convergence plane lands {worst:.3g} apart (NDC) in the two images: each eye's "
                "window must be slid so that both meet there")
