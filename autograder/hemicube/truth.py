"""Independent truths for stage 3: closed-form form factors, and the exact matrices the tasks define.

Computed on the grader's side only and never shipped: a student copy gets the
arrays these give for the public tests (``checks.py`` compares).

Nothing here calls the reference. The closed forms are Howell's catalog
(A Catalog of Radiation Heat Transfer Configuration Factors, 3rd ed.):
C-11 parallel opposed rectangles, C-14 perpendicular rectangles sharing an
edge, B-13 differential area to a coaxial parallel disk; Lambert's contour
integral for a point to a polygon (written here as a plain loop over edges,
independently of any vectorised solution); and the exact form factor of a
hemicube cell (the contour integral over the cell's square).
"""
from __future__ import annotations

import math

import numpy as np


def howell_c11(a: float, b: float, c: float) -> float:
    """Parallel, directly opposed rectangles a × b at distance c (Howell C-11). F(1, 1, 1) = 0.19982."""
    X, Y = a / c, b / c
    x1, y1 = math.sqrt(1 + X * X), math.sqrt(1 + Y * Y)
    s = (math.log(x1 * y1 / math.sqrt(1 + X * X + Y * Y)) + X * y1 * math.atan(X / y1) + Y * x1 * math.atan(Y / x1)
         - X * math.atan(X) - Y * math.atan(Y))
    return 2 / (math.pi * X * Y) * s


def howell_c14(l: float, w: float, h: float) -> float:
    """From a rectangle l × w to a rectangle l × h at right angles to it, sharing the edge of length l (Howell C-14).

    F(1, 1, 1) = 0.20004.
    """
    H, W = h / l, w / l
    hw = H * H + W * W
    term = W * math.atan(1 / W) + H * math.atan(1 / H) - math.sqrt(hw) * math.atan(1 / math.sqrt(hw))
    log = (math.log((1 + W * W) * (1 + H * H) / (1 + hw))
           + W * W * math.log(W * W * (1 + hw) / ((1 + W * W) * hw))
           + H * H * math.log(H * H * (1 + hw) / ((1 + H * H) * hw)))
    return (term + 0.25 * log) / (math.pi * W)


def disk(radius: float, height: float) -> float:
    """Differential area to a coaxial parallel disk of ``radius`` at ``height`` (Howell B-13): a²/(a² + h²)."""
    return radius * radius / (radius * radius + height * height)


def contour(point, normal, polygon) -> float:
    """Point to polygon by Lambert's contour integral, F = |Σ β_k cos(angle of normal and edge plane normal)| / 2π."""
    p = [float(v) for v in point]
    n = [float(v) for v in normal]
    verts = [[float(v) for v in q] for q in polygon]
    total = 0.0
    for k in range(len(verts)):
        a = [verts[k][i] - p[i] for i in range(3)]
        b = [verts[(k + 1) % len(verts)][i] - p[i] for i in range(3)]
        la, lb = math.sqrt(sum(x * x for x in a)), math.sqrt(sum(x * x for x in b))
        g = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
        lg = math.sqrt(sum(x * x for x in g))
        if lg < 1e-300 or la == 0 or lb == 0:
            continue
        beta = math.acos(max(-1.0, min(1.0, sum(a[i] * b[i] for i in range(3)) / (la * lb))))
        total += beta * sum(g[i] * n[i] for i in range(3)) / lg
    return abs(total) / (2 * math.pi)


def regular_polygon(radius: float, height: float, sides: int, facing_down: bool = True) -> np.ndarray:
    """A regular polygon of ``sides`` corners on the circle of ``radius`` at z = ``height``, centred on the z axis."""
    t = 2 * np.pi * np.arange(sides) / sides
    if facing_down:
        t = -t                      # clockwise seen from +z: counter-clockwise seen from below, its front faces -z
    return np.stack([radius * np.cos(t), radius * np.sin(t), np.full(sides, height)], axis=1)


def polygon_disk(radius: float, height: float, sides: int) -> float:
    """Differential area to a coaxial regular polygon inscribed in the disk: exact, by the symmetric contour sum."""
    # each edge subtends 2π/sides about the axis; closed form of one edge's contribution
    return contour([0, 0, 0], [0, 0, 1], regular_polygon(radius, height, sides))


# --- what the tasks define exactly ------------------------------------------------

