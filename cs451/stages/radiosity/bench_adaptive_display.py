"""The adaptive mesh drawn and rendered without seams (:mod:`.bench_adaptive`): T-vertices anchored, coarse
elements drawn as fans.

**Display and T-vertices.** Where a coarse element meets two finer ones, the finer ones' shared
corner lies in the middle of the coarse element's edge: a T-vertex. The stage's R5 gives every vertex
the average of the elements that have it as a corner, within a polygon; the coarse element does not
have the T-vertex as a corner, so drawn as it is, its edge would shade linearly between its own two
corners while the fine side shows the T-vertex's own average: a seam. So the T-vertex is *anchored*:
it takes the colour the coarse edge has at that point (the linear interpolation of the edge's end
colours), and the shading is continuous across the junction. (The fine side gives up its own value
there; on the tests' shadow scene that costs 2–3% more L1 error of the displayed floor than the
seam would, and it takes away the visible line.) No vertex moves: the T-vertex is already on the
coarse edge (the midpoint, in the patch's bilinear parameters, of a straight edge), so no crack opens
in the geometry. The rasteriser still needs every drawn edge to join the same two vertices on both of
its sides, or pixels fall through at the T-vertices (2 in 61,000 on a test mesh at 256 × 256), so an
element with T-vertices on its edges is drawn as a fan of triangles around its centre through them
(:func:`fans`); elements without T-vertices are drawn as their own quads, as the stage draws patches.
"""
from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

from cs451.patches import as_quads

from .bench_substructuring import PatchToElementRows

if TYPE_CHECKING:
    from .bench_adaptive import AdaptiveSolution, ElementMesh


