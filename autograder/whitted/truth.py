"""Independent truths for stage 2, computed on the grader's side only.

Nothing here comes from reference/: camera rays are checked by projecting them with
pyrender's camera, sphere and triangle hits against exact rational arithmetic
(Python's fractions), depths against pyrender's rasteriser, reflection, refraction
and Fresnel against their trigonometric forms, shadow rays against a brute-force
walk over every object, hierarchies against their definition.
"""
from __future__ import annotations

from fractions import Fraction

import numpy as np
import trimesh

from cs451 import raytrace
from cs451.pyrender_shim import pyrender
from cs451.scene import Mesh, Plane, Polygon, Sphere, parse_scene


def _vec(p: dict, key: str) -> np.ndarray:
    return np.asarray(p[key], dtype=np.float64).reshape(-1, 3)


def _camera_pose(camera: dict) -> np.ndarray:
    eye, center, up = (np.asarray(camera[k], float) for k in ("eye", "center", "up"))
    z = eye - center
    z /= np.linalg.norm(z)
    x = np.cross(up, z)
    x /= np.linalg.norm(x)
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2], pose[:3, 3] = x, np.cross(z, x), z, eye
    return pose


# --- W1 ------------------------------------------------------------------------------------

def camera_checks() -> list:
    def origins(out, p):
        eye = np.asarray(p["camera"]["eye"], float)
        if not np.allclose(out["origins"], eye, rtol=1e-9, atol=1e-9 * (1 + np.abs(eye).max())):
            return "every ray must start at the eye"

    def unit(out, p):
        length = np.linalg.norm(out["directions"], axis=1)
        if not np.allclose(length, 1.0, atol=1e-9):
            return f"directions must be unit vectors (lengths from {length.min():.6g} to {length.max():.6g})"

    def through_pixel_centres(out, p):
        cam, w, h = p["camera"], p["width"], p["height"]
        proj = pyrender.PerspectiveCamera(yfov=np.radians(cam["fovy"]), aspectRatio=w / h, znear=0.01,
                                          zfar=100.0).get_projection_matrix(w, h)
        view = np.linalg.inv(_camera_pose(cam))
        d = np.asarray(out["directions"], float)
        eye = np.asarray(cam["eye"], float)
        # a point along each ray, taken 1 unit in front of the eye (so near/far do not matter)
        x = np.c_[eye + d, np.ones(len(d))] @ (proj @ view).T
        if np.any(x[:, 3] <= 0):
            return "some rays point behind the camera"
        ndc = x[:, :2] / x[:, 3:4]
        i, j = np.meshgrid(np.arange(w), np.arange(h), indexing="xy")
        want = np.c_[(2 * (i.ravel() + 0.5) / w - 1), (1 - 2 * (j.ravel() + 0.5) / h)]
        err = np.abs(ndc - want).max(axis=1)
        if err.max() > 1e-6:
            k = int(np.argmax(err))
            return (f"ray {k} (column {k % w}, row {k // w}) goes through NDC {ndc[k].round(5).tolist()}, "
                    f"expected the pixel centre {want[k].round(5).tolist()} (rows from the top)")

    return [("origins at the eye", origins), ("unit directions", unit),
            ("through pixel centres (pyrender's camera)", through_pixel_centres)]


# --- W2, W3: exact rational arithmetic ---------------------------------------------------------

def _frac(v) -> list[Fraction]:
    return [Fraction(float(x)) for x in v]


def sphere_exact(o, d, c, r) -> tuple[float, float]:
    """Roots of |o + t d - c|² = r², from exact rationals (the square root taken in float at the end)."""
    o, d, c, r = _frac(o), _frac(d), _frac(c), Fraction(float(r))
    f = [a - b for a, b in zip(o, c)]
    a = sum(x * x for x in d)
    b = sum(x * y for x, y in zip(f, d))
    cc = sum(x * x for x in f) - r * r
    disc = b * b - a * cc
    if disc < 0:
        return np.inf, np.inf
    # t = (-b ± √disc) / a; the square root of an exact rational, to 1e-30 relative, by Newton in Fractions
    s = Fraction(np.sqrt(float(disc)))
    if s > 0:
        for _ in range(3):
            s = (s + disc / s) / 2
    return float((-b - s) / a), float((-b + s) / a)


