"""A polygon's patches drawn as one quad, the fragment shader finding which patch it is on.

On a CPU rasteriser a hemicube costs what its triangles cost: each is shaded, clipped and binned on the
calling thread (in the room at 128, 65% of the time went to the draw calls, about 1,000 triangles a face).
Stage 4's R1 cuts a polygon into a bilinear grid of nu × nv patches; drawn as the polygon's two triangles,
each fragment finds its (s, t) in the quad (the inverse of the bilinear map that placed the corners) and
its patch from the cell (⌊s·nu⌋, ⌊t·nv⌋). The lines s = i/nu of a planar bilinear quad are straight, so
the cells are the patches: the item buffer is the same except at pixels whose centres lie on a patch edge
within rounding (the rasteriser's fixed-point edge test and the shader's float decide such a pixel
differently), and rows are as close to a finer hemicube's as the patch-by-patch rows
(tests/hemicube/test_formfactor_grids.py).

Grids are found in the order the patches come in, R1's (a polygon's patches row by row along its 0→3 edge,
each row along 0→1), and each is checked corner by corner against the bilinear grid of the planar convex
quad it spans. What is no such grid (a non-planar quad's patches, a triangle's last row, any other order)
is a grid of one cell: the patch's own two triangles, drawn as before. Only the kit's trusted engine draws
grids, with its own shaders (below); a student's H4 shaders are what stage 3 grades.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..patches import as_quads
from .geometry import bilinear

#: a patch's corner is on its grid when within this fraction of the scene's size (float64 rounding of a
#: bilinear subdivision is about 1e-16 of it; float32, which the GPU draws in, 6e-8)
GRID_TOLERANCE = 1e-9
#: the unit square's corners in the patches' order (counter-clockwise seen from the front): cell offsets (s, t)
_CELL_CORNERS = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=np.float64)

#: Replaces H4's vertex shader for grids (after the kit's VERTEX_INTERFACE): the corner's coordinates in the
#: grid's plane go to the fragment interpolated (they are affine in the world, so perspective-correct
#: interpolation gives them exactly); the grid's other corners, first patch and size go flat.
GRID_VERTEX = """
in vec2 in_local;             // this corner in the grid's plane: corner 0 at (0, 0), corner 1 on the +x axis
in vec2 in_b;                 // the grid's corners 1, 2, 3 in the same coordinates
in vec2 in_c;
in vec2 in_d;
in uvec3 in_grid;             // the grid's first patch id, cells along 0→1, cells along 0→3
smooth out vec2 v_local;
flat out vec2 v_b;
flat out vec2 v_c;
flat out vec2 v_d;
flat out uvec3 v_grid;
void main() {
    gl_Position = hemicube_projection() * hemicube_view() * vec4(in_position, 1.0);
    v_local = in_local;
    v_b = in_b;
    v_c = in_c;
    v_d = in_d;
    v_grid = in_grid;
}
"""
#: The patch under a fragment: its bilinear coordinates (s, t) in the grid's quad (a planar convex quad: the
#: root in [0, 1] of k2·t² + k1·t + k0, the stable one of the two, which is t = -k0/k1 for a parallelogram),
#: then its cell, clamped into the grid (a pixel on the quad's edge may land a hair outside). The lines s = i/nu
#: of a planar bilinear quad are straight, so the cells are the patches. A back face hides what is behind it
#: and receives nothing, as H4 says.
GRID_FRAGMENT = """
smooth in vec2 v_local;
flat in vec2 v_b;
flat in vec2 v_c;
flat in vec2 v_d;
flat in uvec3 v_grid;
float cross2(vec2 p, vec2 q) { return p.x * q.y - p.y * q.x; }
void main() {
    vec2 e = v_b, f = v_d, g = v_c - v_b - v_d, h = v_local;
    float k2 = cross2(g, f), k1 = cross2(e, f) + cross2(h, g), k0 = cross2(h, e);
    float root = sqrt(max(k1 * k1 - 4.0 * k2 * k0, 0.0));
    float q = -0.5 * (k1 + (k1 < 0.0 ? -root : root));
    float t = q != 0.0 ? k0 / q : 0.0;
    if ((t < -0.5 || t > 1.5) && k2 != 0.0) t = q / k2;
    vec2 across = e + g * t;
    float s = abs(across.x) > abs(across.y) ? (h.x - f.x * t) / across.x : (h.y - f.y * t) / across.y;
    ivec2 cell = clamp(ivec2(floor(vec2(s, t) * vec2(v_grid.yz))), ivec2(0), ivec2(v_grid.yz) - 1);
    item = gl_FrontFacing ? v_grid.x + uint(cell.y) * v_grid.y + uint(cell.x) + 1u : 0u;
}
"""


@dataclass(frozen=True)
class Grids:
    """Patches gathered into grids: grid g is ``shape[g]`` = (nu, nv) cells, patch ``first[g] + j·nu + i`` in
    cell (i, j) of the bilinear grid of the quad ``corners[g]`` (counter-clockwise, as its patches)."""
    corners: np.ndarray     # (g, 4, 3) float64
    first: np.ndarray       # (g,) int64
    shape: np.ndarray       # (g, 2) int64: nu, nv

    def __len__(self) -> int:
        return len(self.first)

    def plane_coordinates(self) -> np.ndarray:
        """(g, 4, 2): each grid's corners in its own plane, corner 0 at the origin and corner 1 on the +x axis."""
        edge = self.corners - self.corners[:, :1]
        x = edge[:, 1] / np.linalg.norm(edge[:, 1], axis=1, keepdims=True)
        normal = np.cross(edge[:, 1], edge[:, 3])
        y = np.cross(normal, x)
        y /= np.linalg.norm(y, axis=1, keepdims=True)
        return np.stack([np.einsum("gki,gi->gk", edge, x), np.einsum("gki,gi->gk", edge, y)], axis=2)


