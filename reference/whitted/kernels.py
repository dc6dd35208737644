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
_INLINE = dict(_JIT, inline="always")  # small helpers: no call, no reference counting of their array arguments
STACK = 256


@njit(**_INLINE)
def _sphere_roots(ox, oy, oz, dx, dy, dz, sph, s):
    """Both roots of the ray o + t d on sphere s (sph[s] = centre, radius), sorted, or (inf, inf)."""
    r = sph[s, 3]
    fx, fy, fz = ox - sph[s, 0], oy - sph[s, 1], oz - sph[s, 2]
    a = dx * dx + dy * dy + dz * dz
    b = fx * dx + fy * dy + fz * dz
    k = b / a
    px, py, pz = fx - k * dx, fy - k * dy, fz - k * dz
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


@njit(**_INLINE)
def _triangle(okx, oky, okz, kx, ky, kz, sx, sy, sz, tri, i, tmax):
    """Watertight ray-triangle (Woop et al. 2013); returns t in (0, tmax) or inf.

    The origin's coordinates come permuted (okx = o[kx], ...), as ``_shear`` chose the axes.
    """
    x0 = tri[i, kx] - okx
    y0 = tri[i, ky] - oky
    z0 = tri[i, kz] - okz
    x1 = tri[i, 3 + kx] - okx
    y1 = tri[i, 3 + ky] - oky
    z1 = tri[i, 3 + kz] - okz
    x2 = tri[i, 6 + kx] - okx
    y2 = tri[i, 6 + ky] - oky
    z2 = tri[i, 6 + kz] - okz
    x0 += sx * z0
    y0 += sy * z0
    x1 += sx * z1
    y1 += sy * z1
    x2 += sx * z2
    y2 += sy * z2
    e0 = x1 * y2 - y1 * x2
    e1 = x2 * y0 - y2 * x0
    e2 = x0 * y1 - y0 * x1
    if ((e0 < 0.0) | (e1 < 0.0) | (e2 < 0.0)) & ((e0 > 0.0) | (e1 > 0.0) | (e2 > 0.0)):  # one branch, not six
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


@njit(**_INLINE)
def _shear(ox, oy, oz, dx, dy, dz):
    """The watertight test's axes (kz: the direction's largest), shear and permuted origin."""
    d = (dx, dy, dz)
    o = (ox, oy, oz)
    ax, ay, az = abs(dx), abs(dy), abs(dz)
    kz = 0
    if ay > ax and ay >= az:
        kz = 1
    elif az > ax and az > ay:
        kz = 2
    kx = (kz + 1) % 3
    ky = (kx + 1) % 3
    return kx, ky, kz, -d[kx] / d[kz], -d[ky] / d[kz], 1.0 / d[kz], o[kx], o[ky], o[kz]


@njit(**_INLINE)
def _slabs(nf, q, c, ox, oy, oz, ix, iy, iz, tmax):
    """Entry distance into child c's box of row q (float32, rounded outwards), or inf."""
    t0 = 0.0
    t1 = tmax
    ta = (np.float64(nf[q, c]) - ox) * ix
    tb = (np.float64(nf[q, 12 + c]) - ox) * ix
    if ta > tb:
        ta, tb = tb, ta
    if ta > t0:
        t0 = ta
    if tb < t1:
        t1 = tb
    ta = (np.float64(nf[q, 4 + c]) - oy) * iy
    tb = (np.float64(nf[q, 16 + c]) - oy) * iy
    if ta > tb:
        ta, tb = tb, ta
    if ta > t0:
        t0 = ta
    if tb < t1:
        t1 = tb
    ta = (np.float64(nf[q, 8 + c]) - oz) * iz
    tb = (np.float64(nf[q, 20 + c]) - oz) * iz
    if ta > tb:
        ta, tb = tb, ta
    if ta > t0:
        t0 = ta
    if tb < t1:
        t1 = tb
    if t0 <= t1 * 1.0000000000000004:  # slack: a ray grazing a flat box still enters it
        return t0
    return math.inf