def sphere_checks(rel: float = 1e-9) -> list:
    def roots(out, p):
        o, d = _vec(p, "origins"), _vec(p, "directions")
        bad = []
        for i in range(len(o)):
            want = sphere_exact(o[i], d[i], p["center"], p["radius"])
            got = (float(out["t0"][i]), float(out["t1"][i]))
            if np.isinf(want[0]) != np.isinf(got[0]) or np.isinf(want[1]) != np.isinf(got[1]):
                bad.append(f"ray {i}: {'a miss' if np.isinf(want[0]) else 'a hit'} expected, got t = {got}")
                continue
            if not np.isinf(want[0]):
                scale = rel * max(abs(want[1]), p["radius"])
                if abs(got[0] - want[0]) > scale or abs(got[1] - want[1]) > scale:
                    bad.append(f"ray {i}: t = ({got[0]:.12g}, {got[1]:.12g}), exact ({want[0]:.12g}, {want[1]:.12g})")
        return "; ".join(bad[:3]) + (f" (and {len(bad) - 3} more)" if len(bad) > 3 else "") if bad else None
    return [("both roots, smaller first, inf on a miss", roots)]


def triangle_exact(o, d, v0, v1, v2) -> tuple[float, bool]:
    """(t, on_boundary) by exact rational arithmetic; t is inf for a miss or a degenerate triangle."""
    o, d, v0, v1, v2 = (_frac(x) for x in (o, d, v0, v1, v2))
    e1 = [b - a for a, b in zip(v0, v1)]
    e2 = [b - a for a, b in zip(v0, v2)]

    def cross(a, b):
        return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]

    def dot(a, b):
        return sum(x * y for x, y in zip(a, b))

    pv = cross(d, e2)
    det = dot(e1, pv)
    if det == 0 or all(x == 0 for x in cross(e1, e2)):
        return np.inf, False
    tv = [a - b for a, b in zip(o, v0)]
    u = dot(tv, pv) / det
    qv = cross(tv, e1)
    v = dot(d, qv) / det
    t = dot(e2, qv) / det
    if u < 0 or v < 0 or u + v > 1 or t <= 0:
        return np.inf, False
    return float(t), (u == 0 or v == 0 or u + v == 1)


def triangle_checks(rel: float = 1e-9) -> list:
    def hits(out, p):
        o, d = _vec(p, "origins"), _vec(p, "directions")
        v = [np.broadcast_to(_vec(p, k), o.shape) for k in ("v0", "v1", "v2")]
        bad = []
        for i in range(len(o)):
            want, edge = triangle_exact(o[i], d[i], v[0][i], v[1][i], v[2][i])
            got = float(out["t"][i])
            if edge:
                continue  # exactly on an edge: either answer is right here (the watertight test checks edges)
            if np.isinf(want) != np.isinf(got) or (not np.isinf(want) and abs(got - want) > rel * max(1.0, abs(want))):
                bad.append(f"ray {i}: t = {got:.12g}, exact {want:.12g}")
        return "; ".join(bad[:3]) + (f" (and {len(bad) - 3} more)" if len(bad) > 3 else "") if bad else None
    return [("hits and misses against exact arithmetic", hits)]


def watertight_checks() -> list:
    """Rays through the shared edges and vertices of a fan: each ray is paired with every triangle."""
    def no_gaps(out, p):
        t = np.asarray(out["t"], float).reshape(p["rays"], p["triangles"])
        leaks = int((~np.isfinite(t).any(axis=1)).sum())
        if leaks:
            return f"{leaks} of {p['rays']} rays through shared edges or vertices hit none of the triangles (a gap)"
    return [("no ray slips between triangles", no_gaps)]


# --- W4 ----------------------------------------------------------------------------------------

