"""Stage 3's checks: they compare a submission's arrays with the truths' (``expected``) and compute no answer.

Shipped to students with the public tests; the closed forms themselves live in
``truth.py`` (never shipped) and reach a student copy as numbers and arrays.
"""
from __future__ import annotations

import numpy as np

from cs451.grading.checks import output
from cs451.stages.hemicube import tolerances as TOL


def table_cells(out, expected, p, key: str):
    """The table ``key`` equals its closed form cell by cell, else the first bad cell."""
    want = np.asarray(expected[key], float)
    got = output(out, key, want.shape, f"the {key} table")
    if not np.allclose(got, want, rtol=TOL.FLOAT64_RTOL, atol=TOL.CELL_ATOL):
        k = np.unravel_index(np.argmax(np.abs(got - want)), want.shape)
        return f"cell [row {k[0]}, column {k[1]}] is {got[k]:.6g}, expected {want[k]:.6g}"


def table_sum(out, expected, p):
    r = p["resolution"]
    top = output(out, "top", (r, r), "the top table")
    side = output(out, "side", (r // 2, r), "the side table")
    total = float(np.sum(top) + 4 * np.sum(side))
    bound = 0.6 / r ** 2 + TOL.MIDPOINT_SLACK     # the midpoint rule's error: 0.0021 at r = 16 (truth: exact cells sum to 1)
    if not abs(total - 1) <= bound:
        return f"top + 4 sides sum to {total:.6f}, expected 1 within {bound:.2g}"


def tetrahedron_sum(out, expected, p):
    """Three faces enclose the hemisphere: 3 × the face's cells sum to 1 within the midpoint rule's error
    (0.17/r² measured from r = 4 to 512; the cells cut by the patch's plane add to it)."""
    r = p["resolution"]
    total = 3 * float(np.sum(output(out, "face", (r, r), "the face's table")))
    bound = 0.25 / r ** 2 + TOL.MIDPOINT_SLACK
    if not abs(total - 1) <= bound:
        return f"3 faces sum to {total:.6f}, expected 1 within {bound:.2g}"


def known_row(out, expected, p, entries: list, want: list, labels: list, rtol: float):
    """Row entries summed over each list of receivers, against closed-form values."""
    got = output(out, "rows", (1, len(p["quads"])), "the rows")
    problems = []
    for label, js, value in zip(labels, entries, want):
        g = float(got[0, js].sum())
        if not abs(g - value) <= rtol * abs(value):
            problems.append(f"{label} = {g:.5f}, expected {value:.5f} (within {rtol:.1%})")
    return "; ".join(problems) or None


def row_closure(out, expected, p):
    sums = output(out, "rows", (len(p["rows"]), len(p["quads"])), "the rows").sum(axis=1)
    bad = np.abs(sums - 1) > TOL.CLOSURE
    return None if not bad.any() else f"row sums {sums.min():.4f} .. {sums.max():.4f}, expected 1 within {TOL.CLOSURE:.1%}"


def rows_like_reference(out, expected, p, atol: float = TOL.ROW_ATOL):
    """The same rows as the reference's hemicubes (same views and rotations) give, entry by entry."""
    want = np.asarray(expected["rows"], float)
    got = output(out, "rows", want.shape, "the rows")
    err = np.abs(got - want)
    if not np.isfinite(err).all() or err.max() > atol:
        i, j = np.unravel_index(np.argmax(np.where(np.isfinite(err), err, np.inf)), err.shape)
        return f"F[{int(p['rows'][i])}, {int(j)}] is {got[i, j]:.5f}, the reference's hemicube gives {want[i, j]:.5f}"
