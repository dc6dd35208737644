"""R2-R4: progressive refinement radiosity (Cohen, Chen, Wallace & Greenberg 1988), as notes §2.5 write it.

Every array has one row per patch and, for colours, three columns (red, green, blue):
areas (n,), reflectance (n, 3) in [0, 1], emission (n, 3), radiosity and unshot radiosity (n, 3).
A row of form factors is (n,): ``row[j]`` is F_ij, the fraction of the energy leaving patch i
that reaches patch j.
"""
from __future__ import annotations

import heapq
from typing import Callable

import numpy as np

# BEGIN SOLUTION
ONES = np.ones(3)   # |ΔB| @ ONES sums the three channels (a matrix-vector product: faster than .sum(axis=1))
# END SOLUTION


def shoot(i: int, row: np.ndarray, areas: np.ndarray, reflectance: np.ndarray,
          radiosity: np.ndarray, unshot: np.ndarray) -> tuple:
    """Shoot patch ``i``'s unshot radiosity to every patch, once.

    For every patch j: ΔRad_j = ρ_j · ΔB_i · F_ij · A_i / A_j (per colour channel), added to
    both B_j and ΔB_j; then ΔB_i = 0. ``row`` is F_i (n,). Returns ``(radiosity, unshot)``,
    the updated arrays (updating the arrays passed in, in place, is allowed).
    """
    # BEGIN SOLUTION R2: ΔRad_j = ρ_j ΔB_i F_ij A_i / A_j into B and ΔB, then ΔB_i = 0 (handout §R2)
    delta = unshot[i].copy()
    received = np.outer(row * (areas[i] / areas), delta)    # F_ij A_i / A_j · ΔB_i, per channel
    received *= reflectance
    radiosity += received                    # in place: a solve shoots thousands of times
    unshot += received
    unshot[i] = 0.0
    return radiosity, unshot
    # END SOLUTION


def progressive_refinement(row: Callable[[int], np.ndarray], areas: np.ndarray, reflectance: np.ndarray,
                           emission: np.ndarray, tolerance: float, max_shots: int, overshoot: float,
                           on_shot: Callable | None) -> tuple:
    """Solve for the radiosities by shooting, in sweeps ordered by a max-heap, as the course notes write it (§2.5).

    Start with B = ΔB = E. Each sweep (one "Gauss-Seidel iteration" of the notes) builds a max-heap
    with :mod:`heapq` of every patch whose key ``(|ΔB_i,r| + |ΔB_i,g| + |ΔB_i,b|)·A_i`` (channels
    summed, then times the area) is above 0, keyed as the sweep starts (ties go to the lower index),
    then pops the patches in that order; each fetches its form factors with ``row(i)`` and shoots
    its current ΔB (R2). A patch lit for the first time during a sweep waits for the next one.
    Before every shot, stop when the total unshot energy (the keys' sum) is at most ``tolerance``
    times the total emitted energy ``Σ_j (E_j,r + E_j,g + E_j,b)·A_j``, or when ``max_shots`` shots
    are done; stop too when a sweep would be empty.

    ``overshoot`` ω (1 = plain shooting) shoots ω·ΔB_i instead and leaves ΔB_i = (1 − ω)·ΔB_i.
    If ``on_shot`` is not None, call ``on_shot(shots, i, radiosity, unshot)`` after every shot:
    ``shots`` counts the shots so far, this one included, and the arrays are those after it.

    Returns ``(radiosity, unshot, order)``: B (n, 3), ΔB (n, 3) and the patches shot, in order (list of int).
    """
    # BEGIN SOLUTION R3: a heap of (-key, index) built at each sweep's start; pop it to the end, shooting (handout §R3)
    areas = np.asarray(areas, dtype=np.float64)
    radiosity = np.array(emission, dtype=np.float64)
    unshot = radiosity.copy()
    key = np.abs(unshot) @ ONES * areas
    total_emitted = float((np.asarray(emission).sum(axis=1) * areas).sum())
    order: list[int] = []
    while True:
        heap = [(-key[j], j) for j in np.flatnonzero(key > 0).tolist()]
        if not heap:
            break
        heapq.heapify(heap)
        while heap:
            if len(order) >= max_shots or key.sum() <= tolerance * total_emitted:
                return radiosity, unshot, order
            _, i = heapq.heappop(heap)
            amount = overshoot * unshot[i]
            left = unshot[i] - amount
            unshot[i] = amount
            f = row(i)
            radiosity, unshot = shoot(i, f, areas, reflectance, radiosity, unshot)
            unshot[i] = left
            order.append(i)
            key = np.abs(unshot) @ ONES * areas    # every key again: cheaper than picking the changed ones
            if on_shot is not None:
                on_shot(len(order), i, radiosity, unshot)
    return radiosity, unshot, order
    # END SOLUTION


def ambient_term(areas: np.ndarray, reflectance: np.ndarray, unshot: np.ndarray) -> np.ndarray:
    """The 1988 paper's ambient term, for previews: (3,), one value per channel.

    ρ_avg = Σ ρ_j A_j / Σ A_j, R = 1 / (1 − ρ_avg), ambient = R · Σ ΔB_j A_j / Σ A_j, with ΔB
    signed as it is (negative after overshooting). The preview shows B_j + ρ_j · ambient. The
    kit never calls this where ρ_avg = 1.
    """
    # BEGIN SOLUTION R4: area-weighted averages of the reflectance and of the unshot radiosity (handout §R4)
    total = areas.sum()
    rho_avg = (reflectance * areas[:, None]).sum(axis=0) / total
    return (unshot * areas[:, None]).sum(axis=0) / total / (1.0 - rho_avg)
    # END SOLUTION
