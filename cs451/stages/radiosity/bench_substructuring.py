"""Substructuring: patches shoot, finer elements receive (Cohen, Greenberg, Immel & Brock 1986).

The 1988 progressive-refinement paper pairs shooting with this two-level hierarchy: each
patch is split into k × k elements; a patch's hemicube, at its centre, sees the elements,
so a row holds patch-to-element form factors F_pe. Rows then number the patches, not the
elements, while the radiosity is resolved on the elements. The price is an approximation:
a patch shoots its area-averaged unshot radiosity, from its centre, as if it were uniform.

This is the benchmark's code (``cs451 bench radiosity``), which measures what that
approximation costs in accuracy against what it saves in rows. Like every stage's benchmark it is
instructors' only (:func:`cs451.instructor_only`: in no release, and hidden from every sandbox), because its
shooting loop would solve task R3.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from cs451 import import_from_kit
from cs451.errors import KitError
from cs451.patches import as_quads, patch_centers, patch_normals

subdivide_uniform = import_from_kit("bench.meshes").subdivide_uniform    # the kit's fine meshes (bench/)



class PatchToElementRows:
    """Rows F_p· over the elements for shooting patch p: one hemicube at the patch centre, lazily, cached.

    ``engine`` is a :class:`cs451.formfactors.HemicubeFormFactors` over the elements (the
    receivers); ``parent[e]`` is the patch element e belongs to.
    """

    def __init__(self, engine: Any, patches: Any, parent: np.ndarray):
        self.engine = engine
        self.patches = as_quads(patches)
        self.parent = np.asarray(parent)
        if self.parent.shape != (engine.n,) or self.parent.min() < 0 or self.parent.max() >= len(self.patches):
            raise KitError(f"parent must give each of the {engine.n} elements a patch in 0 .. {len(self.patches) - 1}")
        self.centers = patch_centers(self.patches)
        self.normals = patch_normals(self.patches)
        # the patch's own elements must not be seen: raise the base plane above every one of their corners
        own = np.einsum("mkd,md->mk", engine.quads - self.centers[self.parent][:, None, :], self.normals[self.parent])
        self.lift = np.zeros(len(self.patches))
        np.maximum.at(self.lift, self.parent, own.max(axis=1))
        self._rows: dict[int, np.ndarray] = {}
        self.counters = {"hemicubes_rendered": 0, "rows_computed": 0, "rows_cached_hits": 0}

    def row(self, p: int) -> np.ndarray:
        """Row F_p· over the elements, ``(m,)``, through :meth:`rows` (one hemicube at p's centre, cached)."""
        return self.rows([p])[0]

    def rows(self, indices: Any) -> np.ndarray:
        """Rows (k, m) for patches ``indices``; the missing ones are rendered together (many hemicubes per read-back)."""
        idx = [int(p) for p in indices]
        missing = list(dict.fromkeys(p for p in idx if p not in self._rows))
        self.counters["rows_cached_hits"] += len(idx) - len(missing)
        if missing:
            fresh = self.engine.rows_at(self.centers[missing], self.normals[missing], self.lift[missing], ids=missing)
            self._rows.update(zip(missing, fresh))
            self.counters["rows_computed"] += len(missing)
            self.counters["hemicubes_rendered"] += len(missing)
        return np.stack([self._rows[p] for p in idx])

    def matrix(self) -> np.ndarray:
        """Every patch's row (n, m)."""
        return self.rows(range(len(self.patches)))


@dataclass
class SubstructuredSolution:
    """Element radiosities, what is still unshot (per element) and the cost."""
    radiosity: np.ndarray                     # (m, 3) B of the elements
    unshot: np.ndarray                        # (m, 3) ΔB of the elements
    converged: bool
    residual: float                           # unshot energy / emitted energy
    shots: int
    seconds: float
    order: list[int] = field(default_factory=list)
    shot: np.ndarray | None = None            # (n, 3) the radiosity each patch shot in all, summed over its shots


def split_patches(patches: Any, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Each patch into k × k elements: (elements (n·k², 4, 3), parent (n·k²,))."""
    if int(k) != k or k < 1:
        raise KitError(f"elements per patch side must be a positive integer, got {k}")
    return subdivide_uniform(patches, int(k))


def solve_substructured(rows: Any, parent: np.ndarray, element_areas: np.ndarray, reflectance: np.ndarray,
                        emission: np.ndarray, tolerance: float = 1e-3, max_shots: int = 0,
                        on_shot: Callable[[int, int, np.ndarray, np.ndarray], None] | None = None,
                        radiosity: np.ndarray | None = None, unshot: np.ndarray | None = None
                        ) -> SubstructuredSolution:
    """Progressive refinement with patches shooting to elements.

    A patch's unshot energy is the sum of its elements' (ΔB_e·A_e). Patches shoot in sweeps, as in the
    notes' progressive radiosity (§2.5): each sweep in the order of the patches' energies as it starts, the
    most first. A patch shoots its mean unshot radiosity ΔB_p: every element e receives ρ_e·ΔB_p·F_pe·A_p/A_e, into
    B_e and ΔB_e; the shooter's elements' ΔB become 0. Stops when the unshot energy is at most
    ``tolerance`` of the emitted energy, or after ``max_shots``.

    ``radiosity`` and ``unshot`` (both or neither) continue from an earlier state instead of B = ΔB = E
    (cs451/stages/radiosity/bench_adaptive.py does, after refining the elements); ``shot`` in the result is what each patch
    shot in this call, summed: the shots are linear, so B is E plus every patch's ``shot`` gathered over the rows.
    """
    parent = np.asarray(parent)
    a = np.asarray(element_areas, dtype=np.float64)
    n_patches = int(parent.max()) + 1
    patch_area = np.bincount(parent, weights=a, minlength=n_patches)
    if (radiosity is None) != (unshot is None):
        raise KitError("give both radiosity and unshot to continue a solution, or neither")
    B = np.array(emission if radiosity is None else radiosity, dtype=np.float64)
    dB = B.copy() if unshot is None else np.array(unshot, dtype=np.float64)
    emitted = float((np.abs(np.asarray(emission, dtype=np.float64)).sum(axis=1) * a).sum())
    total_shot = np.zeros((n_patches, 3))
    max_shots = max_shots or 1000 * n_patches
    members = [np.flatnonzero(parent == p) for p in range(n_patches)]
    energy = np.stack([np.bincount(parent, weights=dB[:, c] * a, minlength=n_patches) for c in range(3)], axis=1)
    order: list[int] = []
    start = time.perf_counter()
    def shoot(p: int) -> None:
        shot = energy[p] / patch_area[p]
        total_shot[p] += shot
        dB[members[p]] = 0.0
        energy[p] = 0.0
        received = reflectance * (rows.row(p) * (patch_area[p] / a))[:, None] * shot[None, :]
        B[...] += received                          # in place: the sweeps' loop below holds these arrays
        dB[...] += received
        for c in range(3):                          # the elements' new unshot energy, summed per patch
            energy[:, c] += np.bincount(parent, weights=received[:, c] * a, minlength=n_patches)
        order.append(p)
        if on_shot is not None:
            on_shot(len(order), p, B, dB)

    while True:                                     # sweeps, as the notes' (and the student's R3) shoot
        key = np.abs(energy).sum(axis=1)
        sweep = [int(p) for p in np.argsort(-key, kind="stable") if key[p] > 0]   # ties to the lower index
        if not sweep:
            break
        for p in sweep:
            if len(order) >= max_shots or np.abs(energy).sum() <= tolerance * emitted:
                break
            shoot(p)
        else:
            continue
        break
    residual = float(np.abs(energy).sum() / emitted) if emitted > 0 else 0.0
    return SubstructuredSolution(B, dB, residual <= tolerance * (1 + 1e-9), residual, len(order),
                                 time.perf_counter() - start, order, total_shot)
