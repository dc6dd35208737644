"""The reference's hierarchy, built once per geometry: a binned-SAH build and the eight-wide layout the
compiled kernels traverse, both in numba, each kept in a small cache keyed by a digest of the arrays it
was made from (so renders and demo frames of the same geometry build nothing), with counts of what was
built and what was reused. A student's starter has no copy of it.
"""
from __future__ import annotations

import math
from collections import OrderedDict
from typing import Any, Callable

import numpy as np
from numba import njit

from ....tracescene import TraceScene, content_key

from .running import compiled

_JIT = dict(cache=True, nogil=True, error_model="numpy")
BINS = 16
#: Children per row of the kernels' hierarchy: eight float32 boxes are one AVX register per plane, and an
#: eight-wide tree is about two thirds as deep as a four-wide one (measured on the torus against the four-wide
#: float64 rows it replaced: the same hits, 1.1-1.2x the closest-hit rays a second; its whole frame within noise).
WIDTH = 8


class GeometryCache:
    """The last few results of ``make``, keyed by the digest of its input arrays; counts builds and reuses.

    Callers must not change what they are handed (``built`` hands out copies).
    """

    def __init__(self, size: int = 4):
        self.size = size
        self.built = 0
        self.reused = 0
        self._items: OrderedDict[str, Any] = OrderedDict()

    def get(self, key: str, make: Callable[[], Any]) -> Any:
        """The value for ``key``: the kept one (counted as reused, now the most recent), else ``make()`` kept and
        counted as built, the least recent dropped past ``size``."""
        if key in self._items:
            self._items.move_to_end(key)
            self.reused += 1
            return self._items[key]
        value = make()
        self._items[key] = value
        self.built += 1
        while len(self._items) > self.size:
            self._items.popitem(last=False)
        return value

    def clear(self) -> None:
        """Forget every kept value (the counts stay), so that the next ``get`` of each key builds it again."""
        self._items.clear()


#: Built hierarchies (``build_bvh``) and their eight-wide layouts with the scene's arrays (``packed``).
HIERARCHIES = GeometryCache()
LAYOUTS = GeometryCache()


def cache_counts() -> dict[str, int]:
    """How many hierarchies and kernel layouts were built, and how many times one was reused."""
    return {"hierarchies_built": HIERARCHIES.built, "hierarchies_reused": HIERARCHIES.reused,
            "layouts_built": LAYOUTS.built, "layouts_reused": LAYOUTS.reused}


@njit(**_JIT)
def _area(lo, hi):
    ex, ey, ez = hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]
    return ex * ey + ey * ez + ez * ex


