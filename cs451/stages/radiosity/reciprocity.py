"""Reciprocal form factors from computed rows: A_i F_ij = A_j F_ji, each row keeping its sum.

Why: progressive refinement (notes §2.5) spreads patch i's unshot energy with patch i's own row,
F_ij·A_i/A_j to each receiver j, while the gathering equation it stands for (notes §2.2, eq. 4–5)
uses the receivers' rows; the two agree only through reciprocity (notes §2.2, eq. 3). A hemicube
row is computed from its shooter's centre alone (notes §2.4), so the rows of two patches are not
exactly reciprocal, and in a uniform field a receiver j gets Σ_i F_ij·A_i/A_j, which equals j's own
row sum (1 in a closed scene) only when they are. Hence the furnace's patches scatter by a few
percent around B = E/(1 − ρ) although its mean is exact. :func:`enforce_reciprocity` makes the rows
reciprocal and keeps every row's sum, so that a closed scene still conserves energy.

How: G = (AF + (AF)ᵀ)/2 is symmetric (AF: row i of F times A_i); the symmetric Sinkhorn–Knopp
scaling d ← √(d · r / (G d)) finds D = diag(d) with row sums of D G D equal to r_i = A_i·Σ_j F_ij,
and F'_ij = d_i G_ij d_j / A_i. A F' = D G D is symmetric (reciprocity) and F' keeps F's row sums.

Guarantees: on return every row sum of F' is within ``tolerance`` (relative) of F's
and A F' is symmetric to rounding; entries stay non-negative; an entry that is 0 both ways (i and
j do not see each other) stays 0. Costs: every row (so the whole matrix, n hemicubes, where shooting
would have rendered only its shooters' rows), :data:`MATRICES` n × n float64 arrays of memory at the peak,
and O(n²) work per iteration (50–200 iterations for hemicube rows: about 1 ms for 100 patches, 0.2 s
for 900 and 2 s for 2,400 on one core, the measuring included; :data:`MAX_ITERATIONS` at most).

Where it cannot hold: a row of sum 0 (a patch that sees nothing: it faces an opening, or its hemicube
is blind) asks reciprocity for a column of zeros too, so the patch receives nothing and what others
sent it goes to the rest of their rows (counted: ``empty_rows``). Open scenes: rows keep the sums the
hemicube gave them (the light leaving through the opening is kept as measured), which reciprocity
cannot check. Patches of zero area carry no reciprocity and are refused. Where no reciprocal matrix
has the rows' sums (a group of patches that see only each other but whose sums disagree), the scaling
stalls and a :class:`~cs451.errors.KitError` says so.
"""
from __future__ import annotations

import time
from typing import Any

import numpy as np

from ...errors import KitError

TOLERANCE = 1e-12       # relative row-sum error the scaling stops at
MAX_ITERATIONS = 10_000
MATRICES = 5            # n × n float64 arrays alive at the peak, the input's included (one more with rows of sum 0)
STALL_WINDOW = 100      # iterations over which the row-sum error must at least halve, or the scaling is refused
SIGNIFICANT = 1e-3      # pairs compared entry by entry: both A_i F_ij and A_j F_ji above this fraction of the largest


def _checked(F: Any, areas: Any) -> tuple[np.ndarray, np.ndarray]:
    if hasattr(F, "matrix") and not isinstance(F, np.ndarray):
        F = F.matrix()
    F = np.asarray(F, dtype=np.float64)
    a = np.asarray(areas, dtype=np.float64)
    if F.ndim != 2 or F.shape[0] != F.shape[1]:
        raise KitError(f"reciprocity: form factors must be a square (n, n) matrix, got shape {F.shape}")
    if a.shape != (len(F),):
        raise KitError(f"reciprocity: areas must have shape ({len(F)},) for {len(F)} patches, got {a.shape}")
    if not np.isfinite(F).all():
        raise KitError("reciprocity: form factors contain NaN or infinite values")
    if not np.isfinite(a).all():
        raise KitError("reciprocity: areas contain NaN or infinite values")
    if (F < 0).any():
        i, j = np.unravel_index(int(np.argmin(F)), F.shape)
        raise KitError(f"reciprocity: form factor F[{i}, {j}] = {F[i, j]:.3g} is negative")
    if (a <= 0).any():
        raise KitError(f"reciprocity: patch {int(np.argmin(a))} has area {a.min():.3g} (areas must be positive)")
    return F, a


def _measure(AF: np.ndarray) -> tuple[dict[str, float], np.ndarray]:
    """:func:`reciprocity_error` of A F, and which pairs it compared entry by entry (3 n × n temporaries)."""
    scale = np.maximum(AF, AF.T)
    diff = np.subtract(AF, AF.T)
    np.abs(diff, out=diff)
    total = float(diff.sum() / max(2.0 * AF.sum(), 1e-300))
    work = np.subtract(scale, diff)                           # min(A_i F_ij, A_j F_ji) = max − |difference|
    significant = work > SIGNIFICANT * max(float(scale.max()), 1e-300)
    np.divide(diff, scale, out=work, where=significant)
    worst = float(work.max(initial=0.0, where=significant))
    return {"max": worst, "total": total}, significant


def reciprocity_error(F: Any, areas: Any) -> dict[str, float]:
    """How far A F is from symmetric: the largest relative difference |A_i F_ij − A_j F_ji| / max(both) over pairs
    that both see each other clearly (both above 1e-3 of the largest), and the total Σ|difference| / (2 Σ A F).

    The same measure as :meth:`HemicubeFormFactors.report` (there on the rows computed so far)."""
    F, a = _checked(F, areas)
    return _measure(F * a[:, None])[0]


