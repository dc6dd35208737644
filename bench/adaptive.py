"""Adaptive subdivision within substructuring (notes §2.3): split elements where the radiosity jumps.

The notes' first step (§2.3) asks for patches small enough to catch the changes in the lighting,
and says the subdivision may adapt while the solution runs. Substructuring (bench/substructuring.py)
is the frame for it: patches shoot, elements receive, so the elements can be refined without
touching the patches, their rows or the order they shoot in. This module refines them.

**The criterion.** Two elements are neighbours when they belong to the same polygon and share a piece
of an edge (a whole edge, or part of one where a coarse element meets finer ones). Their contrast is
``|B_e − B_f|₁ / max(|B_e|₁, |B_f|₁, floor)``, summed over the three channels; ``floor`` is
:data:`FLOOR` of the area-weighted mean |B|₁ of the lit elements, so that two nearly black elements in
a shadow do not count as different. An element whose contrast with some neighbour exceeds
``threshold`` (relative: 0.2 means 20%) is a candidate; it is split 2 × 2 in its patch's bilinear
parameters unless it has been split ``max_depth`` times already. Both elements of a pair are
candidates: the edge of a shadow lies somewhere between them. With an element ``budget``, candidates
are split in the order of the light their jump misplaces, ``|B_e − B_f|₁ · A_e`` (big elements with a
big jump first), and each pass may use its share of the budget only, so the finer passes keep some.

**The new elements' radiosity: an exact re-gather, not a re-solve.** A shot is linear: patch p
shooting ΔB_p gives element e the radiosity ρ_e·ΔB_p·F_pe·A_p/A_e. So an element's radiosity is
``E_e + ρ_e Σ_p F_pe (A_p/A_e) S_p``, where S_p is everything patch p has shot so far (the
solver's ``shot``), whatever the element was when the shots happened. After a split the elements
are gathered again from that sum, with each shooter's row rendered over the new elements (one
hemicube per patch that has shot: the hemicube engine renders receivers it was built with, so a
refined mesh needs a new engine and new rows). This is what the refined elements would have
received had they existed from the first shot, without shooting anything again. The patches'
solution does not change: a patch's unshot energy is the sum of its elements' ΔB·A, and the
children of a split element inherit its ΔB (the four children's areas sum to the parent's), so
every patch keeps its unshot energy and the shooting simply continues. (How a patch's unshot
energy is spread over its elements never matters: a patch shoots its mean.) Shooting everything
again onto the refined elements would render the same rows (every shooter's, over the new
elements) and then repeat every shot, to reach the same answer; the re-gather skips the shots.
Energy is conserved as far as the hemicube conserves it: in a closed scene every row sums to the
same s whatever the receivers, so the furnace stays at E/(1 − ρs), provided the receivers the
hemicube sees are watertight (:class:`ElementRows`; T-vertices, below, would let light through).

**When to refine.** First after the emitters have shot (the first sweep): the direct light makes
the shadow boundaries and the sharp fall-off near corners, and a pass then costs one hemicube per
emitting patch. Then the solution is shot to the tolerance and refined again on the converged
radiosity (indirect light, colour bleeding), at a hemicube per shooter for each such pass.

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

This is the benchmark's code (``cs451 bench radiosity``). It lives in bench/ because its shooting
loop would solve task R3: nothing in bench/ reaches students.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import Any, Callable, Sequence

import numpy as np

from cs451 import KIT_ROOT
from cs451.errors import KitError
from cs451.patches import as_quads, patch_areas

from bench.meshes import subdivide_uniform
from bench.substructuring import PatchToElementRows, solve_substructured

#: contrasts are measured against at least this fraction of the lit elements' mean |B|₁
FLOOR = 0.05


# --- the element mesh: a quadtree in each patch's bilinear parameters ------------------------------

@dataclass(frozen=True)
class ElementMesh:
    """Elements of patches, each a square of a patch's lattice of ``cells`` × ``cells`` in its bilinear (u, v).

    ``box[e] = (U0, V0, U1, V1)`` in lattice units (u = U / cells); ``depth[e]`` the 2 × 2 splits since the
    initial k × k; ``cells = k · 2^max_depth``, so every element the refinement can make has integer corners.
    The element's corners are the patch's bilinear map at its box's corners, in the patch's order.
    """
    quads: np.ndarray          # (m, 4, 3)
    patch: np.ndarray          # (m,) int: the patch each element belongs to
    box: np.ndarray            # (m, 4) int
    depth: np.ndarray          # (m,) int
    cells: int

    def __len__(self) -> int:
        return len(self.quads)

    @property
    def areas(self) -> np.ndarray:
        return patch_areas(self.quads)


def initial_mesh(patches: Any, k: int, max_depth: int) -> ElementMesh:
    """Each patch into k × k elements (as :func:`bench.substructuring.split_patches`), on a lattice fine enough for ``max_depth`` splits."""
    if int(k) != k or k < 1 or int(max_depth) != max_depth or max_depth < 0:
        raise KitError(f"need k >= 1 and max_depth >= 0 (integers), got k={k}, max_depth={max_depth}")
    quads, patch = subdivide_uniform(as_quads(patches), int(k))
    cells = int(k) * 2 ** int(max_depth)
    step = cells // int(k)
    i, j = np.meshgrid(np.arange(k), np.arange(k), indexing="ij")          # subdivide_uniform's order: i (along u) major
    lo = np.column_stack([i.ravel(), j.ravel()]) * step
    box = np.tile(np.column_stack([lo, lo + step]), (len(as_quads(patches)), 1))
    return ElementMesh(quads, patch, box.astype(np.int64), np.zeros(len(quads), dtype=np.int64), cells)


def split(mesh: ElementMesh, which: Any) -> tuple[ElementMesh, np.ndarray]:
    """Split elements ``which`` 2 × 2: (the new mesh, the old element each new one comes from).

    The children are the bilinear subdivision of the element's own quad, which is the patch's bilinear
    map at the children's boxes: corners shared with neighbours come out at the same points. Elements
    stay ordered by patch (stable), the children where their parent was.
    """
    which = np.unique(np.asarray(which, dtype=np.int64))
    if len(which) and (which.min() < 0 or which.max() >= len(mesh)):
        raise KitError(f"elements to split must be in 0 .. {len(mesh) - 1}")
    half = (mesh.box[which, 2] - mesh.box[which, 0]) // 2
    if (half < 1).any():
        raise KitError("an element to split is already one lattice cell: it has reached max_depth")
    children, _ = subdivide_uniform(mesh.quads[which], 2)                 # (4·len(which), 4, 3), (0,0) (0,1) (1,0) (1,1)
    di = np.array([0, 0, 1, 1])
    dj = np.array([0, 1, 0, 1])
    u0 = (mesh.box[which, 0][:, None] + di * half[:, None]).ravel()
    v0 = (mesh.box[which, 1][:, None] + dj * half[:, None]).ravel()
    h = np.repeat(half, 4)
    keep = np.setdiff1d(np.arange(len(mesh)), which)
    origin = np.concatenate([keep, np.repeat(which, 4)])
    quads = np.concatenate([mesh.quads[keep], children])
    box = np.concatenate([mesh.box[keep], np.column_stack([u0, v0, u0 + h, v0 + h])])
    depth = np.concatenate([mesh.depth[keep], np.repeat(mesh.depth[which] + 1, 4)])
    # back into patch order, each parent's place taken by its children (the sort key: patch, then origin)
    order = np.lexsort((np.arange(len(origin)), origin, mesh.patch[origin]))
    return ElementMesh(quads[order], mesh.patch[origin][order], box[order], depth[order], mesh.cells), origin[order]


# --- neighbours: the same polygon, a shared piece of edge -----------------------------------------

def _side_cells(cells: int) -> tuple[np.ndarray, np.ndarray]:
    """Lattice cells along each patch side s in the order of the side (corner s to corner s+1): (I, J) each (4, cells)."""
    t = np.arange(cells)
    last = np.full(cells, cells - 1)
    first = np.zeros(cells, dtype=np.int64)
    return (np.stack([t, last, t[::-1], first]), np.stack([first, t, last, t[::-1]]))


def _side_points(cells: int, s: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lattice points (U, V) at parameter t (0 .. cells) along patch side s (corner s to corner s+1)."""
    n = cells
    U = np.choose(s, [t, np.full_like(t, n), n - t, np.zeros_like(t)])
    V = np.choose(s, [np.zeros_like(t), t, np.full_like(t, n), n - t])
    return U, V


