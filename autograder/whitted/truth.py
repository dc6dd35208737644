"""Independent truths for stage 2, computed on the grader's side only; never shipped to students.

Each truth takes a test's parameters and returns arrays (a student copy gets those
arrays for the public tests, not this code; ``checks.py`` compares). Nothing here comes from reference/: camera rays are checked by projecting them with
pyrender's camera, sphere and triangle hits against exact rational arithmetic
(Python's fractions), depths against pyrender's rasteriser, reflection, refraction
and Fresnel against their trigonometric forms, shadow rays against a brute-force
walk over every object, hierarchies against their definition.
"""
from __future__ import annotations

from fractions import Fraction

import numpy as np
import trimesh

from cs451 import tracescene
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


def thin_lens(p: dict) -> dict[str, np.ndarray]:
    """W12 in the camera's own frame (x right, y up, z backwards: pyrender's pose): the lens point (r cos φ, r sin φ, 0)
    and the pinhole ray scaled to depth −focus, then both turned into the world by the pose."""
    pose = _camera_pose(p["camera"])
    turn = pose[:3, :3]
    local = np.asarray(p["directions"], float) @ turn                        # the pinhole rays in camera space
    sharp = local * (float(p["focus"]) / -local[:, 2])[:, None]
    u = np.asarray(p["u"], float)
    radius = float(p["aperture"]) * np.sqrt(u[:, 0])
    lens = np.c_[radius * np.cos(2 * np.pi * u[:, 1]), radius * np.sin(2 * np.pi * u[:, 1]), np.zeros(len(u))]
    aim = sharp - lens
    aim /= np.linalg.norm(aim, axis=1, keepdims=True)
    return {"origins": lens @ turn.T + pose[:3, 3], "directions": aim @ turn.T}


# --- W1 ------------------------------------------------------------------------------------

def camera(params: dict) -> dict[str, np.ndarray]:
    """pyrender's clip-from-world matrix for the camera, and every pixel centre in NDC (rows from the top)."""
    cam, w, h = params["camera"], params["width"], params["height"]
    proj = pyrender.PerspectiveCamera(yfov=np.radians(cam["fovy"]), aspectRatio=w / h, znear=0.01,
                                      zfar=100.0).get_projection_matrix(w, h)
    view = np.linalg.inv(_camera_pose({"up": [0, 1, 0], **cam}))
    i, j = np.meshgrid(np.arange(w), np.arange(h), indexing="xy")
    ndc = np.c_[(2 * (i.ravel() + 0.5) / w - 1), (1 - 2 * (j.ravel() + 0.5) / h)]
    return {"clip_from_world": proj @ view, "ndc": ndc, "eye": np.asarray(cam["eye"], float)}


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
    if disc < 0 or (disc == 0 and b == 0):   # the handout's rule: tangent at its own origin (both roots 0) is a miss
        return np.inf, np.inf
    # t = (-b ± √disc) / a; the square root of an exact rational, to 1e-30 relative, by Newton in Fractions
    s = Fraction(np.sqrt(float(disc)))
    if s > 0:
        for _ in range(3):
            s = (s + disc / s) / 2
    return float((-b - s) / a), float((-b + s) / a)


def sphere_roots(params: dict) -> dict[str, np.ndarray]:
    """Both roots of every ray, exactly (inf on a miss)."""
    o, d = _vec(params, "origins"), _vec(params, "directions")
    roots = np.array([sphere_exact(o[i], d[i], params["center"], params["radius"]) for i in range(len(o))]).reshape(-1, 2)
    return {"t0": roots[:, 0], "t1": roots[:, 1]}


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


def triangle_hits(params: dict) -> dict[str, np.ndarray]:
    """Each ray's t on its triangle by exact arithmetic (inf: a miss), and whether it lies exactly on an edge."""
    o, d = _vec(params, "origins"), _vec(params, "directions")
    v = [np.broadcast_to(_vec(params, k), o.shape) for k in ("v0", "v1", "v2")]
    hits = [triangle_exact(o[i], d[i], v[0][i], v[1][i], v[2][i]) for i in range(len(o))]
    return {"t": np.array([t for t, _ in hits], float).reshape(-1), "edge": np.array([e for _, e in hits], bool).reshape(-1)}


# --- W4 ----------------------------------------------------------------------------------------