@njit(**_JIT)
def build(lo, hi, leaf_size):
    """Top-down build with a binned surface area heuristic (16 bins per axis), partitioning in place.

    Returns the arrays of the hierarchy format (bvh.py): lo, hi, child, start, count, order.
    """
    bins = BINS
    n = lo.shape[0]
    cen = 0.5 * (lo + hi)
    order = np.arange(n)
    cap = 2 * n + 1
    nlo = np.empty((cap, 3))
    nhi = np.empty((cap, 3))
    child = np.full(cap, -1, np.int64)
    start = np.zeros(cap, np.int64)
    count = np.zeros(cap, np.int64)
    stack = np.empty((cap, 3), np.int64)
    stack[0, 0], stack[0, 1], stack[0, 2] = 0, 0, n
    sp = 1
    m = 1
    blo = np.empty((bins, 3))
    bhi = np.empty((bins, 3))
    bcount = np.empty(bins, np.int64)
    right_area = np.empty(bins)
    acc_lo = np.empty(3)
    acc_hi = np.empty(3)
    clo = np.empty(3)
    chi = np.empty(3)
    while sp > 0:
        sp -= 1
        node, s, e = stack[sp, 0], stack[sp, 1], stack[sp, 2]
        for a in range(3):
            nlo[node, a], nhi[node, a] = math.inf, -math.inf
            clo[a], chi[a] = math.inf, -math.inf
        for j in range(s, e):
            k = order[j]
            for a in range(3):
                nlo[node, a] = min(nlo[node, a], lo[k, a])
                nhi[node, a] = max(nhi[node, a], hi[k, a])
                clo[a] = min(clo[a], cen[k, a])
                chi[a] = max(chi[a], cen[k, a])
        cnt = e - s
        if cnt <= leaf_size:
            start[node] = s
            count[node] = cnt
            continue
        best_cost, best_axis, best_bin = math.inf, -1, 0
        for axis in range(3):
            extent = chi[axis] - clo[axis]
            if extent <= 0.0:
                continue
            for b in range(bins):
                bcount[b] = 0
                for a in range(3):
                    blo[b, a], bhi[b, a] = math.inf, -math.inf
            for j in range(s, e):
                k = order[j]
                b = min(int((cen[k, axis] - clo[axis]) / extent * bins), bins - 1)
                bcount[b] += 1
                for a in range(3):
                    blo[b, a] = min(blo[b, a], lo[k, a])
                    bhi[b, a] = max(bhi[b, a], hi[k, a])
            for a in range(3):
                acc_lo[a], acc_hi[a] = math.inf, -math.inf
            for b in range(bins - 1, 0, -1):
                for a in range(3):
                    acc_lo[a] = min(acc_lo[a], blo[b, a])
                    acc_hi[a] = max(acc_hi[a], bhi[b, a])
                right_area[b] = _area(acc_lo, acc_hi)
            for a in range(3):
                acc_lo[a], acc_hi[a] = math.inf, -math.inf
            left_n = 0
            for b in range(bins - 1):
                left_n += bcount[b]
                for a in range(3):
                    acc_lo[a] = min(acc_lo[a], blo[b, a])
                    acc_hi[a] = max(acc_hi[a], bhi[b, a])
                if left_n == 0 or left_n == cnt:
                    continue
                cost = _area(acc_lo, acc_hi) * left_n + right_area[b + 1] * (cnt - left_n)
                if cost < best_cost:
                    best_cost, best_axis, best_bin = cost, axis, b
        if best_axis < 0:
            mid = s + cnt // 2          # all centroids coincide: split the range in half
        else:
            extent = chi[best_axis] - clo[best_axis]
            i, j = s, e - 1
            while i <= j:              # partition: bins up to best_bin to the left
                b = min(int((cen[order[i], best_axis] - clo[best_axis]) / extent * bins), bins - 1)
                if b <= best_bin:
                    i += 1
                else:
                    order[i], order[j] = order[j], order[i]
                    j -= 1
            mid = i
        c = m
        m += 2
        child[node] = c
        stack[sp, 0], stack[sp, 1], stack[sp, 2] = c + 1, mid, e
        sp += 1
        stack[sp, 0], stack[sp, 1], stack[sp, 2] = c, s, mid
        sp += 1
    return nlo[:m].copy(), nhi[:m].copy(), child[:m].copy(), start[:m].copy(), count[:m].copy(), order


def built(lo: np.ndarray, hi: np.ndarray, leaf_size: int) -> dict[str, np.ndarray]:
    """The hierarchy over boxes (lo, hi), from the cache when the same boxes were seen before."""
    keys = ("lo", "hi", "child", "start", "count", "order")

    def make() -> dict[str, np.ndarray]:
        compiled(build, (lo, hi, leaf_size))   # the first compile says so
        return dict(zip(keys, build(lo, hi, leaf_size)))
    bvh = HIERARCHIES.get(content_key(lo, hi, np.int64(leaf_size)), make)
    return {k: v.copy() for k, v in bvh.items()}   # a copy: no caller can change the next one's