def shared_sides(patches: Any, polygon: np.ndarray) -> np.ndarray:
    """Pairs of patch sides (p, s, q, s2) of the same polygon that are one edge, run in opposite directions.

    Side s of a patch runs from its corner s to corner s + 1; corners are the same point within 1e-6 of the
    scene's size. A triangle's repeated corner makes no side. Each shared edge appears once per direction.
    """
    q = as_quads(patches)
    points = q.reshape(-1, 3)
    scale = max(float(np.ptp(points, axis=0).max()), 1e-300)
    snapped = np.round((q - points.min(axis=0)) / (1e-6 * scale)).astype(np.int64)
    ends: dict[tuple, tuple[int, int]] = {}
    for p in range(len(q)):
        for s in range(4):
            a, b = tuple(snapped[p, s]), tuple(snapped[p, (s + 1) % 4])
            if a != b:
                ends[(int(polygon[p]), a, b)] = (p, s)
    out = [(p, s, *ends[(poly, b, a)]) for (poly, a, b), (p, s) in ends.items() if (poly, b, a) in ends]
    return np.array(sorted(out), dtype=np.int64).reshape(-1, 4)


def _owners(mesh: ElementMesh, n_patches: int) -> np.ndarray:
    """(n_patches, cells, cells): the element covering each lattice cell."""
    grid = np.full((n_patches, mesh.cells, mesh.cells), -1, dtype=np.int64)
    sizes = mesh.box[:, 2] - mesh.box[:, 0]
    for h in np.unique(sizes):
        group = np.flatnonzero(sizes == h)
        d = np.arange(h)
        I = mesh.box[group, 0][:, None, None] + d[None, :, None]
        J = mesh.box[group, 1][:, None, None] + d[None, None, :]
        grid[mesh.patch[group][:, None, None], I, J] = group[:, None, None]
    if (grid < 0).any():
        raise KitError("the elements do not tile their patches")
    return grid


