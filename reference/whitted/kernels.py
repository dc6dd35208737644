"""The reference's compiled inner loops (numba): hierarchy traversal, closest hit and shadow rays.

Written per ray, in float64, and run on chunks of rays in threads (``nogil``).
A clear numpy solution does not need this file: it is how the reference reaches
Embree-like speeds (see ``bench/whitted.py``). Students' copies of it are empty.
"""
# BEGIN SOLUTION
from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from numba import njit

_JIT = dict(cache=True, nogil=True, error_model="numpy")
STACK = 128


@njit(**_JIT)
def _sphere_roots(o, d, c, r):
    fx, fy, fz = o[0] - c[0], o[1] - c[1], o[2] - c[2]
    a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
    b = fx * d[0] + fy * d[1] + fz * d[2]
    k = b / a
    px, py, pz = fx - k * d[0], fy - k * d[1], fz - k * d[2]
    disc = r * r - (px * px + py * py + pz * pz)
    if disc < 0.0:
        return math.inf, math.inf
    q = -(b + math.copysign(math.sqrt(a * disc), b))
    if q == 0.0:
        return math.inf, math.inf
    cc = fx * fx + fy * fy + fz * fz - r * r
    t0, t1 = cc / q, q / a
    if t0 > t1:
        t0, t1 = t1, t0
    return t0, t1


@njit(**_JIT)
def _triangle(o, kx, ky, kz, sx, sy, sz, tri, i, tmax):
    """Watertight ray-triangle (Woop et al. 2013); returns t in (0, tmax) or inf."""
    x0 = tri[i, kx] - o[kx]
    y0 = tri[i, ky] - o[ky]
    z0 = tri[i, kz] - o[kz]
    x1 = tri[i, 3 + kx] - o[kx]
    y1 = tri[i, 3 + ky] - o[ky]
    z1 = tri[i, 3 + kz] - o[kz]
    x2 = tri[i, 6 + kx] - o[kx]
    y2 = tri[i, 6 + ky] - o[ky]
    z2 = tri[i, 6 + kz] - o[kz]
    x0 += sx * z0
    y0 += sy * z0
    x1 += sx * z1
    y1 += sy * z1
    x2 += sx * z2
    y2 += sy * z2
    e0 = x1 * y2 - y1 * x2
    e1 = x2 * y0 - y2 * x0
    e2 = x0 * y1 - y0 * x1
    if (e0 < 0.0 or e1 < 0.0 or e2 < 0.0) and (e0 > 0.0 or e1 > 0.0 or e2 > 0.0):
        return math.inf
    det = e0 + e1 + e2
    if det == 0.0:
        return math.inf
    ts = (e0 * z0 + e1 * z1 + e2 * z2) * sz
    if det < 0.0:
        if ts >= 0.0 or ts < tmax * det:
            return math.inf
    else:
        if ts <= 0.0 or ts > tmax * det:
            return math.inf
    return ts / det


@njit(**_JIT)
def _box(box, n, o, inv, tmax):
    """Entry distance of a ray into node n's box (float32, rounded outwards), or inf."""
    t0 = 0.0
    t1 = tmax
    for a in range(3):
        ta = (np.float64(box[n, a]) - o[a]) * inv[a]
        tb = (np.float64(box[n, 3 + a]) - o[a]) * inv[a]
        if ta > tb:
            ta, tb = tb, ta
        if ta > t0:
            t0 = ta
        if tb < t1:
            t1 = tb
    if t0 <= t1 * 1.0000000000000004:  # slack: a ray grazing a flat box still enters it
        return t0
    return math.inf


@njit(**_JIT)
def _shear(d):
    ax, ay, az = abs(d[0]), abs(d[1]), abs(d[2])
    kz = 0
    if ay > ax and ay >= az:
        kz = 1
    elif az > ax and az > ay:
        kz = 2
    kx = (kz + 1) % 3
    ky = (kx + 1) % 3
    return kx, ky, kz, -d[kx] / d[kz], -d[ky] / d[kz], 1.0 / d[kz]


