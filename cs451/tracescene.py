"""Stage 2's scaffolding: a scene as flat arrays a vectorised ray tracer reads, and trusted helpers.

Nothing here traces a ray. :func:`build` turns a validated :class:`~cs451.scene.Scene`
into a :class:`TraceScene`: primitives (spheres, triangles from polygons and OBJ
meshes, infinite planes) numbered in one sequence, materials as arrays indexed by
material number, and every light as point samples (an area light becomes a
stratified grid of samples, seeded, so every implementation sees the same ones).
The student's functions (``reference/whitted``) read these arrays.

Two helpers are given, not written by students: :func:`spawn` (offsetting a
secondary ray's origin off the surface by a distance that scales with the
coordinates, as Mitsuba and pbrt-v4 do, never one fixed epsilon) and
:meth:`TraceScene.light_toward` (a light sample's intensity and direction
at a set of points).
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .errors import KitError
from .objfile import load_mesh
from .scene import BUNDLED_DIR

#: Relative offset of spawned rays: (1 + max|p|) · SPAWN_OFFSET along the normal. Float64 hit points
#: are accurate to a few 1e-16·|p|; 1e-9 leaves six orders of magnitude of margin and stays invisible
#: (a 1e-4-sized scene moves by 1e-9, a millionth of a pixel's footprint at 1000 pixels).
SPAWN_OFFSET = 1e-9

#: Counter names every tracer reports (rays by kind, then the work of the hierarchy).
COUNTERS = ("camera", "shadow", "reflection", "transmission", "nodes_visited", "tests")


def spawn(points: np.ndarray, normals: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """Origins for rays leaving ``points`` along ``directions``: moved off the surface to the side they leave by.

    ``normals`` are unit surface normals (either orientation). The offset is
    (1 + max_i |p_i|) · SPAWN_OFFSET along ±n, so it scales with the scene's coordinates.
    """
    points = np.asarray(points, dtype=np.float64)
    normals = np.asarray(normals, dtype=np.float64)
    side = np.sign(np.einsum("ij,ij->i", normals, directions))
    side[side == 0] = 1.0
    scale = (1.0 + np.abs(points).max(axis=1)) * SPAWN_OFFSET
    return points + normals * (side * scale)[:, None]


@dataclass
class TraceScene:
    """A scene as arrays. Primitives are numbered spheres first, then triangles, then planes."""
    # spheres (S)
    sphere_center: np.ndarray
    sphere_radius: np.ndarray
    # triangles (T), from polygons (fans) and meshes
    tri_v0: np.ndarray
    tri_v1: np.ndarray
    tri_v2: np.ndarray
    # infinite planes (P), with a checkerboard frame
    plane_point: np.ndarray
    plane_normal: np.ndarray
    plane_u: np.ndarray
    plane_v: np.ndarray
    plane_checker: np.ndarray          # square size, 0 = plain
    plane_checker_material: np.ndarray  # material index of the odd squares
    # material index of every primitive (S + T + P)
    prim_material: np.ndarray
    # materials (M): arrays indexed by material number
    mat_ambient: np.ndarray
    mat_diffuse: np.ndarray
    mat_specular: np.ndarray
    mat_shininess: np.ndarray
    mat_emission: np.ndarray
    mat_reflectance: np.ndarray
    mat_transmittance: np.ndarray
    mat_ior: np.ndarray
    mat_fresnel: np.ndarray
    material_names: list[str]
    # light samples (K): point lights are one sample each, area lights `samples` each
    light_position: np.ndarray
    light_diffuse: np.ndarray
    light_specular: np.ndarray
    light_attenuation: np.ndarray       # constant, linear, quadratic
    light_normal: np.ndarray            # emitting side of an area light; zero for point lights
    # the rest of the picture
    ambient_light: np.ndarray
    background: np.ndarray
    max_depth: int = 5
    min_weight: float = 0.01
    #: The bounding volume hierarchy over the bounded primitives (spheres and triangles), or None
    #: when there are too few for one to pay off (see HIERARCHY_THRESHOLD).
    bvh: dict[str, np.ndarray] | None = None
    counters: dict[str, int] = field(default_factory=lambda: {k: 0 for k in COUNTERS})

    @property
    def n_spheres(self) -> int:
        return len(self.sphere_radius)

    @property
    def n_triangles(self) -> int:
        return len(self.tri_v0)

    @property
    def n_planes(self) -> int:
        return len(self.plane_point)

    @property
    def n_bounded(self) -> int:
        return self.n_spheres + self.n_triangles

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Axis-aligned boxes (lo, hi), each (S + T, 3), of the bounded primitives in their numbering."""
        r = self.sphere_radius[:, None]
        lo = np.concatenate([self.sphere_center - r, np.minimum(np.minimum(self.tri_v0, self.tri_v1), self.tri_v2)])
        hi = np.concatenate([self.sphere_center + r, np.maximum(np.maximum(self.tri_v0, self.tri_v1), self.tri_v2)])
        return lo, hi

    def material_at(self, prim: np.ndarray, points: np.ndarray) -> np.ndarray:
        """Material index at hit ``points`` of primitives ``prim`` (n,), taking checkerboards into account."""
        prim = np.asarray(prim, dtype=np.int64)
        mats = self.prim_material[np.clip(prim, 0, len(self.prim_material) - 1)].copy()
        plane = prim - self.n_bounded
        on_plane = (prim >= 0) & (plane >= 0)
        if on_plane.any():
            k = plane[on_plane]
            size = self.plane_checker[k]
            rel = points[on_plane] - self.plane_point[k]
            a = np.floor(np.einsum("ij,ij->i", rel, self.plane_u[k]) / np.where(size > 0, size, 1.0))
            b = np.floor(np.einsum("ij,ij->i", rel, self.plane_v[k]) / np.where(size > 0, size, 1.0))
            odd = (size > 0) & ((a + b) % 2 == 1)
            sub = mats[on_plane]
            sub[odd] = self.plane_checker_material[k][odd]
            mats[on_plane] = sub
        return mats

    def light_toward(self, k: int, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Light sample ``k`` seen from ``points`` (n, 3).

        Returns ``(diffuse, specular, to_light, distance)``: the (n, 3) diffuse and specular
        intensities arriving (attenuated by distance, and by the cosine at an area light's
        surface, zero behind it), unit directions (n, 3) from the points to the light, and
        distances (n,).
        """
        d = self.light_position[k] - points
        dist = np.linalg.norm(d, axis=1)
        safe = np.where(dist > 0, dist, 1.0)
        to_light = d / safe[:, None]
        c, l, q = self.light_attenuation[k]
        att = 1.0 / (c + l * dist + q * dist * dist)
        n = self.light_normal[k]
        if np.any(n):
            att = att * np.maximum(-(to_light @ n), 0.0)
        att = np.where(dist > 0, att, 0.0)
        return self.light_diffuse[k] * att[:, None], self.light_specular[k] * att[:, None], to_light, dist

    def reset_counters(self) -> None:
        self.counters = {k: 0 for k in COUNTERS}


#: Build a hierarchy only when there are more bounded primitives than this (below it, testing every
#: primitive costs less than visiting nodes).
HIERARCHY_THRESHOLD = 16


def _plane_frame(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    axis = np.eye(3)[int(np.argmin(np.abs(normal)))]
    u = np.cross(normal, axis)
    u /= np.linalg.norm(u)
    return u, np.cross(normal, u)


def _stratified(n: int, seed: int) -> np.ndarray:
    """``n`` points in the unit square, one per cell of a near-square grid, jittered with a fixed seed."""
    rows = int(np.floor(np.sqrt(n)))
    while n % rows:
        rows -= 1
    cols = n // rows
    rng = np.random.default_rng(seed)
    i, j = np.meshgrid(np.arange(cols), np.arange(rows), indexing="xy")
    jitter = rng.random((2, rows, cols))
    return np.stack([((i + jitter[0]) / cols).ravel(), ((j + jitter[1]) / rows).ravel()], axis=1)


def build(scene: Any, max_depth: int = 5, min_weight: float = 0.01, light_samples: int | None = None) -> TraceScene:
    """The arrays of ``scene`` (a validated Scene). ``light_samples`` overrides every area light's count."""
    from .scene import AreaLight, Mesh, PointLight, Plane, Polygon, Sphere
    label = scene.label
    names = ["default"] + sorted(k for k in scene.materials if k != "default")
    index = {n: i for i, n in enumerate(names)}
    mats = [scene.material(n) for n in names]

    centers, radii, sph_mat = [], [], []
    tris, tri_mat = [], []
    planes = []
    for i, obj in enumerate(scene.objects):
        if not isinstance(obj, (Sphere, Polygon, Mesh, Plane)):
            raise KitError(f"{label}: objects[{i}]: stage 2 cannot trace a {type(obj).__name__}")
        m = index[obj.material]
        if isinstance(obj, Sphere):
            centers.append(obj.center)
            radii.append(obj.radius)
            sph_mat.append(m)
        elif isinstance(obj, Polygon):
            v = np.asarray(obj.vertices, np.float64)
            j = np.arange(1, len(v) - 1)
            tris.append(np.stack([np.broadcast_to(v[0], (len(j), 3)), v[j], v[j + 1]], axis=1))  # a fan
            tri_mat.extend([m] * len(j))
        elif isinstance(obj, Mesh):
            base = Path(scene.source).parent if scene.source else BUNDLED_DIR  # scenes given as dicts: the bundled folder
            v, f = load_mesh(base / obj.file, f"{label}: objects[{i}].file")
            v = v * obj.scale + np.asarray(obj.translate)
            tris.append(v[f])
            tri_mat.extend([m] * len(f))
        elif isinstance(obj, Plane):
            n = np.asarray(obj.normal, np.float64)
            n = n / np.linalg.norm(n)
            u, w = _plane_frame(n)
            planes.append((np.asarray(obj.point, np.float64), n, u, w, obj.checker, index[obj.checker_material], m))
        else:
            raise KitError(f"{label}: objects[{i}]: stage 2 cannot trace a {type(obj).__name__}")

    light_rows = []
    for i, light in enumerate(scene.lights):
        if isinstance(light, PointLight):
            if light.space != "world":
                raise KitError(f"{label}: lights[{i}].space: stage 2 places lights in world space only")
            light_rows.append((light.position, light.diffuse, light.specular, light.attenuation, (0.0, 0.0, 0.0)))
        elif isinstance(light, AreaLight):
            eu, ev = np.asarray(light.edge_u), np.asarray(light.edge_v)
            normal = np.cross(eu, ev)     # not zero: the scene's AreaLight refused parallel edges
            area = float(np.linalg.norm(normal))
            normal /= area
            n = light_samples or light.samples
            uv = _stratified(n, seed=1000 + i)
            # a sample stands for area/n of the light: L·cosθ_light·(A/n)/π is its intensity toward a point,
            # so that a diffuse surface (albedo ρ, shaded as ρ·I·cosθ/r²) receives ρ/π·∫L cosθ cosθ' / r² dA.
            power = np.asarray(light.radiance) * area / (n * np.pi)
            for s, t in uv:
                pos = np.asarray(light.corner) + s * eu + t * ev
                light_rows.append((tuple(pos), tuple(power), tuple(power), (0.0, 0.0, 1.0), tuple(normal)))
        else:
            raise KitError(f"{label}: lights[{i}]: stage 2 traces point and area lights, not a {type(light).__name__}")

    def arr(rows, width=3):
        return np.asarray(rows, np.float64).reshape(-1, width)

    tri = np.concatenate(tris).astype(np.float64).reshape(-1, 3, 3) if tris else np.zeros((0, 3, 3))
    plane_cols = list(zip(*planes)) if planes else [[] for _ in range(7)]
    return TraceScene(
        sphere_center=arr(centers), sphere_radius=np.asarray(radii, np.float64),
        tri_v0=tri[:, 0].copy(), tri_v1=tri[:, 1].copy(), tri_v2=tri[:, 2].copy(),
        plane_point=arr(plane_cols[0]), plane_normal=arr(plane_cols[1]), plane_u=arr(plane_cols[2]),
        plane_v=arr(plane_cols[3]), plane_checker=np.asarray(plane_cols[4], np.float64),
        plane_checker_material=np.asarray(plane_cols[5], np.int64),
        prim_material=np.asarray(sph_mat + tri_mat + list(plane_cols[6]), np.int64),
        mat_ambient=arr([m.ambient for m in mats]), mat_diffuse=arr([m.diffuse for m in mats]),
        mat_specular=arr([m.specular for m in mats]), mat_shininess=np.asarray([m.shininess for m in mats]),
        mat_emission=arr([m.emission for m in mats]), mat_reflectance=arr([m.reflectance for m in mats]),
        mat_transmittance=arr([m.transmittance for m in mats]), mat_ior=np.asarray([m.ior for m in mats]),
        mat_fresnel=np.asarray([m.fresnel for m in mats], bool), material_names=names,
        light_position=arr([r[0] for r in light_rows]), light_diffuse=arr([r[1] for r in light_rows]),
        light_specular=arr([r[2] for r in light_rows]), light_attenuation=arr([r[3] for r in light_rows]),
        light_normal=arr([r[4] for r in light_rows]),
        ambient_light=np.asarray(scene.ambient, np.float64), background=np.asarray(scene.image.background, np.float64),
        max_depth=max_depth, min_weight=min_weight)


# --- checking what a hierarchy looks like (used by the stage and the autograder) -------------------

BVH_KEYS = ("lo", "hi", "child", "start", "count", "order")


def content_key(*arrays: Any) -> str:
    """A key for the contents of numeric arrays (values, dtypes, shapes): SHA-256, ~1 ms per MB.

    Raises TypeError for arrays that are not plain numbers (objects, strings).
    """
    h = hashlib.sha256()
    for a in arrays:
        a = np.ascontiguousarray(a)
        if a.dtype.kind not in "biuf":
            raise TypeError(f"cannot key an array of {a.dtype}")
        h.update(f"{a.dtype.str}{a.shape};".encode())
        h.update(a.reshape(-1).view(np.uint8))
    return h.hexdigest()


#: Verdicts of ``bvh_problems`` by the contents of the hierarchy and the boxes: the same hierarchy handed
#: in again (every render of a mesh scene) is not walked again.
_CHECKED: dict[str, list[str]] = {}


def bvh_problems(bvh: Any, lo: np.ndarray, hi: np.ndarray, max_leaf: int = 8) -> list[str]:
    """What is wrong with a hierarchy over boxes (lo, hi); empty when it is a valid one.

    Format: ``lo``, ``hi`` (m, 3) node boxes; ``child`` (m,) the first child's index (the second is
    child + 1), -1 at a leaf; ``start``, ``count`` (m,) a leaf's range in ``order``; ``order`` (n,)
    the primitives, each once. Node 0 is the root.
    """
    try:
        key = content_key(*(np.asarray(bvh[k]) for k in BVH_KEYS), lo, hi, np.int64(max_leaf))
    except (TypeError, ValueError, KeyError, IndexError):
        return _bvh_problems(bvh, lo, hi, max_leaf)   # not a dict of numeric arrays: nothing to key on
    if key not in _CHECKED:
        if len(_CHECKED) >= 64:
            _CHECKED.clear()
        _CHECKED[key] = _bvh_problems(bvh, lo, hi, max_leaf)
    return list(_CHECKED[key])


def _bvh_problems(bvh: Any, lo: np.ndarray, hi: np.ndarray, max_leaf: int) -> list[str]:
    if not isinstance(bvh, dict) or any(k not in bvh for k in BVH_KEYS):
        return [f"must be a dict with keys {', '.join(BVH_KEYS)}"]
    try:
        nlo, nhi = np.asarray(bvh["lo"], float), np.asarray(bvh["hi"], float)
        child, start, count, order = (np.asarray(bvh[k]) for k in ("child", "start", "count", "order"))
    except (TypeError, ValueError) as err:
        return [f"arrays could not be read ({err})"]
    m, n = len(child), len(lo)
    problems = []
    if nlo.shape != (m, 3) or nhi.shape != (m, 3) or start.shape != (m,) or count.shape != (m,) or m == 0:
        return [f"lo, hi must be (m, 3) and child, start, count (m,) with m ≥ 1 nodes; got {nlo.shape}, "
                f"{nhi.shape}, {child.shape}, {start.shape}, {count.shape}"]
    if any(a.dtype.kind not in "iu" for a in (child, start, count, order)):
        return ["child, start, count and order must be integer arrays"]
    if not (np.isfinite(nlo).all() and np.isfinite(nhi).all()):
        return ["node boxes contain NaN or infinite values"]
    if sorted(order.tolist()) != list(range(n)):
        problems.append(f"order must hold each of the {n} primitives exactly once")
        return problems
    leaf = child < 0
    inner = ~leaf
    if np.any(child[inner] < 1) or np.any(child[inner] + 1 >= m):
        return ["a child index points outside the node arrays"]
    if np.any(count[leaf] < 1) or np.any(start[leaf] < 0) or np.any(start[leaf] + count[leaf] > n):
        return ["a leaf's start/count range lies outside order (or is empty)"]
    if np.any(count[leaf] > max_leaf):
        problems.append(f"a leaf holds {int(count[leaf].max())} primitives (at most {max_leaf})")
    # reachability: every node reached once from the root, leaves covering each primitive once
    seen = np.zeros(m, int)
    covered = np.zeros(n, int)
    stack = [0]
    while stack:
        i = stack.pop()
        seen[i] += 1
        if seen[i] > 1 or len(stack) > m:
            return ["the hierarchy has a cycle or a node with two parents"]
        if child[i] < 0:
            covered[order[start[i]:start[i] + count[i]]] += 1
        else:
            stack += [int(child[i]), int(child[i]) + 1]
    if np.any(covered != 1):
        problems.append(f"{int((covered != 1).sum())} primitives are not in exactly one leaf")
    # containment: each child box inside its parent's, each primitive inside its leaf's box
    tol = 1e-9 * (1 + np.abs(np.concatenate([lo, hi])).max())
    parents = np.nonzero(inner)[0]
    for kids in (child[parents], child[parents] + 1):
        outside = np.any(nlo[kids] < nlo[parents] - tol, axis=1) | np.any(nhi[kids] > nhi[parents] + tol, axis=1)
        if outside.any():
            i = int(np.argmax(outside))
            problems.append(f"node {int(kids[i])}'s box is not inside its parent {int(parents[i])}'s")
            break
    leaves = np.nonzero(leaf)[0]
    slot_leaf = np.repeat(leaves, count[leaves])
    slots = np.concatenate([np.arange(s, s + c) for s, c in zip(start[leaves], count[leaves])]) if len(leaves) else np.zeros(0, int)
    prims = order[slots]
    outside = np.any(lo[prims] < nlo[slot_leaf] - tol, axis=1) | np.any(hi[prims] > nhi[slot_leaf] + tol, axis=1)
    if outside.any():
        problems.append(f"leaf {int(slot_leaf[int(np.argmax(outside))])}'s box does not contain its primitives")
    return problems


def bvh_depth(bvh: dict[str, np.ndarray]) -> int:
    child = np.asarray(bvh["child"])
    depth, stack = 0, [(0, 1)]
    while stack:
        i, d = stack.pop()
        depth = max(depth, d)
        if child[i] >= 0:
            stack += [(int(child[i]), d + 1), (int(child[i]) + 1, d + 1)]
    return depth