def neighbour_pairs(mesh: ElementMesh, sides: np.ndarray, n_patches: int) -> np.ndarray:
    """(k, 2) int, e < f: elements of the same polygon that share a piece of an edge (T-junctions included)."""
    grid = _owners(mesh, n_patches)
    pairs = [np.column_stack([grid[:, :-1, :].ravel(), grid[:, 1:, :].ravel()]),
             np.column_stack([grid[:, :, :-1].ravel(), grid[:, :, 1:].ravel()])]
    if len(sides):
        I, J = _side_cells(mesh.cells)
        p, s, q, s2 = sides.T
        mine = grid[p[:, None], I[s], J[s]]
        theirs = grid[q[:, None], I[s2], J[s2]][:, ::-1]                  # the other patch runs the edge the other way
        pairs.append(np.column_stack([mine.ravel(), theirs.ravel()]))
    pairs = np.concatenate(pairs)
    pairs = pairs[pairs[:, 0] != pairs[:, 1]]
    return np.unique(np.sort(pairs, axis=1), axis=0)


def contrasts(pairs: np.ndarray, radiosity: np.ndarray, areas: np.ndarray, lit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per pair: (relative contrast |B_e − B_f|₁ / max(|B_e|₁, |B_f|₁, floor), the jump |B_e − B_f|₁)."""
    norm = np.abs(radiosity).sum(axis=1)
    mean = float((norm[lit] * areas[lit]).sum() / max(areas[lit].sum(), 1e-300)) if lit.any() else 0.0
    e, f = pairs.T
    jump = np.abs(radiosity[e] - radiosity[f]).sum(axis=1)
    scale = np.maximum(np.maximum(norm[e], norm[f]), max(FLOOR * mean, 1e-300))
    return jump / scale, jump


def select(mesh: ElementMesh, pairs: np.ndarray, radiosity: np.ndarray, lit: np.ndarray, threshold: float,
           max_depth: int, max_splits: int | None = None) -> np.ndarray:
    """The elements to split: over ``threshold`` against a neighbour, not at ``max_depth``, the most misplaced light first."""
    if len(pairs) == 0:
        return np.zeros(0, dtype=np.int64)
    a = mesh.areas
    rel, jump = contrasts(pairs, radiosity, a, lit)
    over = rel > threshold
    priority = np.zeros(len(mesh))
    for side in (0, 1):
        e = pairs[over, side]
        np.maximum.at(priority, e, jump[over] * a[e])
    candidates = np.flatnonzero((priority > 0) & (mesh.depth < max_depth))
    candidates = candidates[np.argsort(-priority[candidates], kind="stable")]
    return np.sort(candidates if max_splits is None else candidates[:max(int(max_splits), 0)])


# --- the solve ------------------------------------------------------------------------------------

def gather(rows: Any, shot: np.ndarray, patch_areas_: np.ndarray, element_areas: np.ndarray,
           reflectance: np.ndarray, emission: np.ndarray) -> np.ndarray:
    """B_e = E_e + ρ_e Σ_p F_pe (A_p/A_e) S_p over the patches that have shot (S_p ≠ 0): (m, 3)."""
    shooters = np.flatnonzero(np.abs(shot).sum(axis=1) > 0)
    B = np.array(emission, dtype=np.float64)
    if len(shooters):
        F = rows.rows(shooters)                                           # (k, m)
        B += reflectance * (F.T @ (patch_areas_[shooters, None] * shot[shooters])) / element_areas[:, None]
    return B


@dataclass
class AdaptiveSolution:
    """The refined elements, their radiosity and unshot radiosity, and what it cost."""
    mesh: ElementMesh
    polygon: np.ndarray        # (m,) the polygon of each element
    radiosity: np.ndarray      # (m, 3)
    unshot: np.ndarray         # (m, 3)
    shot: np.ndarray           # (n, 3) everything each patch has shot
    converged: bool
    residual: float
    shots: int
    hemicubes: int             # every hemicube rendered, over every mesh
    seconds: float
    passes: list[dict] = field(default_factory=list)   # per pass: when, elements before, splits
    sides: np.ndarray = field(default_factory=lambda: np.zeros((0, 4), dtype=np.int64))


def solve_adaptive(patches: Any, engine: Callable[[np.ndarray], Any], k: int = 1, threshold: float = 0.2,
                   max_depth: int = 3, budget: int | None = None, direct_passes: int | None = None,
                   converged_passes: int = 1, tolerance: float = 1e-3) -> AdaptiveSolution:
    """Substructured progressive refinement whose elements are refined where neighbours' radiosity jumps.

    ``patches``: a :class:`cs451.patching.Patches` (quads, parent = polygon, areas, reflectance, emission).
    ``engine(quads)``: a hemicube engine over those receivers (:class:`cs451.formfactors.HemicubeFormFactors`).
    Starts from k × k elements per patch; ``direct_passes`` (default ``max_depth``) refinement passes after
    the emitters' sweep, then shoots to ``tolerance``, then ``converged_passes`` passes each followed by
    shooting to ``tolerance`` again. ``budget``: at most this many elements (each pass may split a share
    of what is left, the remainder divided by the passes to come).
    """
    start = time.perf_counter()
    quads = as_quads(patches.quads)
    n = len(quads)
    polygon = np.asarray(patches.parent)
    A_p = patch_areas(quads)
    direct_passes = max_depth if direct_passes is None else int(direct_passes)
    mesh = initial_mesh(quads, k, max_depth)
    if budget is not None and budget < len(mesh):
        raise KitError(f"a budget of {budget} elements is below the {len(mesh)} elements the refinement starts from")
    sides = shared_sides(quads, polygon)
    rho_p, E_p = np.asarray(patches.reflectance, dtype=np.float64), np.asarray(patches.emission, dtype=np.float64)
    lit_p = E_p.max(axis=1) == 0
    state = SimpleNamespace(B=E_p[mesh.patch].copy(), dB=E_p[mesh.patch].copy(), shot=np.zeros((n, 3)),
                            shots=0, residual=1.0, converged=False, hemicubes=0)
    rows = ElementRows(engine, quads, mesh, sides, polygon)

    def shoot(tol: float, max_shots: int = 0) -> None:
        sol = solve_substructured(rows, mesh.patch, mesh.areas, rho_p[mesh.patch], E_p[mesh.patch], tolerance=tol,
                                  max_shots=max_shots, radiosity=state.B, unshot=state.dB)
        state.B, state.dB, state.shot = sol.radiosity, sol.unshot, state.shot + sol.shot
        state.shots += sol.shots
        state.residual, state.converged = sol.residual, sol.converged

    emitters = int((np.abs(E_p).sum(axis=1) * A_p > 0).sum())
    shoot(0.0, max_shots=max(emitters, 1))                             # the first sweep: the emitters, the direct light
    passes: list[str] = ["direct"] * direct_passes + ["converged"] * converged_passes
    log: list[dict] = []
    for number, when in enumerate(passes):
        if when == "converged":
            shoot(tolerance)
        splits = None
        if budget is not None:
            splits = (budget - len(mesh)) // 3 // (len(passes) - number)
        pairs = neighbour_pairs(mesh, sides, n)
        pick = select(mesh, pairs, state.B, lit_p[mesh.patch], threshold, max_depth, splits)
        log.append({"when": when, "elements": len(mesh), "splits": int(len(pick))})
        if len(pick) == 0:
            continue
        state.hemicubes += rows.counters["hemicubes_rendered"]
        mesh, origin = split(mesh, pick)
        state.dB = state.dB[origin]                                   # children inherit ΔB: every patch keeps its unshot energy
        rows = ElementRows(engine, quads, mesh, sides, polygon)
        state.B = gather(rows, state.shot, A_p, mesh.areas, rho_p[mesh.patch], E_p[mesh.patch])
    shoot(tolerance)
    state.hemicubes += rows.counters["hemicubes_rendered"]
    return AdaptiveSolution(mesh, polygon[mesh.patch], state.B, state.dB, state.shot, state.converged, state.residual,
                            state.shots, state.hemicubes, time.perf_counter() - start, log, sides)


# --- display: vertex colours with anchored T-vertices, coarse elements drawn as fans -----------------

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
    as themselves) through :class:`bench.substructuring.PatchToElementRows`; each element's form factor is the
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
        return self.rows([p])[0]

    def rows(self, indices: Any) -> np.ndarray:
        """Rows (k, m) for patches ``indices``: each element's pieces summed."""
        pieces = self.pieces.rows(indices)
        out = np.zeros((self.m, len(pieces)))
        np.add.at(out, self.owner, pieces.T)
        return out.T


def display_colors(solution: AdaptiveSolution, vertex_colors: Callable, n_patches: int, watertight: bool = True
                   ) -> Callable:
    """An R5-shaped ``vertex_colors(quads, parent, radiosity)`` for the adaptive mesh, for :func:`cs451.drawing.draw_solution`.

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

    ``drawer`` (a :class:`cs451.drawing.GouraudDrawer`) is made current first: the hemicube engines and
    other drawers switch the current GL context, and moderngl draws into whichever is current.
    """
    from cs451 import drawing as D
    from cs451.gl import make_current
    from cs451.stages import radiosity as R

    drawer = drawer or D.GouraudDrawer()
    make_current(drawer.ctx)
    r5 = lambda q, p, b: R.call_vertex_colors(ref, q, p, b)
    colors = display_colors(solution, r5, n_patches) if anchored else r5
    elements = SimpleNamespace(quads=solution.mesh.quads, parent=solution.polygon)
    return D.draw_solution(scene, colors, elements, solution.radiosity, size, R.camera_view(scene), drawer=drawer)


def uniform_solution(patches: Any, engine: Callable[[np.ndarray], Any], k: int, tolerance: float = 1e-3) -> AdaptiveSolution:
    """Substructuring on k × k elements per patch, no refinement, in the same form (for comparisons)."""
    return solve_adaptive(patches, engine, k=k, max_depth=0, direct_passes=0, converged_passes=0, tolerance=tolerance)


# --- the benchmark: uniform against adaptive at equal element count, against Mitsuba -------------

#: the full and the quick run: patch size, hemicube resolution, image size, Mitsuba's samples per pixel (two halves),
#: uniform elements per patch side (each compared with adaptive at the same element count)
RUNS = {False: {"patch_size": 100.0, "resolution": 128, "size": (256, 256), "spp": 512, "ks": (2, 3, 4)},
        True: {"patch_size": 140.0, "resolution": 64, "size": (128, 128), "spp": 64, "ks": (2,)}}
#: the relative contrast between neighbours above which elements are split
THRESHOLD = 0.1
#: the finest element the refinement may make: 1/8 of a patch's side
FINEST = 8
#: the light's patches split again, k × k, so that it shoots from more points than the walls' patch size gives it
#: (a patch shoots from its centre: four points make four hard shadows where the real light makes penumbrae)
LIGHT_SPLIT = 2
#: the mesh figure's panels, pixels
FIGURE_SIZE = (320, 320)
#: the figure's second row: the floor seen from high above the box, the near plane past the ceiling and the light
#: (951 away) so that they are cut away, the back wall at the top; Mitsuba renders it with half the table's samples
PLAN = (("eye", (278.0, 1500.0, 279.6)), ("center", (278.0, 0.0, 279.6)), ("up", (0.0, 0.0, 1.0)), ("fovy", 23.0),
        ("near", 960.0), ("far", 3000.0))
#: the handout's copy of the mesh figure (kit only: a student's release has no bench), written by the full bench run
HANDOUT_FIGURE = KIT_ROOT / "assignments" / "04-radiosity" / "kit" / "adaptive-mesh.png"


def split_emitters(patches: Any, k: int) -> Any:
    """The patches with every emitting patch split k × k again (a :class:`cs451.patching.Patches`)."""
    from cs451.patching import Patches

    emits = np.asarray(patches.emission).max(axis=1) > 0
    light, rest = np.flatnonzero(emits), np.flatnonzero(~emits)
    finer, parent = subdivide_uniform(patches.quads[light], k)
    source = np.concatenate([rest, light[parent]])
    quads = np.concatenate([patches.quads[rest], finer])
    return Patches(quads, patches.parent[source], patch_areas(quads), patches.reflectance[source],
                   patches.emission[source], patches.polygons, patches.labels)


def image_errors(ours: np.ndarray, theirs: np.ndarray, masks: dict[str, np.ndarray]) -> dict[str, float]:
    """Relative L1 error Σ|ours − theirs| / Σ|theirs| over each wall's pixels (all channels), and over all of them ("image")."""
    out, num, den = {}, 0.0, 0.0
    for wall, mask in masks.items():
        d, t = float(np.abs(ours[mask] - theirs[mask]).sum()), float(np.abs(theirs[mask]).sum())
        out[wall] = d / max(t, 1e-300)
        num, den = num + d, den + t
    out["image"] = num / max(den, 1e-300)
    return out


def mesh_overlay(screen: np.ndarray, ids: np.ndarray, color: Sequence[int] = (40, 150, 255), alpha: float = 0.75
                 ) -> np.ndarray:
    """A displayed (uint8) image with the element edges drawn: pixels whose element differs from the next pixel's."""
    edge = np.zeros(ids.shape, dtype=bool)
    edge[:, :-1] |= ids[:, :-1] != ids[:, 1:]
    edge[:-1, :] |= ids[:-1, :] != ids[1:, :]
    out = screen.astype(np.float64)
    out[edge] = (1 - alpha) * out[edge] + alpha * np.asarray(color, dtype=np.float64)
    return np.round(out).astype(np.uint8)


def compare_adaptive(ref: Any, quick: bool) -> dict | None:
    """The Cornell box, uniform against adaptive elements at equal counts: error against Mitsuba per wall and on the image.

    The image error is the relative L1 over the walls' pixels (:func:`image_errors`), and ꟻLIP over the
    whole frame as a screen shows it (sRGB). Mitsuba's own noise: half the L1 difference of its two halves (the
    noise of their mean), and ꟻLIP between the halves (each noisier than the mean). Adaptive elements start from
    half the uniform side (one element a patch below 4 × 4) and may be cut down to 1/:data:`FINEST` of a patch.
    """
    try:
        import mitsuba  # noqa: F401
    except ImportError:
        print("Mitsuba 3 is not installed (pip install -e '.[peers]'): skipping the adaptive subdivision comparison")
        return None
    from cs451 import drawing as D
    from cs451.compare import flip_error
    from cs451.gl import create_context
    from cs451.imageio import to_uint8
    from cs451.scene import load_scene
    from cs451.stages import radiosity as R
    from bench.radiosity import mitsuba_reference, polygon_ids, wall_masks

    import dataclasses

    run = RUNS[quick]
    scene = load_scene("cornell-box")
    plan = dataclasses.replace(scene, camera=dataclasses.replace(scene.camera, **dict(PLAN)))
    size = run["size"]
    peer = mitsuba_reference("cornell-box", size, run["spp"], 64)
    theirs = peer["image"]
    ctx = create_context()
    drawer = D.GouraudDrawer(ctx)
    masks = wall_masks(polygon_ids(scene, size, drawer=drawer))
    screen = lambda image: to_uint8(image, scene.image.exposure, scene.image.srgb)
    patches = split_emitters(R.make_patches(scene, ref, run["patch_size"]), LIGHT_SPLIT)
    engine = lambda quads: R.hemicube_formfactors(quads, run["resolution"], "none", ctx=ctx)
    noise = image_errors(peer["halves"][0], peer["halves"][1], masks)
    rows: list[dict] = [{"method": "Mitsuba's own noise", "k": None, "elements": None, "hemicubes": None, "seconds": None,
                         "errors": {w: 0.5 * e for w, e in noise.items()},
                         "flip": flip_error(screen(peer["halves"][0]), screen(peer["halves"][1]))[0]}]
    figure: dict[str, Any] = {}
    for k in run["ks"]:
        start_k = max(1, k // 2)                    # room to place three quarters of the budget, or more
        depth = int(round(math.log2(FINEST / start_k)))
        for method in ("uniform", "adaptive"):
            if method == "uniform":
                sol = uniform_solution(patches, engine, k)
            else:
                sol = solve_adaptive(patches, engine, k=start_k, threshold=THRESHOLD, max_depth=depth,
                                     budget=len(patches) * k * k)
            ours = draw(scene, ref, sol, len(patches), size, drawer=drawer)
            rows.append({"method": method, "k": k, "elements": len(sol.mesh), "hemicubes": sol.hemicubes,
                         "seconds": sol.seconds, "errors": image_errors(ours, theirs, masks),
                         "flip": flip_error(screen(theirs), screen(ours))[0], "passes": sol.passes,
                         "start": None if method == "uniform" else {"k": start_k, "max_depth": depth}})
            if k == run["ks"][0]:                     # the figure shows the coarsest pair, where the mesh can be seen
                views = []
                for seen in (scene, plan):            # the scene's camera, and the floor from above
                    big = draw(seen, ref, sol, len(patches), FIGURE_SIZE, drawer=drawer)
                    views.append(mesh_overlay(screen(big), polygon_ids(seen, FIGURE_SIZE, quads=sol.mesh.quads,
                                                                      drawer=drawer)))
                figure[method] = {"image": views[0], "plan": views[1], "elements": len(sol.mesh),
                                  "error": rows[-1]["errors"]["image"], "floor": rows[-1]["errors"]["floor"]}
            print(f"  adaptive subdivision: {method} at {len(sol.mesh)} elements done", flush=True)
    above = mitsuba_reference("cornell-box", FIGURE_SIZE, max(run["spp"] // 2, 2), 64, PLAN)
    figure["mitsuba"] = {"image": screen(theirs), "plan": screen(above["image"]), "spp": peer["spp"],
                         "plan_spp": above["spp"]}
    return {"scene": "cornell-box", "patches": len(patches), "patch_size": run["patch_size"], "light_split": LIGHT_SPLIT,
            "resolution": run["resolution"], "size": list(size), "threshold": THRESHOLD, "finest": FINEST,
            "mitsuba_spp": peer["spp"], "mitsuba_seconds": peer["seconds"], "rows": rows, "figure": figure}


def print_adaptive(result: dict) -> list[str]:
    """The table: per wall and on the image, relative L1 error against Mitsuba, uniform against adaptive."""
    walls = [w for w in result["rows"][0]["errors"] if w != "image"]
    short = {w: w.split(" ")[0] for w in walls}
    head = "".join(f"{short[w]:>8}" for w in walls)
    lines = ["", f"adaptive subdivision: the Cornell box, {result['patches']} patches (the light's split "
             f"{result['light_split']} × {result['light_split']}), hemicube {result['resolution']}; relative L1 error "
             f"against Mitsuba 3 ({result['mitsuba_spp']} spp, {result['mitsuba_seconds']:.0f} s) per wall and over all "
             f"walls ('image'), ꟻLIP over the frame; adaptive: threshold {result['threshold']:g}, finest 1/{result['finest']} "
             f"of a patch",
             f"{'method':<20} {'elements':>8} {'hemicubes':>9} {'seconds':>7}{head} {'image':>7} {'ꟻLIP':>6}", "-" * 120]
    for row in result["rows"]:
        e = row["errors"]
        cells = "".join(f"{100 * e[w]:>7.2f}%" for w in walls)
        cost = (f"{row['elements']:>8} {row['hemicubes']:>9} {row['seconds']:>7.1f}" if row["elements"] is not None
                else f"{'':>8} {'':>9} {'':>7}")
        lines.append(f"{row['method']:<20} {cost}{cells} {100 * e['image']:>6.2f}% {row['flip']:>6.3f}")
    print("\n".join(lines))
    return lines


def mesh_figure(fig_data: dict, path: Any) -> Any:
    """Uniform and adaptive meshes of the same element count over their renders, beside Mitsuba's: a PNG at ``path``.

    The top row shows the box from the scene's camera, the bottom row its floor from above (:data:`PLAN`), where
    the shadows are. ``fig_data`` is :func:`compare_adaptive`'s ``figure``. The full run of
    ``cs451 bench radiosity`` writes it to :data:`HANDOUT_FIGURE` too, the copy the handout shows.
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from pathlib import Path

    u, a, m = fig_data["uniform"], fig_data["adaptive"], fig_data["mitsuba"]
    titles = [f"uniform: {u['elements']} elements\nerror {100 * u['error']:.1f}% (floor {100 * u['floor']:.1f}%)",
              f"adaptive: {a['elements']} elements\nerror {100 * a['error']:.1f}% (floor {100 * a['floor']:.1f}%)",
              f"Mitsuba 3, {m['spp']} spp\n(the reference; from above, {m['plan_spp']} spp)"]
    fig, axes = plt.subplots(2, 3, figsize=(12, 8.4))
    for col, (panel, title) in enumerate(zip((u, a, m), titles)):
        axes[0, col].imshow(panel["image"], interpolation="nearest")
        axes[0, col].set_title(title, fontsize=10)
        axes[1, col].imshow(panel["plan"], interpolation="nearest")
        for ax in axes[:, col]:
            ax.axis("off")
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=80)
    plt.close(fig)
    return path