@njit(**_JIT)
def closest(O, D, box, child, start, count, order, use_bvh, nsph, sph, tri, planes, tri_normal, out_t, out_prim,
            out_n, stats):
    """Closest hit of each ray: t (inf on a miss), primitive number (-1), unit normal; stats[i] = (nodes, tests)."""
    stack = np.empty(STACK, np.int64)
    snear = np.empty(STACK, np.float64)
    inv = np.empty(3)
    nb = nsph + tri.shape[0]
    for i in range(O.shape[0]):
        o = O[i]
        d = D[i]
        for a in range(3):
            inv[a] = 1.0 / d[a]
        kx, ky, kz, sx, sy, sz = _shear(d)
        best = math.inf
        prim = -1
        nodes = 0
        tests = 0
        for p in range(planes.shape[0]):
            dn = d[0] * planes[p, 3] + d[1] * planes[p, 4] + d[2] * planes[p, 5]
            tests += 1
            if dn != 0.0:
                t = ((planes[p, 0] - o[0]) * planes[p, 3] + (planes[p, 1] - o[1]) * planes[p, 4]
                     + (planes[p, 2] - o[2]) * planes[p, 5]) / dn
                if 0.0 < t < best:
                    best = t
                    prim = nb + p
        if use_bvh:
            nodes += 1
            if _box(box, 0, o, inv, best) < math.inf:
                sp = 1
                stack[0] = 0
                snear[0] = 0.0
            else:
                sp = 0
        else:
            sp = 0
            for k in range(nb):
                tests += 1
                if k < nsph:
                    t0, t1 = _sphere_roots(o, d, sph[k, :3], sph[k, 3])
                    t = t0 if t0 > 0.0 else t1
                else:
                    t = _triangle(o, kx, ky, kz, sx, sy, sz, tri, k - nsph, best)
                if 0.0 < t < best:
                    best = t
                    prim = k
        while sp > 0:
            sp -= 1
            node = stack[sp]
            if snear[sp] > best:
                continue
            c = child[node]
            if c < 0:
                for j in range(start[node], start[node] + count[node]):
                    k = order[j]
                    tests += 1
                    if k < nsph:
                        t0, t1 = _sphere_roots(o, d, sph[k, :3], sph[k, 3])
                        t = t0 if t0 > 0.0 else t1
                    else:
                        t = _triangle(o, kx, ky, kz, sx, sy, sz, tri, k - nsph, best)
                    if 0.0 < t < best:
                        best = t
                        prim = k
            else:
                nodes += 2
                ta = _box(box, c, o, inv, best)
                tb = _box(box, c + 1, o, inv, best)
                if ta > tb:
                    if ta < math.inf:
                        stack[sp] = c
                        snear[sp] = ta
                        sp += 1
                    stack[sp] = c + 1
                    snear[sp] = tb
                    sp += 1
                else:
                    if tb < math.inf:
                        stack[sp] = c + 1
                        snear[sp] = tb
                        sp += 1
                    if ta < math.inf:
                        stack[sp] = c
                        snear[sp] = ta
                        sp += 1
        out_t[i] = best
        out_prim[i] = prim
        if prim < 0:
            out_n[i, 0], out_n[i, 1], out_n[i, 2] = 0.0, 0.0, 0.0
        elif prim < nsph:
            r = sph[prim, 3]
            for a in range(3):
                out_n[i, a] = (o[a] + best * d[a] - sph[prim, a]) / r
            length = math.sqrt(out_n[i, 0] ** 2 + out_n[i, 1] ** 2 + out_n[i, 2] ** 2)
            for a in range(3):
                out_n[i, a] /= length
        elif prim < nb:
            for a in range(3):
                out_n[i, a] = tri_normal[prim - nsph, a]
        else:
            for a in range(3):
                out_n[i, a] = planes[prim - nb, 3 + a]
        stats[i, 0] = nodes
        stats[i, 1] = tests


@njit(**_JIT)
def _material(k, x, nb, prim_mat, planes, pframe, checker, checker_mat):
    m = prim_mat[k]
    p = k - nb
    if p >= 0 and checker[p] > 0.0:
        rx, ry, rz = x[0] - planes[p, 0], x[1] - planes[p, 1], x[2] - planes[p, 2]
        a = math.floor((rx * pframe[p, 0] + ry * pframe[p, 1] + rz * pframe[p, 2]) / checker[p])
        b = math.floor((rx * pframe[p, 3] + ry * pframe[p, 4] + rz * pframe[p, 5]) / checker[p])
        if (a + b) % 2 == 1:
            m = checker_mat[p]
    return m


@njit(**_JIT)
def _attenuate(T, k, t, o, d, nb, prim_mat, trans, planes, pframe, checker, checker_mat):
    """Multiply T by the transmittance of primitive k crossed at t; True when T is now zero."""
    x = np.empty(3)
    for a in range(3):
        x[a] = o[a] + t * d[a]
    m = _material(k, x, nb, prim_mat, planes, pframe, checker, checker_mat)
    zero = True
    for a in range(3):
        T[a] *= trans[m, a]
        if T[a] > 0.0:
            zero = False
    return zero