def patch_grids(quads: np.ndarray, tolerance: float = GRID_TOLERANCE) -> Grids:
    """The patches in runs that are bilinear grids of planar convex quads, row by row; the patches of a row that is
    no such grid are grids of one cell each. Every patch lands in exactly one grid, in order: the grids' cells are
    the patches."""
    q = as_quads(quads)
    n = len(q)
    eps = tolerance * max(float(np.ptp(q.reshape(-1, 3), axis=0).max()), 1e-300)

    def near(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return np.abs(a - b).max(axis=-1) <= eps

    # patch b + 1 is patch b's right neighbour: it shares b's edge 1-2 as its edge 0-3; chain[b] patches from b on
    # make a row (b's first break at or after it, the last of the row)
    right = near(q[1:, 0], q[:-1, 1]) & near(q[1:, 3], q[:-1, 2])
    breaks = np.where(np.append(right, False), n, np.arange(n))
    chain = np.minimum.accumulate(breaks[::-1])[::-1] - np.arange(n) + 1
    corners, first, shape = [], [], []
    a = 0
    while a < n:
        nu, nv = int(chain[a]), 1
        if not _is_grid(q[a:a + nu], nu, 1, eps):      # not even the first row: its patches are drawn on their own
            corners += list(q[a:a + nu])
            first += range(a, a + nu)
            shape += [(1, 1)] * nu
            a += nu
            continue
        while a + (nv + 1) * nu <= n:          # the next row: chained, and on top of this one
            row, below = q[a + nv * nu:a + (nv + 1) * nu], q[a + (nv - 1) * nu:a + nv * nu]
            if not (chain[a + nv * nu] >= nu and near(row[:, 0], below[:, 3]).all() and near(row[:, 1], below[:, 2]).all()):
                break
            nv += 1
        # the most rows that are a grid (a run can run on into the next polygon's rows): the first k rows of a
        # grid are a grid (of the quad they span), so the largest k is found by bisection
        if not _is_grid(q[a:a + nu * nv], nu, nv, eps):
            good, bad = 1, nv
            while bad - good > 1:
                mid = (good + bad) // 2
                good, bad = (mid, bad) if _is_grid(q[a:a + nu * mid], nu, mid, eps) else (good, mid)
            nv = good
        corners.append(_spanned(q[a:a + nu * nv], nu))
        first.append(a)
        shape.append((nu, nv))
        a += nu * nv
    return Grids(np.asarray(corners, dtype=np.float64).reshape(-1, 4, 3), np.asarray(first, dtype=np.int64),
                 np.asarray(shape, dtype=np.int64).reshape(-1, 2))


def _is_grid(cells: np.ndarray, nu: int, nv: int, eps: float) -> bool:
    """Whether ``cells`` (nu·nv, 4, 3), row-major, are the bilinear grid of the planar convex quad they span."""
    if nu * nv == 1:
        return True
    quad = _spanned(cells, nu)
    edges = np.roll(quad, -1, axis=0) - quad
    turns = np.cross(edges, np.roll(edges, -1, axis=0))             # at corners 1, 2, 3, 0
    normal = turns.sum(axis=0)
    size = np.linalg.norm(normal)
    if size <= eps * eps or (turns @ normal <= eps * eps * size).any():   # degenerate, or not convex
        return False
    if abs((quad[3] - quad[0]) @ normal) / size > eps:                 # not planar
        return False
    i, j = np.meshgrid(np.arange(nu), np.arange(nv))
    st = (np.stack([i.ravel(), j.ravel()], axis=1)[:, None, :] + _CELL_CORNERS[None]) / np.array([nu, nv])
    return bool(np.abs(bilinear(quad, st) - cells).max() <= eps)


def _spanned(cells: np.ndarray, nu: int) -> np.ndarray:
    """The quad (4, 3) that row-major cells (nu per row) span: the outer corners of the corner cells."""
    return np.array([cells[0, 0], cells[nu - 1, 1], cells[-1, 2], cells[-nu, 3]])
