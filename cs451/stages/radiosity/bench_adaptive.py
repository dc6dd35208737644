"""Adaptive subdivision within substructuring (notes §2.3): split elements where the radiosity jumps.

The notes' first step (§2.3) asks for patches small enough to catch the changes in the lighting,
and says the subdivision may adapt while the solution runs. Substructuring (cs451/stages/radiosity/bench_substructuring.py)
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

How the refined mesh is drawn (T-vertices) is :mod:`.bench_adaptive_display`; the comparison with a uniform mesh
against Mitsuba is :mod:`.bench_adaptive_runs`. This is the benchmark's code (``cs451 bench radiosity``): instructors'
only, like every stage's benchmarks, because its shooting loop would solve task R3.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import Any, Callable

import numpy as np

from cs451 import import_from_kit
from cs451.errors import KitError
from cs451.patches import as_quads, patch_areas

from .bench_adaptive_display import ElementRows
from .bench_substructuring import solve_substructured

subdivide_uniform = import_from_kit("bench.meshes").subdivide_uniform    # the kit's fine meshes (bench/)

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
        """Each element's area ``(m,)``, from its quad."""
        return patch_areas(self.quads)


def initial_mesh(patches: Any, k: int, max_depth: int) -> ElementMesh:
    """Each patch into k × k elements (as :func:`cs451.stages.radiosity.bench_substructuring.split_patches`), on a lattice fine enough for ``max_depth`` splits."""
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


def uniform_solution(patches: Any, engine: Callable[[np.ndarray], Any], k: int, tolerance: float = 1e-3) -> AdaptiveSolution:
    """Substructuring on k × k elements per patch, no refinement, in the same form (for comparisons)."""
    return solve_adaptive(patches, engine, k=k, max_depth=0, direct_passes=0, converged_passes=0, tolerance=tolerance)
