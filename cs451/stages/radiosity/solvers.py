"""Radiosity solvers on rows of form factors: a stage-4 implementation's shooting loop, and the full-matrix
methods the benchmark compares it with (Jacobi, Gauss-Seidel as in the course notes §2.2, a direct solve).

The full-matrix methods are not student tasks; the shooting loop is (R3), so it comes in through
``calls`` (the stage's checked calls of a submission). Rows come from anything with ``row(i)``:
the hemicube engine, or :class:`MatrixRows` over a given matrix.
"""
from __future__ import annotations

import itertools
import time
from dataclasses import dataclass, field as dc_field, replace
from typing import Any, Callable, Literal

import numpy as np

from ...errors import KitError


class MatrixRows:
    """Rows of a given form-factor matrix, with the same interface and counters as the hemicube engine."""

    def __init__(self, matrix: np.ndarray):
        self.F = np.asarray(matrix, dtype=np.float64)
        self.counters = {"hemicubes_rendered": 0, "rows_computed": 0, "rows_cached_hits": 0}
        self._seen: set[int] = set()

    def row(self, i: int) -> np.ndarray:
        """Row ``i`` ``(n,)``, counted as the engine counts: computed the first time, a cache hit after."""
        if i in self._seen:
            self.counters["rows_cached_hits"] += 1
        else:
            self._seen.add(i)
            self.counters["rows_computed"] += 1
        return self.F[i]

    def rows(self, indices: Any) -> np.ndarray:
        """Rows ``indices`` stacked ``(k, n)``, each counted as :meth:`row` counts it."""
        return np.stack([self.row(int(i)) for i in indices])

    def matrix(self) -> np.ndarray:
        """The whole matrix ``(n, n)``, through :meth:`rows` (so every row is counted)."""
        return self.rows(range(len(self.F)))


@dataclass
class Solution:
    """A solve's result, its cost and whether it met the tolerance."""
    radiosity: np.ndarray            # (m, 3) B
    unshot: np.ndarray               # (m, 3) ΔB (zero for the full-matrix methods)
    display: np.ndarray              # (m, 3) what is drawn: B, plus ρ·ambient when asked
    method: str
    converged: bool
    residual: float                  # unshot (or residual) energy / emitted energy
    steps: int                       # shots or sweeps
    seconds: float
    order: list[int] = dc_field(default_factory=list)
    counters: dict[str, int] = dc_field(default_factory=dict)
    reciprocity: dict[str, Any] | None = None   # what enforcing reciprocity changed (cs451.stages.radiosity.reciprocity)

    @property
    def summary(self) -> str:
        """One line: the method, whether it converged, its steps, residual and time."""
        what = "shots" if self.method == "progressive" else "sweeps" if self.method != "direct" else "solve"
        state = "converged" if self.converged else "did NOT converge (best state returned)"
        return (f"radiosity {self.method}: {state} after {self.steps} {what}, residual {self.residual:.3g} of the "
                f"emitted energy, {self.seconds:.2f} s")

    @property
    def message(self) -> str:
        """The summary and every counter (``--verbose``)."""
        counters = ", ".join(f"{k.replace('_', ' ')} {v}" for k, v in self.counters.items())
        message = self.summary + (f"; {counters}" if counters else "")
        if self.reciprocity is not None:
            from .reciprocity import describe
            message += "\n" + describe(self.reciprocity)
        return message


def energy(values: np.ndarray, areas: np.ndarray) -> float:
    """Σ_j |values_j|·A_j over all channels."""
    return float((np.abs(values).sum(axis=1) * areas).sum())


def validate_system(areas: np.ndarray, reflectance: np.ndarray, emission: np.ndarray) -> None:
    """Refuse, before any shot, a system holding NaN or infinity, negative emission, a patch without positive
    area, or a reflectance outside [0, 1]."""
    for name, arr in (("areas", areas), ("reflectance", reflectance), ("emission", emission)):
        if not np.isfinite(arr).all():
            raise KitError(f"radiosity: {name} contains NaN or infinite values")
    if (emission < 0).any():
        raise KitError("radiosity: negative emission")
    if (areas <= 0).any():
        raise KitError(f"radiosity: patch {int(np.argmin(areas))} has zero area")
    if (reflectance < 0).any() or (reflectance > 1).any():
        raise KitError("radiosity: reflectance must lie in [0, 1]")