def bvh_checks(max_depth: int = 64) -> list:
    def valid(out, p):
        problems = raytrace.bvh_problems({k: out[k] for k in raytrace.BVH_KEYS}, out["box_lo"], out["box_hi"])
        return "; ".join(problems[:3]) or None

    def root(out, p):
        lo, hi = np.asarray(out["box_lo"]), np.asarray(out["box_hi"])
        if not (np.allclose(out["lo"][0], lo.min(axis=0)) and np.allclose(out["hi"][0], hi.max(axis=0))):
            return "node 0 must be the root, whose box is the union of all primitives' boxes"

    def shallow(out, p):
        if raytrace.bvh_problems({k: out[k] for k in raytrace.BVH_KEYS}, out["box_lo"], out["box_hi"]):
            return "not a valid hierarchy (see above)"
        depth = raytrace.bvh_depth({k: out[k] for k in raytrace.BVH_KEYS})
        n = len(out["box_lo"])
        if depth > max_depth:
            return f"depth {depth} for {n} primitives (at most {max_depth}: split the boxes, do not peel them one by one)"

    def tight(out, p):
        """A good split keeps children's boxes small: the summed surface area of the leaves, against a median split's."""
        if raytrace.bvh_problems({k: out[k] for k in raytrace.BVH_KEYS}, out["box_lo"], out["box_hi"]):
            return "not a valid hierarchy (see above)"
        def sah(lo, hi, child, start, count):
            e = hi - lo
            area = e[:, 0] * e[:, 1] + e[:, 1] * e[:, 2] + e[:, 2] * e[:, 0]
            leaf = child < 0
            return (area[~leaf].sum() + (area[leaf] * count[leaf]).sum()) / max(area[0], 1e-300)
        got = sah(out["lo"], out["hi"], out["child"], out["start"], out["count"])
        ref = sah(*_median_bvh(np.asarray(out["box_lo"]), np.asarray(out["box_hi"])))
        if got > 1.5 * ref:
            return f"surface-area cost {got:.1f}, more than 1.5× a plain median split's {ref:.1f}: rays will visit many nodes"

    return [("a valid hierarchy", valid), ("node 0 is the root", root), ("depth", shallow), ("tight boxes", tight)]


def _median_bvh(lo: np.ndarray, hi: np.ndarray, leaf: int = 4):
    """A median split along the widest axis of the centroids: the yardstick for `tight`."""
    cen = 0.5 * (lo + hi)
    nlo, nhi, child, start, count = [], [], [], [], []

    def node(ids: np.ndarray) -> int:
        k = len(child)
        nlo.append(lo[ids].min(axis=0))
        nhi.append(hi[ids].max(axis=0))
        child.append(-1)
        start.append(0)
        count.append(len(ids))
        return k

    todo = [(node(np.arange(len(lo))), np.arange(len(lo)))]
    while todo:
        k, ids = todo.pop()
        if len(ids) <= leaf:
            continue
        axis = int(np.argmax(np.ptp(cen[ids], axis=0)))
        ids = ids[np.argsort(cen[ids, axis], kind="stable")]
        half = len(ids) // 2
        a = node(ids[:half])
        node(ids[half:])
        child[k] = a
        todo += [(a, ids[:half]), (a + 1, ids[half:])]
    return np.array(nlo), np.array(nhi), np.array(child), np.array(start), np.array(count)


# --- W5: primary visibility against a rasteriser ---------------------------------------------------

def rasterised_depth(scene: dict, width: int, height: int) -> np.ndarray:
    """pyrender's depth (distance along the view axis; 0 where empty) of the scene's triangles and polygons."""
    sc = parse_scene(scene, "<truth scene>")
    verts, faces = [], []
    for obj in sc.objects:
        if isinstance(obj, Polygon):
            v = np.asarray(obj.vertices, float)
            base = sum(len(x) for x in verts)
            verts.append(v)
            faces += [[base, base + j, base + j + 1] for j in range(1, len(v) - 1)]
        elif isinstance(obj, (Sphere, Plane, Mesh)):
            raise ValueError("the depth truth rasterises polygons only (spheres and planes are not exact as meshes)")
    mesh = trimesh.Trimesh(np.concatenate(verts), np.asarray(faces), process=False)
    cam = sc.camera
    world = pyrender.Scene()
    world.add(pyrender.Mesh.from_trimesh(mesh, smooth=False, material=pyrender.MetallicRoughnessMaterial(doubleSided=True)))
    world.add(pyrender.PerspectiveCamera(yfov=np.radians(cam.fovy), aspectRatio=width / height, znear=cam.near, zfar=cam.far),
              pose=_camera_pose({"eye": cam.eye, "center": cam.center, "up": cam.up}))
    renderer = pyrender.OffscreenRenderer(width, height)
    try:
        return renderer.render(world, flags=pyrender.RenderFlags.DEPTH_ONLY).astype(np.float64)
    finally:
        renderer.delete()