@njit(**_JIT)
def _groups(child, area, width):
    """Collapse the binary tree ``width``-wide: rows in depth-first order, each the (up to) width nodes it holds.

    Each row takes a binary node's two children and opens its largest inner one (by surface area, the
    first on a tie) until it holds width. Row 0 holds the root alone; returns (rows, row of each node).
    """
    m = child.shape[0]
    rows = np.full((m + 1, width), -1, np.int64)
    row_of = np.full(m, -1, np.int64)
    rows[0, 0] = 0
    n_rows = 1
    todo = np.empty(m + 1, np.int64)
    sp = 0
    if child[0] >= 0:
        todo[0] = 0
        sp = 1
    group = np.empty(width, np.int64)
    while sp > 0:
        sp -= 1
        node = todo[sp]
        row_of[node] = n_rows
        group[0], group[1] = child[node], child[node] + 1
        size = 2
        while size < width:
            pick = -1
            for g in range(size):
                k = group[g]
                if child[k] >= 0 and (pick < 0 or area[k] > area[group[pick]]):
                    pick = g
            if pick < 0:
                break
            k = group[pick]
            for g in range(size - 1, pick, -1):   # open k in place: its two children take its slot
                group[g + 1] = group[g]
            group[pick], group[pick + 1] = child[k], child[k] + 1
            size += 1
        for g in range(size):
            rows[n_rows, g] = group[g]
        n_rows += 1
        for g in range(size - 1, -1, -1):          # the first inner child is opened next
            if child[group[g]] >= 0:
                todo[sp] = group[g]
                sp += 1
    return rows[:n_rows], row_of


@njit(**_JIT)
def _fill(rows, row_of, lo32, hi32, child, start, count, nf, ni):
    """Write each row's child slots: boxes (float32, rounded outwards) and where each child is."""
    w = rows.shape[1]
    for q in range(rows.shape[0]):
        for c in range(w):
            k = rows[q, c]
            if k < 0:
                continue
            for a in range(3):
                nf[q, w * a + c] = lo32[k, a]
                nf[q, 3 * w + w * a + c] = hi32[k, a]
            if child[k] >= 0:
                ni[q, 6 * w + c], ni[q, 7 * w + c] = row_of[k], -1
            else:
                ni[q, 6 * w + c], ni[q, 7 * w + c] = start[k], count[k]


def eight_wide(bvh: dict, nsph: int, tri: np.ndarray) -> tuple:
    """The hierarchy as the kernels read it: ``WIDTH`` (eight) children a row, one 256-byte row per node
    (four cache lines).

    Row q, in 8·WIDTH = 64 words: float32 boxes of its children as lo x, y, z then hi x, y, z, WIDTH of each
    (rounded outwards; words 0-47), then int32 words 48-55 the children's rows (or a leaf's first slot
    in ``order``) and 56-63: -1 for a row, the leaf's count, or -2 for an empty slot. Row 0 holds only
    the root. Triangles are copied into slot order (``ltri``).
    """
    lo, hi = np.asarray(bvh["lo"], np.float64), np.asarray(bvh["hi"], np.float64)
    lo32, hi32 = lo.astype(np.float32), hi.astype(np.float32)
    lo32 = np.where(lo32 > lo, np.nextafter(lo32, np.float32(-np.inf)), lo32)
    hi32 = np.where(hi32 < hi, np.nextafter(hi32, np.float32(np.inf)), hi32)
    child = np.ascontiguousarray(bvh["child"], np.int64)
    ext = hi - lo
    area = ext[:, 0] * ext[:, 1] + ext[:, 1] * ext[:, 2] + ext[:, 2] * ext[:, 0]
    compiled(_groups, (child, area, WIDTH))
    rows, row_of = _groups(child, area, WIDTH)
    words = 8 * WIDTH
    raw = np.zeros(len(rows) * words + 16, np.int32)  # rows start on 64-byte cache lines
    skip = (-raw.ctypes.data % 64) // 4
    ni = raw[skip:skip + len(rows) * words].reshape(-1, words)
    nf = ni.view(np.float32)
    ni[:, 7 * WIDTH:] = -2
    nf[:, :6 * WIDTH] = np.inf          # an empty slot's box: no ray enters it
    fill = (rows, row_of, lo32, hi32, child, np.ascontiguousarray(bvh["start"], np.int64),
            np.ascontiguousarray(bvh["count"], np.int64), nf, ni)
    compiled(_fill, fill)
    _fill(*fill)
    order = np.ascontiguousarray(bvh["order"], np.int64)
    ltri = np.zeros((len(order), 9))
    is_tri = order >= nsph
    ltri[is_tri] = tri[order[is_tri] - nsph]
    return nf, ni, order, ltri, True


