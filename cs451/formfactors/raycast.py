"""Form factors by Monte Carlo ray casting on Embree (an optional peer), to compare the hemicube with."""
from __future__ import annotations

from typing import Any, Iterable

import numpy as np

from ..errors import KitError
from ..patches import as_quads, patch_centers, patch_normals, patch_triangles


def formfactor_matrix_raycast(quads: Any, samples: int, seed: int = 0, rows: Iterable[int] | None = None,
                              origin: str = "area") -> np.ndarray:
    """Form factors by Monte Carlo ray casting (Embree through embreex): ``samples`` cosine-weighted rays per patch.

    Each ray leaves patch i in a cosine-distributed direction about its normal, from a
    uniformly random point of the patch (``origin="area"``: estimates the true F_ij, the
    area average) or from its centre (``origin="center"``: estimates what a hemicube
    computes, the form factor of the centre's differential area). F_ij is the fraction of
    i's rays whose first hit is the front of patch j (a back face absorbs the ray, as in
    the hemicube). Unbiased; the standard error of F_ij is sqrt(F_ij (1 - F_ij) / samples).
    Returns (len(rows), n).
    """
    if origin not in ("area", "center"):
        raise KitError(f"origin must be 'area' or 'center', got {origin!r}")
    try:
        import embreex.mesh_construction as mc
        import embreex.rtcore_scene as rtcs
    except ImportError:
        raise KitError("ray casting runs on Embree, an optional peer: pip install -e '.[peers]'") from None

    q = as_quads(quads)
    n = len(q)
    rows = list(range(n)) if rows is None else [int(i) for i in rows]
    tris, ids = patch_triangles(q)
    scene = rtcs.EmbreeScene()
    mc.TriangleMesh(scene, tris.astype(np.float32))
    normals, centers = patch_normals(q), patch_centers(q)
    rng = np.random.default_rng(seed)
    out = np.zeros((len(rows), n))
    chunk = max(1, 2_000_000 // max(samples, 1))
    tri_area = 0.5 * np.linalg.norm(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]), axis=1)
    for start in range(0, len(rows), chunk):
        block = rows[start:start + chunk]
        m = len(block)
        b = np.repeat(np.array(block), samples)
        start_at, d = cosine_rays(tris, tri_area, normals, b, rng, centers if origin == "center" else None)
        hit = scene.run(start_at.astype(np.float32), d.astype(np.float32))
        hit = np.asarray(hit)
        valid = hit >= 0
        j = ids[np.where(valid, hit, 0)]
        front = valid & (np.einsum("ij,ij->i", d, normals[j]) < 0)
        key = np.repeat(np.arange(m), samples)[front] * n + j[front]
        out[start:start + m] = np.bincount(key, minlength=m * n).reshape(m, n) / samples
    return out


def cosine_rays(tris: np.ndarray, tri_area: np.ndarray, normals: np.ndarray, b: np.ndarray,
                rng: np.random.Generator, centers: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Rays leaving patches ``b`` (indices into quads split as triangles 2i and 2i + 1): from a uniform point of
    the patch (one of its two triangles picked by area, then a uniform point in it), or from its centre where
    ``centers`` is given, in a cosine-weighted direction about its normal. The start is lifted off the surface by
    a distance that grows with |p|, so the ray cannot hit its own patch. Returns (origins, directions)."""
    a0, a1 = tri_area[2 * b], tri_area[2 * b + 1]
    t = 2 * b + (rng.random(len(b)) * (a0 + a1) >= a0)
    r1, r2 = rng.random(len(b)), rng.random(len(b))
    s1 = np.sqrt(r1)
    p = (1 - s1)[:, None] * tris[t, 0] + (s1 * (1 - r2))[:, None] * tris[t, 1] + (s1 * r2)[:, None] * tris[t, 2]
    if centers is not None:
        p = centers[b]
    nrm = normals[b]
    tangent = np.cross(nrm, np.where(np.abs(nrm[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]]))
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    bitangent = np.cross(nrm, tangent)
    u1, u2 = rng.random(len(b)), rng.random(len(b))
    rad, phi = np.sqrt(u1), 2 * np.pi * u2
    d = (rad * np.cos(phi))[:, None] * tangent + (rad * np.sin(phi))[:, None] * bitangent + np.sqrt(1 - u1)[:, None] * nrm
    return p + nrm * (1e-5 * (1 + np.abs(p).max(axis=1)))[:, None], d