def hierarchy_boxes(params: dict) -> dict[str, np.ndarray]:
    """The primitives' boxes the hierarchy is built over, and a plain median split's surface-area cost over them."""
    if params.get("scene") is not None:
        lo, hi = tracescene.build(parse_scene(params["scene"], "<truth scene>")).bounds()
    else:
        lo, hi = np.asarray(params["lo"], float).reshape(-1, 3), np.asarray(params["hi"], float).reshape(-1, 3)
    return {"box_lo": lo, "box_hi": hi, "median_cost": np.array(sah_cost(*_median_bvh(lo, hi)))}


def sah_cost(lo, hi, child, start, count) -> float:
    """Summed surface area of the inner nodes plus each leaf's times its primitives, over the root's."""
    e = np.asarray(hi, float) - np.asarray(lo, float)
    area = e[:, 0] * e[:, 1] + e[:, 1] * e[:, 2] + e[:, 2] * e[:, 0]
    leaf = np.asarray(child) < 0
    return float((area[~leaf].sum() + (area[leaf] * np.asarray(count)[leaf]).sum()) / max(area[0], 1e-300))


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


def depth_range(params: dict) -> dict[str, np.ndarray]:
    """What primary visibility may be at each pixel, from pyrender's depth buffer at 3× the resolution.

    Each pixel's 3×3 sub-pixels span ±1/3 pixel around its centre (the rasteriser's depth is taken
    off the sample centre, so a range, not one value, is the truth); ``cos`` turns a ray's t into
    the depth along the view axis.
    """
    w, h = params["size"]
    sub = rasterised_depth(params["scene"], 3 * w, 3 * h).reshape(h, 3, w, 3).transpose(1, 3, 0, 2).reshape(9, -1)
    cam = params["scene"]["camera"]
    tan_y = np.tan(np.radians(cam["fovy"]) / 2)
    x = (2 * (np.arange(w) + 0.5) / w - 1) * tan_y * w / h
    y = (1 - 2 * (np.arange(h) + 0.5) / h) * tan_y
    xx, yy = np.meshgrid(x, y, indexing="xy")
    return {"raster": sub[4], "covered_any": (sub > 0).any(axis=0), "empty_any": (sub == 0).any(axis=0),
            "lo": np.where(sub > 0, sub, np.inf).min(axis=0), "hi": np.where(sub > 0, sub, -np.inf).max(axis=0),
            "cos": 1 / np.sqrt(1 + xx.ravel() ** 2 + yy.ravel() ** 2)}


# --- W6 ----------------------------------------------------------------------------------------

def shading(p: dict) -> np.ndarray:
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

def transmission(p: dict) -> np.ndarray:
    """Product of the transmittances crossed strictly between origin and target, object by object.

    A checkerboard plane crossed in one of its odd squares takes the checker material's transmittance:
    which square a point is in comes from the kit's plane frame (``TraceScene.material_at``), the one
    convention every implementation shares.
    """
    sc = parse_scene(p["scene"], "<truth scene>")
    arrays = tracescene.build(sc)
    planes = [obj for obj in sc.objects if isinstance(obj, Plane)]
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
                    if isinstance(obj, Plane) and obj.checker > 0:
                        prim = arrays.n_bounded + next(k for k, q in enumerate(planes) if q is obj)
                        square = arrays.material_at(np.array([prim]), (o[i] + t * d)[None])[0]
                        out[i] *= arrays.mat_transmittance[square]
                    else:
                        out[i] *= np.asarray(m.transmittance)
    return out


# --- W8, W9, W10: trigonometric forms --------------------------------------------------------------

def reflect(p: dict) -> np.ndarray:
    """Mirror each direction: keep its tangential part, flip its normal part (by angles, not by d − 2(d·n)n)."""
    out = []
    for d, n in zip(_vec(p, "directions"), _vec(p, "normals")):
        theta = np.arccos(np.clip(-np.dot(d, n), -1, 1))
        tangent = d + np.cos(theta) * n
        tl = np.linalg.norm(tangent)
        out.append(n * np.cos(theta) + (tangent / tl * np.sin(theta) if tl > 0 else 0))
    return np.array(out)


def refract_angles(p: dict) -> tuple[np.ndarray, np.ndarray]:
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


def refract(p: dict) -> dict[str, np.ndarray]:
    """Refracted directions (zero under total internal reflection) and the TIR mask."""
    dirs, tir = refract_angles(p)
    return {"t": dirs.reshape(-1, 3), "tir": tir.reshape(-1)}


def fresnel(p: dict) -> np.ndarray:
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