class RowsAhead:
    """Rows for a shooting loop: a row not rendered yet is rendered in one batch with the rows of the patches most
    likely to shoot next, those with the most unshot energy (ΔB·A, as last seen) whose rows are not rendered yet.

    A hemicube engine draws a batch of hemicubes for the price of little more than one read-back, and the notes'
    sweeps (R3) shoot in the order of exactly these keys, so most rows rendered ahead are used. ``ahead`` extra rows
    per batch (0: one row at a time); ``most`` > ``ahead``: the batch doubles after each one, up to ``most`` extra
    rows, so a solve that keeps asking for new rows (a large scene shoots nearly every patch) waits on a few large
    read-backs, not on hundreds of small ones. Counted: ``rows_ahead`` rendered ahead, ``rows_ahead_unused`` never
    asked for.
    """

    def __init__(self, rows: Any, areas: np.ndarray, emission: np.ndarray, ahead: int, most: int = 0):
        self.source, self.areas, self.ahead = rows, areas, max(0, int(ahead))
        self.most = max(self.ahead, int(most))
        self.unshot = np.asarray(emission, dtype=np.float64)   # ΔB starts as E
        self.asked: set[int] = set()
        self.rendered_ahead: set[int] = set()
        self.can_batch = self.ahead > 0 and hasattr(rows, "rows") and hasattr(rows, "has_row")

    def seen(self, unshot: np.ndarray) -> None:
        """The loop's ΔB after a shot (its ``on_shot``): the keys the next batch is chosen by."""
        self.unshot = unshot

    def row(self, i: int) -> np.ndarray:
        """Row ``i``; one not rendered yet comes in one batch with the rows of the likeliest next shooters (the batch
        growing each time, up to ``most``)."""
        self.asked.add(i)
        if self.can_batch and not self.source.has_row(i):
            key = np.abs(self.unshot).sum(axis=1) * self.areas
            order = np.argsort(-key, kind="stable")
            likely = list(itertools.islice((int(j) for j in order[key[order] > 0]
                                            if j != i and not self.source.has_row(int(j))), self.ahead))
            self.rendered_ahead.update(likely)
            self.ahead = min(2 * self.ahead + 1, self.most)
            return self.source.rows([i, *likely])[0]   # row i from the batch: not counted again as a cache hit
        return self.source.row(i)

    def counters(self) -> dict[str, int]:
        """How many rows were rendered ahead, and how many of those the loop never asked for."""
        return {"rows_ahead": len(self.rendered_ahead), "rows_ahead_unused": len(self.rendered_ahead - self.asked)}