def _side_points(cells: int, s: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lattice points (U, V) at parameter t (0 .. cells) along patch side s (corner s to corner s+1)."""
    n = cells
    U = np.choose(s, [t, np.full_like(t, n), n - t, np.zeros_like(t)])
    V = np.choose(s, [np.zeros_like(t), t, np.full_like(t, n), n - t])
    return U, V


@dataclass(frozen=True)
class TVertices:
    """Vertex ``v[i]`` lies at parameter ``t[i]`` on edge ``side[i]`` (corner s to s + 1) of the coarser element ``host[i]``."""
    v: np.ndarray
    host: np.ndarray
    side: np.ndarray
    t: np.ndarray

    def __len__(self) -> int:
        return len(self.v)


def t_vertices(mesh: ElementMesh, sides: np.ndarray, corners: np.ndarray, n_patches: int) -> TVertices:
    """The T-vertices of the mesh: element corners that lie inside an edge of another element of the same polygon.

    ``corners`` (m, 4) are the vertex indices of the elements' corners (R5's output, which merges the corners of a
    polygon's elements that lie at the same point). Found on the patches' lattices; across a shared patch side the
    lattice of the patch on the other side is read, run the other way.
    """
    N = mesh.cells
    vid = np.full((n_patches, N + 1, N + 1), -1, dtype=np.int64)
    U0, V0, U1, V1 = mesh.box.T
    for c, (U, V) in enumerate(((U0, V0), (U1, V0), (U1, V1), (U0, V1))):
        vid[mesh.patch, U, V] = corners[:, c]
    other = np.full((n_patches, 4, 2), -1, dtype=np.int64)              # (patch, side) -> (patch, side) across the edge
    if len(sides):
        other[sides[:, 0], sides[:, 1]] = sides[:, 2:]
    found = []
    sizes = U1 - U0
    for h in np.unique(sizes[sizes > 1]):
        group = np.flatnonzero(sizes == h)
        t = np.arange(1, h)
        for s in range(4):                                             # the element's edge from corner s to corner s + 1
            sU, sV = _side_points(h, np.full(len(t), s), t)            # points inside that edge of an h × h square
            U = U0[group][:, None] + sU
            V = V0[group][:, None] + sV
            p = np.broadcast_to(mesh.patch[group][:, None], U.shape)
            v = vid[p, U, V]
            # on the patch's own side s, the point may be a corner of the neighbouring patch's elements
            on_side = np.choose(s, [V == 0, U == N, V == N, U == 0])
            q, s2 = other[p, s, 0], other[p, s, 1]
            across = on_side & (q >= 0) & (v < 0)
            if across.any():
                tp = np.choose(s, [U, V, N - U, N - V])[across]        # parameter along the patch side
                qU, qV = _side_points(N, s2[across], N - tp)
                v[across] = vid[q[across], qU, qV]
            hit = v >= 0
            e = np.broadcast_to(group[:, None], U.shape)[hit]
            found.append((v[hit], e, np.full(len(e), s), np.broadcast_to(t / h, U.shape)[hit]))
    if not found:
        return TVertices(np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0))
    v, host, side, t = (np.concatenate(parts) for parts in zip(*found))
    return TVertices(v.astype(np.int64), host.astype(np.int64), side.astype(np.int64), t.astype(np.float64))


def anchor(colors: np.ndarray, corners: np.ndarray, tv: TVertices, levels: int) -> np.ndarray:
    """Each T-vertex's colour set to its host edge's Gouraud colour there: (1 − t)·c_a + t·c_b.

    A host's corner may itself be a T-vertex of a coarser element; ``levels`` passes (the mesh's depth + 1)
    settle such chains coarse first, whatever their order.
    """
    out = np.array(colors, dtype=np.float64)
    a = corners[tv.host, tv.side]
    b = corners[tv.host, (tv.side + 1) % 4]
    for _ in range(max(int(levels), 1)):
        out[tv.v] = (1 - tv.t)[:, None] * out[a] + tv.t[:, None] * out[b]
    return out


def fans(positions: np.ndarray, corners: np.ndarray, tv: TVertices, colors: np.ndarray | None = None
         ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray, np.ndarray]:
    """Elements with T-vertices on their edges as fans of triangles around their centre, the others as quads.

    Every edge then joins the same two vertices on both of its sides, which is what a rasteriser needs to leave
    no pixel uncovered: a coarse quad drawn whole beside finer neighbours leaves pinholes at the T-vertices (its
    edge is not the finer elements' two edges, in floating point). That holds for the hemicube's item buffer as
    for the display: pinholes there lose light (a furnace of ρ = 0.9 refined with quads ends 4e-4 low). The
    centre is the mean of the four corners (with the mean of their colours, the bilinear value there); a triangle
    comes as a quad with its last corner repeated, as the drawer and the hemicube take them.
    Returns (positions, colors or None, corners of the pieces (P, 4), the element of each piece (P,)).
    """
    hosts = np.unique(tv.host)
    keep = np.setdiff1d(np.arange(len(corners)), hosts)
    order = np.lexsort((tv.t, tv.side, tv.host))
    v, host, side = tv.v[order], tv.host[order], tv.side[order]
    bounds = np.searchsorted(host, hosts, side="left"), np.searchsorted(host, hosts, side="right")
    triangles, owners = [], []
    for k, (e, lo, hi) in enumerate(zip(hosts, *bounds)):
        loop: list[int] = []
        for s in range(4):
            loop.append(int(corners[e, s]))
            loop += [int(x) for x in v[lo:hi][side[lo:hi] == s]]
        c = len(positions) + k
        fan = [(c, x, y, y) for x, y in zip(loop, loop[1:] + loop[:1]) if x != y]
        triangles += fan
        owners += [int(e)] * len(fan)
    centre = corners[hosts]
    positions = np.concatenate([positions, positions[centre].mean(axis=1)])
    if colors is not None:
        colors = np.concatenate([colors, colors[centre].mean(axis=1)])
    drawn = np.concatenate([corners[keep], np.asarray(triangles, dtype=np.int64).reshape(-1, 4)])
    return positions, colors, drawn, np.concatenate([keep, np.asarray(owners, dtype=np.int64)])


def vertex_ids(quads: np.ndarray, polygon: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Corners of a polygon's elements at the same point (within 1e-9 of the scene's size) as one vertex:
    (positions (k, 3), corners (m, 4)), for the receivers the hemicube renders (the display takes R5's)."""
    points = quads.reshape(-1, 3)
    scale = max(float(np.ptp(points, axis=0).max()), 1e-300)
    keys = np.column_stack([np.repeat(polygon, 4), np.round((points - points.min(axis=0)) / (1e-9 * scale))])
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    return points[first], inverse.reshape(-1, 4).astype(np.int64)


class ElementRows:
    """Rows F_p· over the elements of a refined mesh, from hemicubes that see them as a watertight surface.

    The engine renders the pieces of :func:`fans` (an element with T-vertices as its fan of triangles, the others
    as themselves) through :class:`cs451.stages.radiosity.bench_substructuring.PatchToElementRows`; each element's form factor is the
    sum over its pieces. Rows, counters and laziness are PatchToElementRows'.
    """

    def __init__(self, engine: Callable[[np.ndarray], Any], patches: Any, mesh: ElementMesh, sides: np.ndarray,
                 polygon: np.ndarray):
        positions, corners = vertex_ids(mesh.quads, polygon[mesh.patch])
        tv = t_vertices(mesh, sides, corners, len(as_quads(patches)))
        if len(tv):
            positions, _, drawn, self.owner = fans(positions, corners, tv)
            pieces = positions[drawn]
        else:
            pieces, self.owner = mesh.quads, np.arange(len(mesh))
        self.m = len(mesh)
        self.pieces = PatchToElementRows(engine(pieces), patches, mesh.patch[self.owner])
        self.counters = self.pieces.counters

    def row(self, p: int) -> np.ndarray:
        """Row F_p· over the elements, ``(m,)``: the one-row interface the solvers ask for, through :meth:`rows`."""
        return self.rows([p])[0]

    def rows(self, indices: Any) -> np.ndarray:
        """Rows (k, m) for patches ``indices``: each element's pieces summed."""
        pieces = self.pieces.rows(indices)
        out = np.zeros((self.m, len(pieces)))
        np.add.at(out, self.owner, pieces.T)
        return out.T


def display_colors(solution: AdaptiveSolution, vertex_colors: Callable, n_patches: int, watertight: bool = True
                   ) -> Callable:
    """An R5-shaped ``vertex_colors(quads, parent, radiosity)`` for the adaptive mesh, for :func:`cs451.stages.radiosity.display.draw_solution`.

    R5's vertex colours, the T-vertices anchored (:func:`anchor`), and with ``watertight`` the elements that have
    T-vertices drawn as fans (:func:`fans`).
    """
    def colors(quads: np.ndarray, parent: np.ndarray, radiosity: np.ndarray) -> tuple:
        positions, col, corners = vertex_colors(quads, parent, radiosity)
        corners = np.asarray(corners, dtype=np.int64)
        tv = t_vertices(solution.mesh, solution.sides, corners, n_patches)
        if len(tv) == 0:
            return positions, col, corners
        col = anchor(col, corners, tv, int(solution.mesh.depth.max(initial=0)) + 1)
        if not watertight:
            return positions, col, corners
        positions, col, drawn, _ = fans(np.asarray(positions, dtype=np.float64), corners, tv, col)
        return positions, col, drawn
    return colors


def draw(scene: Any, ref: Any, solution: AdaptiveSolution, n_patches: int, size: tuple[int, int],
         anchored: bool = True, drawer: Any = None) -> np.ndarray:
    """The solution drawn Gouraud-shaded with the scene camera through ``ref``'s R5: linear radiance (h, w, 3).

    ``drawer`` (a :class:`cs451.stages.radiosity.display.GouraudDrawer`) is made current first: the hemicube engines and
    other drawers switch the current GL context, and moderngl draws into whichever is current.
    """
    from cs451.stages.radiosity import display as D
    from cs451.gl import make_current
    from cs451.stages import radiosity as R

    drawer = drawer or D.GouraudDrawer()
    make_current(drawer.ctx)
    r5 = lambda q, p, b: R.call_vertex_colors(ref, q, p, b)
    colors = display_colors(solution, r5, n_patches) if anchored else r5
    elements = SimpleNamespace(quads=solution.mesh.quads, parent=solution.polygon)
    return D.draw_solution(scene, colors, elements, solution.radiosity, size, R.camera_view(scene), drawer=drawer)