@njit(**_INLINE)
def _axis(nf, q, col, o, inv, t0, t1):
    """Clip (t0, t1) to one axis's slab of a child's box: near and far planes in nf[q, col], nf[q, col + 12]."""
    ta = (np.float64(nf[q, col]) - o) * inv
    tb = (np.float64(nf[q, col + 12]) - o) * inv
    lo = tb if ta > tb else ta
    hi = ta if ta > tb else tb
    return (lo if lo > t0 else t0), (hi if hi < t1 else t1)


@njit(**_INLINE)
def _slabs4(nf, q, ox, oy, oz, ix, iy, iz, tmax, dist):
    """dist[c] = entry distance into child c's box of row q, or inf: ``_slabs`` for the four children.

    Written out lane by lane (straight-line, the same operations on columns c = 0..3) so that LLVM's
    SLP vectoriser can test the four boxes at once (see ``_compiled``).
    """
    n0, f0 = _axis(nf, q, 0, ox, ix, 0.0, tmax)
    n1, f1 = _axis(nf, q, 1, ox, ix, 0.0, tmax)
    n2, f2 = _axis(nf, q, 2, ox, ix, 0.0, tmax)
    n3, f3 = _axis(nf, q, 3, ox, ix, 0.0, tmax)
    n0, f0 = _axis(nf, q, 4, oy, iy, n0, f0)
    n1, f1 = _axis(nf, q, 5, oy, iy, n1, f1)
    n2, f2 = _axis(nf, q, 6, oy, iy, n2, f2)
    n3, f3 = _axis(nf, q, 7, oy, iy, n3, f3)
    n0, f0 = _axis(nf, q, 8, oz, iz, n0, f0)
    n1, f1 = _axis(nf, q, 9, oz, iz, n1, f1)
    n2, f2 = _axis(nf, q, 10, oz, iz, n2, f2)
    n3, f3 = _axis(nf, q, 11, oz, iz, n3, f3)
    slack = 1.0000000000000004  # a ray grazing a flat box still enters it
    dist[0] = n0 if n0 <= f0 * slack else math.inf
    dist[1] = n1 if n1 <= f1 * slack else math.inf
    dist[2] = n2 if n2 <= f2 * slack else math.inf
    dist[3] = n3 if n3 <= f3 * slack else math.inf


@njit(**_INLINE)
def _order(da, ca, db, cb):
    """Two (distance, slot) pairs, nearer first (on a tie, the lower slot)."""
    swap = (db < da) | ((db == da) & (cb < ca))  # bitwise: no branches to mispredict
    return (db if swap else da), (cb if swap else ca), (da if swap else db), (ca if swap else cb)


@njit(**_INLINE)
def _prim_t(ox, oy, oz, dx, dy, dz, okx, oky, okz, kx, ky, kz, sx, sy, sz, k, j, nsph, sph, ltri, tmax):
    """Distance to primitive k (slot j of the leaf-ordered triangles): a sphere's first root ahead, or inf."""
    if k < nsph:
        t0, t1 = _sphere_roots(ox, oy, oz, dx, dy, dz, sph, k)
        return t0 if t0 > 0.0 else t1
    return _triangle(okx, oky, okz, kx, ky, kz, sx, sy, sz, ltri, j, tmax)