def solve_progressive(calls: Any, rows: Any, areas: np.ndarray, reflectance: np.ndarray, emission: np.ndarray,
                      tolerance: float = 1e-3, max_shots: int = 0, overshoot: float = 1.0, use_ambient: bool = True,
                      on_shot: Callable | None = None, rows_ahead: int = 0, known: dict | None = None,
                      rows_ahead_most: int = 0) -> Solution:
    """Run a stage-4 implementation's shooting loop (``calls.progressive``, R3, checked) on rows from
    ``rows.row(i)``, and its ambient term (``calls.ambient``, R4) for the display; counts rows and skipped patches.

    ``rows_ahead`` > 0 renders that many likely next shooters' rows with each row not yet rendered
    (:class:`RowsAhead`; only for a source with ``rows`` and ``has_row``, the hemicube engine), doubling after each
    batch up to ``rows_ahead_most``. With ``known``
    (patch → row, kept from an earlier solve of the same patches) the implementation's R6 solves instead, asking
    ``rows`` only for the rows it does not know, and adds them to ``known``."""
    validate_system(areas, reflectance, emission)
    n = len(areas)
    max_shots = max_shots or 1000 * n
    fetched: list[int] = []
    source = RowsAhead(rows, areas, emission, rows_ahead, rows_ahead_most)

    def row(i: Any) -> np.ndarray:
        i = int(i)
        if not 0 <= i < n:
            raise KitError(f"R3 progressive_refinement() asked for row {i} of {n}")
        fetched.append(i)
        return np.array(source.row(i), dtype=np.float64)

    def shot(shots: int, i: int, radiosity: np.ndarray, unshot: np.ndarray) -> None:
        source.seen(unshot)
        if on_shot is not None:
            on_shot(shots, i, radiosity, unshot)

    start = time.perf_counter()
    args = (row, areas.copy(), reflectance.copy(), emission.copy(), float(tolerance), int(max_shots), float(overshoot),
            shot if source.can_batch or on_shot is not None else None)
    radiosity, unshot, order = calls.progressive(*args) if known is None else calls.again(known, *args)
    seconds = time.perf_counter() - start
    emitted = energy(emission, areas)
    residual = energy(unshot, areas) / emitted if emitted > 0 else 0.0
    # with every patch reflecting all of a colour, ρ_avg = 1 and R = 1/(1 − ρ_avg) is infinite: show B alone
    ambient_defined = not np.all(reflectance >= 1.0, axis=0).any()
    display = (radiosity + reflectance * calls.ambient(areas, reflectance, unshot)
               if use_ambient and ambient_defined else radiosity)
    counters = dict(getattr(rows, "counters", {}))
    if source.can_batch:
        counters.update(source.counters())
    counters.update(patches=n, shots=len(order), distinct_shooters=len(set(order)), rows_requested=len(fetched),
                    patches_never_shot=n - len(set(order)),
                    zero_albedo_receivers=int((reflectance.max(axis=1) == 0).sum()))
    return Solution(radiosity, unshot, display, "progressive", residual <= tolerance * (1 + 1e-9), residual,
                    len(order), seconds, order, counters)


def shooting_matrix(F: np.ndarray, areas: np.ndarray) -> np.ndarray:
    """The form factors shooting uses: F̃_ji = F_ij·A_i/A_j, from the shooters' rows.

    Progressive refinement takes row i (from patch i's hemicube) and spreads patch i's energy
    with it; the gathering form B_j = E_j + ρ_j Σ_i F_ji B_i would take column entries from the
    receivers' hemicubes instead. With exact reciprocity (A_i F_ij = A_j F_ji) the two are equal;
    hemicube rows are not exactly reciprocal (a small bright light covers few cells of a distant
    receiver's hemicube), so the full-matrix solvers are run on F̃ to solve the same equations.
    """
    F = np.asarray(F, dtype=np.float64)
    return (F * areas[:, None] / areas[None, :]).T


def system_matrix(F: np.ndarray, reflectance: np.ndarray, channel: int) -> np.ndarray:
    """I − diag(ρ_c)·F for one colour channel."""
    return np.eye(len(F)) - reflectance[:, channel:channel + 1] * F


def residual_energy(F: np.ndarray, areas: np.ndarray, reflectance: np.ndarray, emission: np.ndarray,
                    B: np.ndarray) -> float:
    """Σ|E + ρFB − B|·A over all channels: how far B is from solving the radiosity equation (in energy)."""
    return energy(emission + reflectance * (F @ B) - B, areas)


def solve_direct(F: np.ndarray, reflectance: np.ndarray, emission: np.ndarray) -> np.ndarray:
    """B from (I − ρF)B = E, one dense LU solve per channel; a clear error when the system is singular."""
    B = np.empty_like(np.asarray(emission, dtype=np.float64))
    for c in range(3):
        M = system_matrix(F, reflectance, c)
        try:
            B[:, c] = np.linalg.solve(M, emission[:, c])
        except np.linalg.LinAlgError:
            raise KitError("radiosity: (I − ρF) is singular (an albedo of 1 in a closed scene?): no solution") from None
        if np.linalg.cond(M, 1) > 1e14:
            raise KitError("radiosity: (I − ρF) is numerically singular (an albedo of 1 in a closed scene?): no solution")
    return B