def depth_checks(rel: float = 5e-3, max_bad: float = 0.02) -> list:
    def visibility(out, p):
        w, h = p["size"]
        # pyrender at 3× the resolution: each pixel's 3×3 sub-pixels span ±1/3 pixel around its centre (its
        # multisampled depth is taken off the sample centre, so a range, not one value, is the truth)
        sub = rasterised_depth(p["scene"], 3 * w, 3 * h).reshape(h, 3, w, 3).transpose(1, 3, 0, 2).reshape(9, -1)
        raster = sub[4]
        cam = p["scene"]["camera"]
        t = np.asarray(out["t"], float)
        hit = np.isfinite(t)
        width, height = w, h
        tan_y = np.tan(np.radians(cam["fovy"]) / 2)
        x = (2 * (np.arange(width) + 0.5) / width - 1) * tan_y * width / height
        y = (1 - 2 * (np.arange(height) + 0.5) / height) * tan_y
        xx, yy = np.meshgrid(x, y, indexing="xy")
        cos = 1 / np.sqrt(1 + xx.ravel() ** 2 + yy.ravel() ** 2)
        depth = np.where(hit, t * cos, 0.0)
        covered_any, empty_any = (sub > 0).any(axis=0), (sub == 0).any(axis=0)
        lo = np.where(sub > 0, sub, np.inf).min(axis=0)
        hi = np.where(sub > 0, sub, -np.inf).max(axis=0)
        mismatch = (hit & ~covered_any) | (~hit & ~empty_any)
        both = hit & covered_any
        mismatch |= both & ((depth < lo * (1 - rel)) | (depth > hi * (1 + rel)))
        frac = float(mismatch.mean())
        if frac > max_bad:
            k = int(np.argmax(mismatch))
            return (f"{frac:.1%} of pixels disagree with pyrender's depth buffer (allowed {max_bad:.0%}); e.g. pixel "
                    f"{k % w},{k // w}: your depth {depth[k]:.6g}, rasterised {raster[k]:.6g}")

    def normals(out, p):
        n = np.asarray(out["normals"], float)
        hit = np.isfinite(np.asarray(out["t"], float))
        length = np.linalg.norm(n[hit], axis=1)
        if hit.any() and not np.allclose(length, 1.0, atol=1e-6):
            return "normals at hits must be unit vectors"

    return [("primary visibility matches a rasteriser", visibility), ("unit normals", normals)]


# --- W6 ----------------------------------------------------------------------------------------

def shading_truth(p: dict) -> np.ndarray:
    """Lambert plus Blinn-Phong, one point at a time, written from the formula with angles."""
    out = []
    for i in range(len(p["normals"])):
        n, v, l = (np.asarray(p[k][i], float) for k in ("normals", "to_eye", "to_light"))
        cos_l = float(np.dot(n, l))
        colour = np.asarray(p["diffuse"][i]) * np.asarray(p["light_diffuse"][i]) * max(cos_l, 0.0)
        if cos_l > 0:
            half = (l + v) / np.linalg.norm(l + v)
            colour = colour + np.asarray(p["specular"][i]) * np.asarray(p["light_specular"][i]) * \
                max(float(np.dot(n, half)), 0.0) ** p["shininess"][i]
        out.append(colour)
    return np.array(out)


# --- W7: a brute-force walk over every object ------------------------------------------------------