def delta_top(resolution: int) -> np.ndarray:
    """H1's top table: ΔA / (π (x² + y² + 1)²) at cell centres; [row j (y), column i (x)], rows bottom to top."""
    r = int(resolution)
    out = np.empty((r, r))
    for j in range(r):
        y = -1 + (j + 0.5) * 2 / r
        for i in range(r):
            x = -1 + (i + 0.5) * 2 / r
            out[j, i] = (2 / r) ** 2 / (math.pi * (x * x + y * y + 1) ** 2)
    return out


def delta_side(resolution: int) -> np.ndarray:
    """H1's side table: z ΔA / (π (y² + z² + 1)²); [row j (height z above the base), column i (y)]."""
    r = int(resolution)
    out = np.empty((r // 2, r))
    for j in range(r // 2):
        z = (j + 0.5) * 2 / r
        for i in range(r):
            y = -1 + (i + 0.5) * 2 / r
            out[j, i] = z * (2 / r) ** 2 / (math.pi * (y * y + z * z + 1) ** 2)
    return out


def exact_cell_top(resolution: int, i: int, j: int) -> float:
    """The exact form factor from the hemicube's centre to top cell (column i, row j): the contour integral of its square."""
    h = 2 / resolution
    x0, y0 = -1 + i * h, -1 + j * h
    return contour([0, 0, 0], [0, 0, 1], [[x0, y0, 1], [x0 + h, y0, 1], [x0 + h, y0 + h, 1], [x0, y0 + h, 1]])


def exact_cell_side(resolution: int, i: int, j: int) -> float:
    """The exact form factor to side cell (column i, row j) of the face x = 1 (z up from the base)."""
    h = 2 / resolution
    y0, z0 = -1 + i * h, j * h
    return contour([0, 0, 0], [0, 0, 1], [[1, y0, z0], [1, y0 + h, z0], [1, y0 + h, z0 + h], [1, y0, z0 + h]])


def look_at(eye, center, up) -> np.ndarray:
    """gluLookAt (GLU 1.3): f = norm(center − eye), s = norm(f × up), u = s × f; rows [s; u; −f], then translate(−eye)."""
    eye, center, up = (np.asarray(v, dtype=np.float64) for v in (eye, center, up))
    f = (center - eye) / np.linalg.norm(center - eye)
    s = np.cross(f, up)
    s /= np.linalg.norm(s)
    u = np.cross(s, f)
    rot = np.array([s, u, -f])
    m = np.eye(4)
    m[:3, :3] = rot
    m[:3, 3] = -rot @ eye
    return m


def frustum(left, right, bottom, top, near, far) -> np.ndarray:
    """glFrustum (OpenGL 2.1 spec §2.11.2)."""
    return np.array([[2 * near / (right - left), 0, (right + left) / (right - left), 0],
                     [0, 2 * near / (top - bottom), (top + bottom) / (top - bottom), 0],
                     [0, 0, -(far + near) / (far - near), -2 * far * near / (far - near)],
                     [0, 0, -1, 0]])


def views(params: dict) -> np.ndarray:
    """H2: the five faces, top along the normal (up = up), then ±up and ±(normal × up), each with the normal as up."""
    c, n, u = (np.asarray(params[k], dtype=np.float64) for k in ("center", "normal", "up"))
    s = np.cross(n, u)
    return np.stack([look_at(c, c + d, w) for d, w in ((n, u), (u, n), (-u, n), (s, n), (-s, n))])


def projections(params: dict) -> np.ndarray:
    near, far = params["near"], params["far"]
    return np.stack([frustum(-near, near, -near, near, near, far), frustum(-near, near, 0, near, near, far)])


def tables(params: dict) -> dict[str, np.ndarray]:
    """H1's two tables at the test's resolution."""
    return {"top": delta_top(params["resolution"]), "side": delta_side(params["resolution"])}


def tetrahedron_face(params: dict) -> dict[str, np.ndarray]:
    """H7 by its definition, in vectors: for each cell centre d = (x, y, 1) on the face, cos θ at the patch (against
    the normal (1, 1, 1)/√3) times cos θ at the face (against its normal z) over π|d|², times the cell's area;
    nothing where d points below the patch's plane."""
    r = int(params["resolution"])
    centres = -2 + 3 * (np.arange(r) + 0.5) / r
    face = np.zeros((r, r))
    normal = np.ones(3) / np.sqrt(3)
    for j, y in enumerate(centres):
        for i, x in enumerate(centres):
            d = np.array([x, y, 1.0])
            length = np.linalg.norm(d)
            cos_patch, cos_face = d @ normal / length, 1.0 / length
            face[j, i] = max(cos_patch, 0.0) * cos_face / (np.pi * length ** 2) * (3 / r) ** 2
    return {"face": face}


def contour_value(params: dict) -> np.ndarray:
    """H6: Lambert's formula for the test's point, normal and polygon."""
    return np.array(contour(params["point"], params["normal"], params["polygon"]))


def row_from_items(params: dict) -> np.ndarray:
    """H5 by plain accumulation (np.add.at), independent of bincount."""
    n = params["n_patches"]
    row = np.zeros(n + 1)
    np.add.at(row, np.asarray(params["top_items"]).ravel(), np.asarray(params["top_weights"]).ravel())
    side = np.asarray(params["side_items"])
    for k in range(side.shape[0]):
        np.add.at(row, side[k].ravel(), np.asarray(params["side_weights"]).ravel())
    return row[1:]


# --- configurations with known answers (patches as (n, 4, 3) lists) -----------------------------

def square(x0, y0, z, size, facing_up: bool):
    q = [[x0, y0, z], [x0 + size, y0, z], [x0 + size, y0 + size, z], [x0, y0 + size, z]]
    return q if facing_up else q[::-1]


def opposed_squares(size: float, distance: float) -> list:
    """Two squares size × size, directly opposed at ``distance``: patch 0 at z = 0 facing up, patch 1 above facing down."""
    return [square(0, 0, 0, size, True), square(0, 0, distance, size, False)]


def perpendicular_squares(size: float, height: float) -> list:
    """Patch 0: square in z = 0 facing up; patch 1: size × height in x = 0 facing +x, sharing the edge on the y axis."""
    return [square(0, 0, 0, size, True), [[0, 0, 0], [0, size, 0], [0, size, height], [0, 0, height]]]


def cube(k: int = 1) -> list:
    """A closed unit cube, faces facing inwards, each cut into k × k patches."""
    faces = [
        [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 0, 1], [0, 1, 1], [1, 1, 1], [1, 0, 1]],
        [[0, 0, 0], [0, 1, 0], [0, 1, 1], [0, 0, 1]], [[1, 0, 0], [1, 0, 1], [1, 1, 1], [1, 1, 0]],
        [[0, 0, 0], [0, 0, 1], [1, 0, 1], [1, 0, 0]], [[0, 1, 0], [1, 1, 0], [1, 1, 1], [0, 1, 1]],
    ]
    out = []
    t = np.linspace(0, 1, k + 1)
    for f in np.asarray(faces, dtype=float):
        a, b, c, d = f
        for i in range(k):
            for j in range(k):
                p = lambda s, u: (1 - s) * (1 - u) * a + s * (1 - u) * b + s * u * c + (1 - s) * u * d
                out.append([p(t[i], t[j]).tolist(), p(t[i + 1], t[j]).tolist(), p(t[i + 1], t[j + 1]).tolist(),
                            p(t[i], t[j + 1]).tolist()])
    return out


def small_patch_under_disk(patch_size: float, radius: float, height: float, sides: int) -> list:
    """Patch 0: a tiny square centred at the origin facing up; then the polygon fanned into triangles (as quads)."""
    h = patch_size / 2
    poly = regular_polygon(radius, height, sides)
    centre = [0.0, 0.0, height]
    tris = [[centre, poly[k].tolist(), poly[(k + 1) % sides].tolist(), poly[(k + 1) % sides].tolist()] for k in range(sides)]
    return [[[-h, -h, 0], [h, -h, 0], [h, h, 0], [-h, h, 0]]] + tris


# --- the family of configurations the engine must meet within 1% at resolution 128 (bench and tests) -----------

def rectangle(x0: float, x1: float, y0: float, y1: float, z: float, facing_up: bool) -> list:
    q = [[x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z]]
    return q if facing_up else q[::-1]


def parallel_rectangles(a: float, b: float, c: float) -> list:
    """Howell C-11's scene: a × b facing up at z = 0, the same facing down at z = c (patch 0 shoots to patch 1)."""
    return [rectangle(0, a, 0, b, 0, True), rectangle(0, a, 0, b, c, False)]


def perpendicular_rectangles(l: float, w: float, h: float) -> list:
    """Howell C-14's scene: l × w facing up at z = 0 (x in [0, w]), l × h in x = 0 facing +x, sharing the y edge."""
    return [rectangle(0, w, 0, l, 0, True), [[0, 0, 0], [0, l, 0], [0, l, h], [0, 0, h]]]


def disk_fan(radius: float, z: float, sides: int, facing_up: bool) -> list:
    """A regular polygon of ``sides`` corners on a circle about the z axis, as a fan of triangles from its centre
    (each stored as a quad with a repeated corner)."""
    poly = regular_polygon(radius, z, sides, facing_down=not facing_up)
    centre = [0.0, 0.0, float(z)]
    return [[centre, poly[k].tolist(), poly[(k + 1) % sides].tolist(), poly[(k + 1) % sides].tolist()]
            for k in range(sides)]


def coaxial_disks(r1: float, r2: float, h: float, sides: int = 32) -> list:
    """Two coaxial parallel regular polygons (disks) at distance h: the first facing up, the second down."""
    return disk_fan(r1, 0.0, sides, True) + disk_fan(r2, h, sides, False)


def disk_to_disk(r1: float, r2: float, h: float) -> float:
    """Coaxial parallel disks of radii r1 (shooter) and r2 at distance h (Howell C-41)."""
    R1, R2 = r1 / h, r2 / h
    X = 1 + (1 + R2 * R2) / (R1 * R1)
    return 0.5 * (X - math.sqrt(X * X - 4 * (R2 / R1) ** 2))


def polygons_form_factor(shooters, receiver, k: int = 6) -> float:
    """F from the union of planar quads ``shooters`` (one plane) to the polygon ``receiver``: Gauss-Legendre k × k
    on each quad of Lambert's contour formula, area-weighted. For the inscribed polygons of :func:`coaxial_disks`,
    whose exact value lies below :func:`disk_to_disk` by the area they miss (0.1-0.6% at 32 sides)."""
    x, w = np.polynomial.legendre.leggauss(k)
    s, ws = 0.5 * (x + 1), 0.5 * w
    total = area = 0.0
    for quad in np.asarray(shooters, dtype=float):
        a, b, c, d = quad
        normal = np.cross(c - a, d - b) if np.linalg.norm(d - b) > 0 else np.cross(b - a, c - a)
        normal = normal / np.linalg.norm(normal)
        for si, wi in zip(s, ws):
            for tj, wj in zip(s, ws):
                p = (1 - si) * (1 - tj) * a + si * (1 - tj) * b + si * tj * c + (1 - si) * tj * d
                jac = np.linalg.norm(np.cross((1 - tj) * (b - a) + tj * (c - d), (1 - si) * (d - a) + si * (c - b)))
                total += wi * wj * jac * contour(p, normal, receiver)
                area += wi * wj * jac
    return total / area


def form_factor_family() -> list[tuple[str, list, list[int], list[int], float]]:
    """(name, patches, shooter patches, receiver patches, exact F) for Howell's C-11 and C-14 and coaxial disks,
    sizes 0.2 to 5 times the separation (C-11, disks) or the shared edge (C-14), several aspect ratios."""
    out = []
    sizes = (0.2, 0.5, 1.0, 2.0, 5.0)
    for k, a in enumerate(sizes):
        for b in sizes[k:]:
            out.append((f"C-11 {a:g} x {b:g}, 1 apart", parallel_rectangles(a, b, 1.0), [0], [1], howell_c11(a, b, 1.0)))
    for l, w, h in ((1, 1, 1), (1, 0.2, 1), (1, 5, 1), (1, 1, 0.2), (1, 1, 5), (0.2, 1, 1), (5, 1, 1), (1, 0.2, 5),
                    (1, 5, 0.2), (2, 0.5, 3)):
        out.append((f"C-14 l {l:g}, w {w:g}, h {h:g}", perpendicular_rectangles(l, w, h), [0], [1], howell_c14(l, w, h)))
    sides = 32
    for r1, r2 in ((0.1, 0.1), (0.5, 0.5), (1, 1), (2.5, 2.5), (0.5, 2), (2, 0.5), (0.1, 2.5), (2.5, 0.1)):
        quads = coaxial_disks(r1, r2, 1.0, sides)
        exact = polygons_form_factor(quads[:sides], regular_polygon(r2, 1.0, sides), k=6)
        out.append((f"disks r {r1:g} to r {r2:g}, 1 apart ({sides}-gons)", quads, list(range(sides)),
                    list(range(sides, 2 * sides)), exact))
    return out