def solve_iterative(method: Literal["jacobi", "gauss-seidel"], F: np.ndarray, areas: np.ndarray, reflectance: np.ndarray,
                    emission: np.ndarray, tolerance: float = 1e-3, max_sweeps: int = 0,
                    on_sweep: Callable[[int, np.ndarray], None] | None = None) -> Solution:
    """Jacobi (B ← E + ρFB, all at once) or Gauss-Seidel (patch by patch, using the newest values), on the full matrix.

    Stops when the residual energy Σ|E + ρFB − B|·A is at most ``tolerance`` of the emitted energy.
    """
    validate_system(areas, reflectance, emission)
    n = len(areas)
    max_sweeps = max_sweeps or 10_000
    F = np.asarray(F, dtype=np.float64)
    B = np.array(emission, dtype=np.float64)
    emitted = energy(emission, areas)
    start = time.perf_counter()
    sweeps, residual = 0, residual_energy(F, areas, reflectance, emission, B) / max(emitted, 1e-300)
    K = reflectance[:, None, :] * F[:, :, None]                      # (n, n, 3): ρ_i F_ij
    while residual > tolerance and sweeps < max_sweeps:
        if method == "jacobi":
            B = emission + np.einsum("ijc,jc->ic", K, B)
        else:  # Gauss-Seidel as in the notes: B_i = (E_i + ρ_i Σ_{j≠i} F_ij B_j) / (1 − ρ_i F_ii), in place
            for i in range(n):
                B[i] = (emission[i] + (K[i] * B).sum(axis=0) - K[i, i] * B[i]) / (1.0 - K[i, i])
        sweeps += 1
        residual = residual_energy(F, areas, reflectance, emission, B) / max(emitted, 1e-300)
        if on_sweep is not None:
            on_sweep(sweeps, B)
    seconds = time.perf_counter() - start
    return Solution(B, np.zeros_like(B), B, method, residual <= tolerance, residual, sweeps, seconds)


def reciprocal_rows(rows: Any, areas: np.ndarray) -> tuple[MatrixRows, dict[str, Any]]:
    """Every row of ``rows`` (its ``matrix()``), made reciprocal with each row's sum kept
    (:func:`cs451.stages.radiosity.reciprocity.enforce_reciprocity`), as :class:`MatrixRows`, and the report.

    A shooting loop on these rows spreads a uniform field uniformly: receiver j gets Σ_i F_ij A_i/A_j = Σ_i F_ji."""
    from .reciprocity import enforce_reciprocity
    F, report = enforce_reciprocity(rows.matrix(), areas)
    return MatrixRows(F), report


def solve(patches: Any, calls: Any, opts: Any, rows: Any, on_shot: Callable | None = None,
          rows_ahead: int = 0, rows_ahead_most: int = 0) -> Solution:
    """Solve a scene's patches with the solver ``opts.solver`` names, on ``rows`` (the hemicube engine's, say).

    With ``opts.reciprocity`` every row is taken first and made reciprocal (:func:`reciprocal_rows`); the solvers,
    the shooting loop included, run on that matrix, and the solution's ``reciprocity`` says what changed."""
    a, rho, E = patches.areas, patches.reflectance, patches.emission
    if getattr(opts, "reciprocity", False):
        corrected, report = reciprocal_rows(rows, a)
        sol = solve(patches, calls, replace(opts, reciprocity=False), corrected, on_shot, rows_ahead, rows_ahead_most)
        shooting = {k: v for k, v in sol.counters.items() if k not in corrected.counters}
        sol.counters = {**dict(getattr(rows, "counters", {})), **shooting}
        sol.reciprocity = report
        return sol
    if opts.solver == "progressive":
        return solve_progressive(calls, rows, a, rho, E, opts.tolerance, opts.max_shots, opts.overshoot, opts.ambient,
                                 on_shot, rows_ahead, rows_ahead_most=rows_ahead_most)
    F = shooting_matrix(rows.matrix(), a)
    if opts.solver == "direct":
        start = time.perf_counter()
        B = solve_direct(F, rho, E)
        residual = residual_energy(F, a, rho, E, B) / max(energy(E, a), 1e-300)
        return Solution(B, np.zeros_like(B), B, "direct", True, residual, 1, time.perf_counter() - start,
                        counters=dict(getattr(rows, "counters", {})))
    sol = solve_iterative(opts.solver, F, a, rho, E, opts.tolerance, opts.max_shots)  # type: ignore[arg-type]
    sol.counters = dict(getattr(rows, "counters", {}))
    return sol