def transmission_truth(p: dict) -> np.ndarray:
    """Product of the transmittances crossed strictly between origin and target, object by object."""
    sc = parse_scene(p["scene"], "<truth scene>")
    o, x = _vec(p, "origins"), _vec(p, "targets")
    out = np.ones((len(o), 3))
    for i in range(len(o)):
        seg = x[i] - o[i]
        length = np.linalg.norm(seg)
        d = seg / length
        for obj in sc.objects:
            m = sc.material(obj.material)
            ts: list[float] = []
            if isinstance(obj, Sphere):
                t0, t1 = sphere_exact(o[i], d, obj.center, obj.radius)
                ts = [t for t in (t0, t1) if np.isfinite(t)]
            elif isinstance(obj, Plane):
                n = np.asarray(obj.normal, float)
                dn = float(np.dot(d, n))
                if dn != 0:
                    ts = [float(np.dot(np.asarray(obj.point) - o[i], n) / dn)]
            elif isinstance(obj, Polygon):
                v = np.asarray(obj.vertices, float)
                for j in range(1, len(v) - 1):
                    t, _ = triangle_exact(o[i], d, v[0], v[j], v[j + 1])
                    if np.isfinite(t):
                        ts.append(t)
            for t in ts:
                if 0 < t < length:
                    out[i] *= np.asarray(m.transmittance)
    return out


# --- W8, W9, W10: trigonometric forms --------------------------------------------------------------

def reflect_truth(p: dict) -> np.ndarray:
    """Mirror each direction: keep its tangential part, flip its normal part (by angles, not by d − 2(d·n)n)."""
    out = []
    for d, n in zip(_vec(p, "directions"), _vec(p, "normals")):
        theta = np.arccos(np.clip(-np.dot(d, n), -1, 1))
        tangent = d + np.cos(theta) * n
        tl = np.linalg.norm(tangent)
        out.append(n * np.cos(theta) + (tangent / tl * np.sin(theta) if tl > 0 else 0))
    return np.array(out)


def refract_truth(p: dict) -> tuple[np.ndarray, np.ndarray]:
    """Snell's law by angles: sin θt = η sin θi, in the plane of d and n."""
    d_all, n_all = _vec(p, "directions"), _vec(p, "normals")
    eta = np.broadcast_to(np.asarray(p["eta"], float), (len(d_all),))
    dirs, tir = [], []
    for d, n, e in zip(d_all, n_all, eta):
        theta_i = np.arccos(np.clip(-np.dot(d, n), -1, 1))
        s = e * np.sin(theta_i)
        if s > 1:
            dirs.append(np.zeros(3))
            tir.append(True)
            continue
        theta_t = np.arcsin(s)
        tangent = d + np.cos(theta_i) * n
        tl = np.linalg.norm(tangent)
        dirs.append(-n * np.cos(theta_t) + (tangent / tl * np.sin(theta_t) if tl > 0 else 0))
        tir.append(False)
    return np.array(dirs), np.array(tir)


def refract_checks(atol: float = 1e-9) -> list:
    def mask(out, p):
        _, tir = refract_truth(p)
        got = np.asarray(out["tir"], bool)
        if not np.array_equal(got, tir):
            i = int(np.argmax(got != tir))
            return f"ray {i}: total internal reflection is {bool(got[i])}, expected {bool(tir[i])}"

    def directions(out, p):
        want, tir = refract_truth(p)
        got = np.asarray(out["t"], float)
        err = np.abs(got - want).max(axis=1)
        err[tir] = 0
        if err.max() > atol:
            i = int(np.argmax(err))
            return f"ray {i}: refracted direction {got[i].round(9).tolist()}, expected {want[i].round(9).tolist()}"

    return [("total internal reflection", mask), ("refracted directions", directions)]


def fresnel_truth(p: dict) -> np.ndarray:
    """Fresnel's equations in their sine and tangent form: r_s = −sin(θi−θt)/sin(θi+θt), r_p = tan(θi−θt)/tan(θi+θt)."""
    cos_i = np.asarray(p["cos_i"], float)
    eta = np.broadcast_to(np.asarray(p["eta"], float), cos_i.shape)
    out = []
    for c, e in zip(cos_i, eta):
        ti = np.arccos(np.clip(c, 0, 1))
        s = e * np.sin(ti)
        if s >= 1:
            out.append(1.0)
            continue
        tt = np.arcsin(s)
        if ti == 0:  # normal incidence: the limit ((η − 1)/(η + 1))²
            out.append(((e - 1) / (e + 1)) ** 2)
            continue
        rs = np.sin(ti - tt) / np.sin(ti + tt)
        rp = np.tan(ti - tt) / np.tan(ti + tt) if abs(ti + tt - np.pi / 2) > 1e-12 else 0.0
        out.append(0.5 * (rs * rs + rp * rp))
    return np.array(out)