@njit(**_JIT)
def transmission(O, D, TMAX, box, child, start, count, order, use_bvh, nsph, sph, tri, planes, pframe,
                 checker, checker_mat, prim_mat, trans, out, stats):
    """Shadow rays: out[i] = product of the transmittances crossed on (0, TMAX[i]); stops at an opaque one."""
    stack = np.empty(STACK, np.int64)
    inv = np.empty(3)
    T = np.empty(3)
    nb = nsph + tri.shape[0]
    for i in range(O.shape[0]):
        o = O[i]
        d = D[i]
        tmax = TMAX[i]
        for a in range(3):
            inv[a] = 1.0 / d[a]
            T[a] = 1.0
        kx, ky, kz, sx, sy, sz = _shear(d)
        nodes = 0
        tests = 0
        blocked = False
        for p in range(planes.shape[0]):
            tests += 1
            dn = d[0] * planes[p, 3] + d[1] * planes[p, 4] + d[2] * planes[p, 5]
            if dn != 0.0:
                t = ((planes[p, 0] - o[0]) * planes[p, 3] + (planes[p, 1] - o[1]) * planes[p, 4]
                     + (planes[p, 2] - o[2]) * planes[p, 5]) / dn
                if 0.0 < t < tmax:
                    if _attenuate(T, nb + p, t, o, d, nb, prim_mat, trans, planes, pframe, checker, checker_mat):
                        blocked = True
                        break
        sp = 0
        if not blocked:
            if use_bvh:
                nodes += 1
                if _box(box, 0, o, inv, tmax) < math.inf:
                    stack[0] = 0
                    sp = 1
            else:
                for k in range(nb):
                    tests += 1
                    if k < nsph:
                        t0, t1 = _sphere_roots(o, d, sph[k, :3], sph[k, 3])
                        if 0.0 < t0 < tmax and _attenuate(T, k, t0, o, d, nb, prim_mat, trans, planes, pframe, checker, checker_mat):
                            blocked = True
                            break
                        if 0.0 < t1 < tmax and _attenuate(T, k, t1, o, d, nb, prim_mat, trans, planes, pframe, checker, checker_mat):
                            blocked = True
                            break
                    else:
                        t = _triangle(o, kx, ky, kz, sx, sy, sz, tri, k - nsph, tmax)
                        if t < tmax and _attenuate(T, k, t, o, d, nb, prim_mat, trans, planes, pframe, checker, checker_mat):
                            blocked = True
                            break
        while sp > 0 and not blocked:
            sp -= 1
            node = stack[sp]
            c = child[node]
            if c < 0:
                for j in range(start[node], start[node] + count[node]):
                    k = order[j]
                    tests += 1
                    if k < nsph:
                        t0, t1 = _sphere_roots(o, d, sph[k, :3], sph[k, 3])
                        if 0.0 < t0 < tmax and _attenuate(T, k, t0, o, d, nb, prim_mat, trans, planes, pframe, checker, checker_mat):
                            blocked = True
                            break
                        if 0.0 < t1 < tmax and _attenuate(T, k, t1, o, d, nb, prim_mat, trans, planes, pframe, checker, checker_mat):
                            blocked = True
                            break
                    else:
                        t = _triangle(o, kx, ky, kz, sx, sy, sz, tri, k - nsph, tmax)
                        if t < tmax and _attenuate(T, k, t, o, d, nb, prim_mat, trans, planes, pframe, checker, checker_mat):
                            blocked = True
                            break
            else:
                nodes += 2
                if _box(box, c, o, inv, tmax) < math.inf:
                    stack[sp] = c
                    sp += 1
                if _box(box, c + 1, o, inv, tmax) < math.inf:
                    stack[sp] = c + 1
                    sp += 1
        for a in range(3):
            out[i, a] = 0.0 if blocked else T[a]
        stats[i, 0] = nodes
        stats[i, 1] = tests



@njit(**_JIT)
def _area(lo, hi):
    ex, ey, ez = hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]
    return ex * ey + ey * ez + ez * ex


@njit(**_JIT)
def build(lo, hi, leaf_size):
    """Top-down build with a binned surface area heuristic (16 bins per axis), partitioning in place."""
    bins = 16
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


def in_threads(kernel, n: int, row_args: tuple, shared: tuple, outs: tuple, threads: int = 2) -> None:
    """Run ``kernel(*rows, *shared, *outs)`` over chunks of n rays in threads (the kernels release the GIL)."""
    if n < 4096 or threads <= 1:
        kernel(*row_args, *shared, *outs)
        return
    bounds = np.linspace(0, n, threads * 4 + 1).astype(int)

    def run(k: int) -> None:
        s, e = bounds[k], bounds[k + 1]
        kernel(*(a[s:e] for a in row_args), *shared, *(a[s:e] for a in outs))

    with ThreadPoolExecutor(threads) as pool:
        list(pool.map(run, range(len(bounds) - 1)))
# END SOLUTION