@njit(**_JIT)
def closest(O, D, nf, ni, order, ltri, use_bvh, nsph, sph, tri, planes, tri_normal, out_t, out_prim,
            out_n, stats):
    """Closest hit of each ray: t (inf on a miss), primitive number (-1), unit normal; stats[i] = (nodes, tests).

    The hierarchy is four-wide (see ``bvh._tree``): nf/ni are float32 and int32 views of the same rows;
    row 0 holds the root alone; ``ltri`` holds the triangles slot by slot (ltri[j] is triangle
    order[j] - nsph). The stack keeps each waiting child's row (or first slot), kind and entry distance.
    """
    stack = np.empty(STACK, np.int64)
    scnt = np.empty(STACK, np.int64)
    snear = np.empty(STACK, np.float64)
    dist = np.empty(4)
    nb = nsph + tri.shape[0]
    for i in range(O.shape[0]):
        ox, oy, oz = O[i, 0], O[i, 1], O[i, 2]
        dx, dy, dz = D[i, 0], D[i, 1], D[i, 2]
        ix, iy, iz = 1.0 / dx, 1.0 / dy, 1.0 / dz
        kx, ky, kz, sx, sy, sz, okx, oky, okz = _shear(ox, oy, oz, dx, dy, dz)
        best = math.inf
        prim = -1
        nodes = 0
        tests = 0
        for p in range(planes.shape[0]):
            dn = dx * planes[p, 3] + dy * planes[p, 4] + dz * planes[p, 5]
            tests += 1
            if dn != 0.0:
                t = ((planes[p, 0] - ox) * planes[p, 3] + (planes[p, 1] - oy) * planes[p, 4]
                     + (planes[p, 2] - oz) * planes[p, 5]) / dn
                if 0.0 < t < best:
                    best = t
                    prim = nb + p
        if use_bvh:
            sp = 0
            nodes += 1
            t = _slabs(nf, 0, 0, ox, oy, oz, ix, iy, iz, best)  # row 0 holds the root alone
            if t < math.inf:
                stack[0] = ni[0, 24]
                scnt[0] = ni[0, 28]
                snear[0] = t
                sp = 1
            q = 0
            cnt = 0
            go = False  # True: (q, cnt) is the next node, taken without a trip through the stack
            while go or sp > 0:
                if not go:
                    sp -= 1
                    if snear[sp] > best:
                        continue
                    q = stack[sp]
                    cnt = scnt[sp]
                go = False
                if cnt >= 0:  # a leaf
                    for j in range(q, q + cnt):
                        k = order[j]
                        tests += 1
                        t = _prim_t(ox, oy, oz, dx, dy, dz, okx, oky, okz, kx, ky, kz, sx, sy, sz, k, j, nsph, sph, ltri, best)
                        if 0.0 < t < best:
                            best = t
                            prim = k
                    continue
                row = np.uint64(q)  # unsigned: no negative-index wraparound on the row's loads
                _slabs4(nf, row, ox, oy, oz, ix, iy, iz, best, dist)
                # sort the four children by entry distance (then slot), without branches
                d0, d1, d2, d3 = dist[0], dist[1], dist[2], dist[3]
                c0, c1, c2, c3 = 0, 1, 2, 3
                d0, c0, d1, c1 = _order(d0, c0, d1, c1)
                d2, c2, d3, c3 = _order(d2, c2, d3, c3)
                d0, c0, d2, c2 = _order(d0, c0, d2, c2)
                d1, c1, d3, c3 = _order(d1, c1, d3, c3)
                d1, c1, d2, c2 = _order(d1, c1, d2, c2)
                nodes += (ni[row, 28] != -2) + (ni[row, 29] != -2) + (ni[row, 30] != -2) + (ni[row, 31] != -2)
                # the others wait on the stack, far to near; a missed child (inf) is overwritten
                stack[sp] = ni[row, 24 + c3]
                scnt[sp] = ni[row, 28 + c3]
                snear[sp] = d3
                sp += d3 < math.inf
                stack[sp] = ni[row, 24 + c2]
                scnt[sp] = ni[row, 28 + c2]
                snear[sp] = d2
                sp += d2 < math.inf
                stack[sp] = ni[row, 24 + c1]
                scnt[sp] = ni[row, 28 + c1]
                snear[sp] = d1
                sp += d1 < math.inf
                if d0 < math.inf:  # the nearest child is next
                    q = ni[row, 24 + c0]
                    cnt = ni[row, 28 + c0]
                    go = True
        else:
            for k in range(nb):
                tests += 1
                if k < nsph:
                    t0, t1 = _sphere_roots(ox, oy, oz, dx, dy, dz, sph, k)
                    t = t0 if t0 > 0.0 else t1
                else:
                    t = _triangle(okx, oky, okz, kx, ky, kz, sx, sy, sz, tri, k - nsph, best)
                if 0.0 < t < best:
                    best = t
                    prim = k
        out_t[i] = best
        out_prim[i] = prim
        if prim < 0:
            out_n[i, 0], out_n[i, 1], out_n[i, 2] = 0.0, 0.0, 0.0
        elif prim < nsph:
            r = sph[prim, 3]
            for a in range(3):
                out_n[i, a] = (O[i, a] + best * D[i, a] - sph[prim, a]) / r
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
def transmission(O, D, TMAX, nf, ni, order, ltri, use_bvh, nsph, sph, tri, planes, pframe,
                 checker, checker_mat, prim_mat, trans, out, stats):
    """Shadow rays: out[i] = product of the transmittances crossed on (0, TMAX[i]); stops at an opaque one."""
    stack = np.empty(STACK, np.int64)
    scnt = np.empty(STACK, np.int64)
    T = np.empty(3)
    nb = nsph + tri.shape[0]
    for i in range(O.shape[0]):
        o = O[i]
        d = D[i]
        tmax = TMAX[i]
        ox, oy, oz = O[i, 0], O[i, 1], O[i, 2]
        dx, dy, dz = D[i, 0], D[i, 1], D[i, 2]
        ix, iy, iz = 1.0 / dx, 1.0 / dy, 1.0 / dz
        for a in range(3):
            T[a] = 1.0
        kx, ky, kz, sx, sy, sz, okx, oky, okz = _shear(ox, oy, oz, dx, dy, dz)
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
                stack[0] = 0
                scnt[0] = -1
                sp = 1
            else:
                for k in range(nb):
                    tests += 1
                    if k < nsph:
                        t0, t1 = _sphere_roots(ox, oy, oz, dx, dy, dz, sph, k)
                        if 0.0 < t0 < tmax and _attenuate(T, k, t0, o, d, nb, prim_mat, trans, planes, pframe, checker, checker_mat):
                            blocked = True
                            break
                        if 0.0 < t1 < tmax and _attenuate(T, k, t1, o, d, nb, prim_mat, trans, planes, pframe, checker, checker_mat):
                            blocked = True
                            break
                    else:
                        t = _triangle(okx, oky, okz, kx, ky, kz, sx, sy, sz, tri, k - nsph, tmax)
                        if t < tmax and _attenuate(T, k, t, o, d, nb, prim_mat, trans, planes, pframe, checker, checker_mat):
                            blocked = True
                            break
        while sp > 0 and not blocked:
            sp -= 1
            q = stack[sp]
            cnt = scnt[sp]
            if cnt >= 0:
                for j in range(q, q + cnt):
                    k = order[j]
                    tests += 1
                    if k < nsph:
                        t0, t1 = _sphere_roots(ox, oy, oz, dx, dy, dz, sph, k)
                        if 0.0 < t0 < tmax and _attenuate(T, k, t0, o, d, nb, prim_mat, trans, planes, pframe, checker, checker_mat):
                            blocked = True
                            break
                        if 0.0 < t1 < tmax and _attenuate(T, k, t1, o, d, nb, prim_mat, trans, planes, pframe, checker, checker_mat):
                            blocked = True
                            break
                    else:
                        t = _triangle(okx, oky, okz, kx, ky, kz, sx, sy, sz, ltri, j, tmax)
                        if t < tmax and _attenuate(T, k, t, o, d, nb, prim_mat, trans, planes, pframe, checker, checker_mat):
                            blocked = True
                            break
            else:
                for c in range(4):
                    kc = ni[q, 28 + c]
                    if kc == -2:
                        break
                    nodes += 1
                    if _slabs(nf, q, c, ox, oy, oz, ix, iy, iz, tmax) < math.inf:
                        stack[sp] = ni[q, 24 + c]
                        scnt[sp] = kc
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


def _compiled(kernel, args: tuple) -> None:
    """Compile (or load from numba's cache) kernel for these arguments with LLVM's SLP vectoriser on.

    Numba leaves it off by default; it lets ``_slabs4`` test four boxes in a few vector instructions.
    The switch is numba's own config value, set only while this compiles (results are the same either way).
    """
    from numba import typeof
    from numba.core import config
    sig = tuple(typeof(a) for a in args)
    if sig in kernel.overloads:
        return
    old = config.SLP_VECTORIZE
    config.SLP_VECTORIZE = 1
    try:
        kernel.compile(sig)
    finally:
        config.SLP_VECTORIZE = old


def in_threads(kernel, n: int, row_args: tuple, shared: tuple, outs: tuple, threads: int = 2) -> None:
    """Run ``kernel(*rows, *shared, *outs)`` over chunks of n rays in threads (the kernels release the GIL)."""
    _compiled(kernel, (*row_args, *shared, *outs))
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