def _scaling(G: np.ndarray, target: np.ndarray, tolerance: float, max_iterations: int
             ) -> tuple[np.ndarray, int, float]:
    """d (n,) with d_i Σ_j G_ij d_j = target_i: symmetric Sinkhorn–Knopp, d ← √(d · target / (G d)).

    Stops at a relative row-sum error of ``tolerance``; refuses when the error stops falling (no such d)."""
    d = np.ones(len(target))
    iterations, checkpoint = 0, np.inf
    while True:
        sums = d * (G @ d)
        error = float(np.abs(sums / target - 1).max())
        if error <= tolerance:
            return d, iterations, error
        if iterations % STALL_WINDOW == 0:
            if error > 0.5 * checkpoint or iterations >= max_iterations:
                raise KitError(f"reciprocity: no reciprocal form factors keep these row sums (the scaling stalled at "
                               f"a row-sum error of {error:.2g} after {iterations} iterations)")
            checkpoint = error
        d *= np.sqrt(target / sums)
        iterations += 1


def enforce_reciprocity(F: Any, areas: Any, tolerance: float = TOLERANCE,
                        max_iterations: int = MAX_ITERATIONS) -> tuple[np.ndarray, dict[str, Any]]:
    """F' (n, n) with A_i F'_ij = A_j F'_ji and Σ_j F'_ij = Σ_j F_ij, and a report of what changed.

    ``F`` (n, n) float, or anything with ``matrix()`` (the hemicube engine: every row is computed);
    ``areas`` (n,) float, positive. The report: ``iterations``, ``seconds``, ``row_sum_error`` (largest relative
    row-sum difference left), ``entry_change_max`` / ``entry_change_mean`` (relative change |F' − F| / F over the
    entries of clearly-seeing pairs), ``energy_moved`` (Σ A|F' − F| / Σ A F), ``reciprocity_before`` /
    ``reciprocity_after`` (:func:`reciprocity_error`'s max and total), ``empty_rows`` (rows of sum 0).
    """
    if not (np.isfinite(tolerance) and 0 < tolerance < 1):
        raise KitError(f"reciprocity: tolerance must lie in (0, 1), got {tolerance}")
    if int(max_iterations) != max_iterations or max_iterations < 1:
        raise KitError(f"reciprocity: max_iterations must be a positive integer, got {max_iterations}")
    F, a = _checked(F, areas)
    start = time.perf_counter()
    AF = F * a[:, None]                                       # A_i F_ij
    target = AF.sum(axis=1)                                   # r_i = A_i Σ_j F_ij
    before, significant = _measure(AF)
    G = np.add(AF, AF.T)
    G *= 0.5
    empty = target <= 0
    G[empty, :] = 0.0                                         # a patch that sees nothing is seen by none
    G[:, empty] = 0.0
    live = ~empty
    d, iterations, error = np.zeros(len(F)), 0, 0.0
    if live.any():
        Gl = G if live.all() else G[np.ix_(live, live)]
        reach = Gl.sum(axis=1)
        if (reach <= 0).any():
            k = int(np.flatnonzero(live)[np.argmin(reach)])
            raise KitError(f"reciprocity: patch {k} sees only patches that see nothing: no reciprocal rows keep its sum")
        d[live], iterations, error = _scaling(Gl, target[live], tolerance, int(max_iterations))
        del Gl
    H = G                                                     # A F' = D G D, in place
    H *= d[:, None]
    H *= d[None, :]
    seconds = time.perf_counter() - start
    change = np.subtract(H, AF)
    np.abs(change, out=change)
    moved = float(change.sum() / max(float(target.sum()), 1e-300))
    keep = significant & (AF > 0)
    np.divide(change, AF, out=change, where=keep)             # |F' − F| / F: the same in A F, row by row
    count = int(keep.sum())
    change_max = float(change.max(initial=0.0, where=keep))
    change_mean = float(change.sum(where=keep) / count) if count else 0.0
    del change, AF, keep, significant
    after, _ = _measure(H)
    H /= a[:, None]                                           # F'
    report = {"patches": len(F), "iterations": iterations, "seconds": seconds, "tolerance": float(tolerance),
              "row_sum_error": error, "entry_change_max": change_max, "entry_change_mean": change_mean,
              "energy_moved": moved,
              "reciprocity_before": before, "reciprocity_after": after, "empty_rows": int(empty.sum())}
    return H, report


def describe(report: dict[str, Any]) -> str:
    """One line for ``--verbose``: what the correction changed, and what it cost."""
    b, a = report["reciprocity_before"], report["reciprocity_after"]
    empty = f", {report['empty_rows']} rows of sum 0 left empty" if report["empty_rows"] else ""
    return (f"reciprocity enforced on {report['patches']} rows: error max {b['max']:.2%} → {a['max']:.1e} "
            f"(total {b['total']:.2%} → {a['total']:.1e}); entries changed by {report['entry_change_mean']:.2%} on average, "
            f"{report['entry_change_max']:.2%} at most ({report['energy_moved']:.2%} of the energy moved); row sums kept "
            f"within {report['row_sum_error']:.1e}; {report['iterations']} Sinkhorn iterations, "
            f"{report['seconds']:.3f} s{empty}")