def _layout(scene: TraceScene, tri: np.ndarray) -> dict:
    bvh = scene.bvh
    if bvh is None:
        ni = np.zeros((1, 8 * WIDTH), np.int32)
        nf, ni, order, ltri, use = ni.view(np.float32), ni, np.zeros(1, np.int64), tri, False
    else:
        nf, ni, order, ltri, use = eight_wide(bvh, scene.n_spheres, tri)
    tree = (nf.reshape(-1), ni.reshape(-1), order, ltri, use)   # the kernels index the rows' words flat
    sph = np.ascontiguousarray(np.column_stack([scene.sphere_center, scene.sphere_radius]).reshape(-1, 4))
    planes = np.ascontiguousarray(np.concatenate([scene.plane_point, scene.plane_normal], axis=1).reshape(-1, 6))
    frame = np.ascontiguousarray(np.concatenate([scene.plane_u, scene.plane_v], axis=1).reshape(-1, 6))
    e1, e2 = scene.tri_v1 - scene.tri_v0, scene.tri_v2 - scene.tri_v0
    tn = np.cross(e1, e2)
    length = np.linalg.norm(tn, axis=1, keepdims=True)
    return {"tree": tree, "nsph": scene.n_spheres, "sph": sph, "tri": tri, "planes": planes, "frame": frame,
            "tri_normal": np.ascontiguousarray(tn / np.where(length > 0, length, 1.0))}


def packed(scene: TraceScene) -> dict:
    """The scene's geometry and hierarchy in the layout the compiled kernels read.

    Kept on the scene for the rest of its render, and in ``LAYOUTS`` for the next scene with the same
    geometry and hierarchy.
    """
    cached = getattr(scene, "_reference_packed", None)
    if cached is not None:
        return cached
    tri = np.ascontiguousarray(np.concatenate([scene.tri_v0, scene.tri_v1, scene.tri_v2], axis=1).reshape(-1, 9))
    parts = [scene.sphere_center, scene.sphere_radius, tri, scene.plane_point, scene.plane_normal, scene.plane_u,
             scene.plane_v]
    if scene.bvh is not None:
        parts += [scene.bvh[k] for k in ("lo", "hi", "child", "start", "count", "order")]
    out = LAYOUTS.get(content_key(*parts), lambda: _layout(scene, tri))
    scene._reference_packed = out  # type: ignore[attr-defined]
    return out


def closest_args(scene: TraceScene, tree: tuple | None = None) -> tuple:
    """The closest-hit kernel's arguments that every ray shares (``tree``: another layout of the hierarchy,
    for the bench; the scene's own by default)."""
    p = packed(scene)
    return (*(p["tree"] if tree is None else tree), p["nsph"], p["sph"], p["tri"], p["planes"], p["tri_normal"])


def shadow_args(scene: TraceScene, tree: tuple | None = None) -> tuple:
    """The shadow-ray kernel's arguments that every ray shares (``tree`` as for ``closest_args``)."""
    p = packed(scene)
    return (*(p["tree"] if tree is None else tree), p["nsph"], p["sph"], p["tri"], p["planes"], p["frame"],
            scene.plane_checker, scene.plane_checker_material, scene.prim_material, scene.mat_transmittance)
