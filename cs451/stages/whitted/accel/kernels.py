"""The reference's compiled inner loops (numba): hierarchy traversal, closest hit, shadow rays, and a
whole Whitted frame (closest hit, shading, shadow rays and the recursion for each camera ray).

Written per ray, in float64 (the hierarchy's boxes aside: tested in float32, widened by the test's error
bound), and run on chunks of rays in threads (``nogil``, see ``running.py``).
A clear numpy solution does not need this file: it is how the reference reaches Embree-like speeds
(see ``cs451/stages/whitted/bench.py``). The frame kernel lives here with the traversal it inlines because numba's
cache checks only the file a kernel is defined in. A student's starter has no copy of it.
"""
from __future__ import annotations

import math
import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

#: The kernels allocate nothing (their stacks come in, see ``scratch``), so they are compiled without numba's
#: reference counting: an inlined helper's array arguments would otherwise cost atomic increments per call.
_JIT = dict(cache=True, nogil=True, error_model="numpy", _nrt=False)
_INLINE = dict(_JIT, inline="always")  # helpers: inlined in numba's IR, no call
STACK = 256
_ROW = np.uint64(64)   # words per row of the eight-wide hierarchy (see hierarchy.eight_wide)
_F0 = np.float32(0.0)
#: The box test's relative slack in float32, 2^-21 (8 ulps): it covers the three roundings of (b - o)·inv
#: and the widening's own two (``_widen``), so no box a ray enters in exact arithmetic is missed.
_SLACK32 = np.float32(2.0 ** -21)
_INF32 = np.float32(math.inf)


def scratch(max_depth: int = 0) -> tuple[np.ndarray, ...]:
    """One thread's working memory for any kernel here: the traversal stack (node, kind, entry distance),
    a row's eight entry distances then the entered ones sorted (distance, slot; float32, which holds both
    exactly: the distances come from the float32 box test), and the frame's waiting rays (origin,
    direction, weight, depth)."""
    return (np.empty(STACK, np.int64), np.empty(STACK, np.int64), np.empty(STACK), np.empty(24, np.float32),
            np.empty((2 * max_depth + 2, 10)))


def _lanes(builder, values, element):
    """The eight scalars as one LLVM vector, by insertelement; where the SLP vectoriser already holds them in a
    register, LLVM takes that register as it is (the row test compiles to one vcmpleps on the slab test's)."""
    vector = ir.Constant(ir.VectorType(element, 8), ir.Undefined)
    for i, v in enumerate(values):
        vector = builder.insert_element(vector, v, ir.Constant(ir.IntType(32), i))
    return vector


@intrinsic
def _le_bits8(typingctx, n0, n1, n2, n3, n4, n5, n6, n7, f0, f1, f2, f3, f4, f5, f6, f7):
    """Bit c set where n_c <= f_c (float32, ordered: false on NaN), for c = 0..7: one vector compare and a
    mask move, where numba's own code takes the eight results apart bit by bit."""
    if not all(a == types.float32 for a in (n0, n1, n2, n3, n4, n5, n6, n7, f0, f1, f2, f3, f4, f5, f6, f7)):
        return None

    def codegen(context, builder, sig, args):
        le = builder.fcmp_ordered("<=", _lanes(builder, args[:8], ir.FloatType()), _lanes(builder, args[8:], ir.FloatType()))
        return builder.zext(builder.bitcast(le, ir.IntType(8)), ir.IntType(32))
    return types.uint32(*([types.float32] * 16)), codegen


@intrinsic
def _count_ne8(typingctx, x0, x1, x2, x3, x4, x5, x6, x7, v):
    """How many of the eight int32 x_c differ from v: one vector compare, a mask move and popcnt."""
    if not all(a == types.int32 for a in (x0, x1, x2, x3, x4, x5, x6, x7, v)):
        return None

    def codegen(context, builder, sig, args):
        splat = _lanes(builder, [args[8]] * 8, ir.IntType(32))
        ne = builder.icmp_unsigned("!=", _lanes(builder, args[:8], ir.IntType(32)), splat)
        return builder.zext(builder.ctpop(builder.bitcast(ne, ir.IntType(8))), ir.IntType(32))
    return types.uint32(*([types.int32] * 9)), codegen


@intrinsic
def _lowest(typingctx, x):
    """The position of an integer's lowest set bit (LLVM's cttz: one tzcnt instruction); x must not be 0."""
    if not isinstance(x, types.Integer):
        return None
    return x(x), lambda context, builder, sig, args: builder.cttz(args[0], ir.Constant(ir.IntType(1), 1))


@intrinsic
def _prefetch(typingctx, array, index):
    """Ask for the cache line holding the element ``index`` places from a C-contiguous array's start (LLVM's
    prefetch: one prefetcht0), without waiting for it; nothing checks the index (a prefetch cannot fault)."""
    if not (isinstance(array, types.Array) and isinstance(index, types.Integer)):
        return None

    def codegen(context, builder, sig, args):
        from numba.core import cgutils
        data = context.make_array(sig.args[0])(context, builder, args[0]).data
        address = builder.bitcast(builder.gep(data, [args[1]]), ir.PointerType(ir.IntType(8)))
        i32 = ir.IntType(32)
        fn = cgutils.get_or_insert_function(builder.module, ir.FunctionType(ir.VoidType(), [address.type, i32, i32, i32]),
                                            "llvm.prefetch.p0")
        builder.call(fn, [address, ir.Constant(i32, 0), ir.Constant(i32, 3), ir.Constant(i32, 1)])
        return context.get_dummy_value()
    return types.none(array, index), codegen


@njit(**_INLINE)
def _fetch_child(nf, ltri, q, cnt):
    """Start loading a child that waits on the stack: a row's four cache lines, or a leaf's first triangles."""
    if cnt < 0:
        k = np.uint64(q) * _ROW
        _prefetch(nf, k)
        _prefetch(nf, k + np.uint64(16))
        _prefetch(nf, k + np.uint64(32))
        _prefetch(nf, k + np.uint64(48))
    else:
        k = np.uint64(q) * np.uint64(9)
        _prefetch(ltri, k)
        _prefetch(ltri, k + np.uint64(8))


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
def _setup(ox, oy, oz, dx, dy, dz, boxes, triangles):
    """What traversal needs of a ray, computed only where it is used: the inverse direction (for boxes) and
    the watertight test's shear (for triangles). With a hierarchy the closest-hit traversal takes the shear
    at its first leaf instead: most rays that miss reach none (three divisions saved; primary rays 1.04x,
    the shadow rays' traversal no faster, so it keeps it here).

    Along an axis the ray is parallel to, the inverse is +inf whatever the zero's sign: then a ray lying in a
    box's face gets NaN for that face's distance and ±inf for the other, in the order the slab tests pass
    over (1/-0.0 = -inf would swap them, and such a ray, in the box, was taken to miss it).
    """
    ix, iy, iz = 0.0, 0.0, 0.0
    if boxes:
        ix = 1.0 / dx if dx != 0.0 else math.inf
        iy = 1.0 / dy if dy != 0.0 else math.inf
        iz = 1.0 / dz if dz != 0.0 else math.inf
    if triangles:
        kx, ky, kz, sx, sy, sz, okx, oky, okz = _shear(ox, oy, oz, dx, dy, dz)
    else:
        kx, ky, kz, sx, sy, sz, okx, oky, okz = 0, 1, 2, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    return ix, iy, iz, kx, ky, kz, sx, sy, sz, okx, oky, okz


@njit(**_INLINE)
def _root(nf, ox, oy, oz, ix, iy, iz, tmax):
    """Entry distance into the root's box (slot 0 of row 0, float32 rounded outwards), or inf; in float64."""
    t0 = 0.0
    t1 = tmax
    ta = (np.float64(nf[0]) - ox) * ix
    tb = (np.float64(nf[24]) - ox) * ix
    if ta > tb:
        ta, tb = tb, ta
    if ta > t0:
        t0 = ta
    if tb < t1:
        t1 = tb
    ta = (np.float64(nf[8]) - oy) * iy
    tb = (np.float64(nf[32]) - oy) * iy
    if ta > tb:
        ta, tb = tb, ta
    if ta > t0:
        t0 = ta
    if tb < t1:
        t1 = tb
    ta = (np.float64(nf[16]) - oz) * iz
    tb = (np.float64(nf[40]) - oz) * iz
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
def _inv32(inv):
    """An inverse direction component for the float32 test: rounded, inf where the ray is parallel to the
    axis, and NaN where it is not but is near or past float32's largest number (|inv| >= 1e38): NaN slab
    distances are passed over by ``_axis``, so that axis then lets the ray into every box (more, never fewer)."""
    if abs(inv) < 1e38 or abs(inv) == math.inf:
        return np.float32(inv)
    return np.float32(math.nan)


@njit(**_INLINE)
def _ray32(ox, oy, oz, ix, iy, iz):
    """The ray as the float32 box tests take it: origin and inverse direction rounded to float32 (``_inv32``),
    and the slack s (float32, rounded up) by which rounding the origin can move a slab distance: the largest
    |(o - o32)·inv| over the axes float32 holds the ray's inverse direction on, parallel ones aside (there the
    test is o inside the slab, and rounding to the nearest float32 keeps a point between two float32 planes
    between them). An origin beyond float32's range gets NaN everywhere: every box is entered.

    With the widening in ``_widen``, no box is missed that the ray enters, in exact arithmetic, nearer than
    float32's largest number (3.4e38).
    """
    if not (abs(ox) < 1e38 and abs(oy) < 1e38 and abs(oz) < 1e38):
        nan = np.float32(math.nan)
        return nan, nan, nan, nan, nan, nan, np.float32(0.0)
    ox32, oy32, oz32 = np.float32(ox), np.float32(oy), np.float32(oz)
    s = 0.0
    if abs(ix) < 1e38:
        s = max(s, abs((ox - np.float64(ox32)) * ix))
    if abs(iy) < 1e38:
        s = max(s, abs((oy - np.float64(oy32)) * iy))
    if abs(iz) < 1e38:
        s = max(s, abs((oz - np.float64(oz32)) * iz))
    return (ox32, oy32, oz32, _inv32(ix), _inv32(iy), _inv32(iz),
            np.float32(s * (1.0 + 2.0 ** -20) + 1e-43))   # + 1e-43: float32's subnormals round absolutely


@njit(**_INLINE)
def _up32(t):
    """A float32 at or above t >= 0 (the nearest float32 to t may be below it)."""
    return np.float32(t * (1.0 + 2.0 ** -22) + 1e-44)


@njit(**_INLINE)
def _axis(nf, q, col, o, inv, t0, t1):
    """Clip (t0, t1) to one axis's slab of a child's box, in float32: near and far planes in words col and
    col + 24 of row q."""
    ta = (nf[q * _ROW + np.uint64(col)] - o) * inv
    tb = (nf[q * _ROW + np.uint64(col + 24)] - o) * inv
    lo = tb if ta > tb else ta
    hi = ta if ta > tb else tb
    return (lo if lo > t0 else t0), (hi if hi < t1 else t1)


@njit(**_INLINE)
def _widen(n, f, s):
    """A child's entry distance (float32, inf where it is not entered) and the widened (n, f): (n, f) widened by
    the float32 test's error bound first, |t|·2^-21 + s on each side, so that the test can only let in more
    than exact arithmetic would."""
    nc = n - (abs(n) * _SLACK32 + s)
    fc = f + (abs(f) * _SLACK32 + s)
    return (nc if nc <= fc else _INF32), nc, fc


@njit(**_INLINE)
def _slabs8(nf, q, ox, oy, oz, ix, iy, iz, tmax, s, dist):
    """dist[c] = entry distance into child c's box of row q, or inf, for the eight children, in float32
    (ray from ``_ray32``, tmax from ``_up32``); returns the children entered as bits (bit c: child c).

    Written out lane by lane (straight-line, the same operations on columns c = 0..7) so that LLVM's
    SLP vectoriser can test the eight boxes at once, one AVX register per plane (see ``running.compiled``);
    the distances stay float32 (exactly what the test found) so that all eight fit one register.
    """
    n0, f0 = _axis(nf, q, 0, ox, ix, _F0, tmax)
    n1, f1 = _axis(nf, q, 1, ox, ix, _F0, tmax)
    n2, f2 = _axis(nf, q, 2, ox, ix, _F0, tmax)
    n3, f3 = _axis(nf, q, 3, ox, ix, _F0, tmax)
    n4, f4 = _axis(nf, q, 4, ox, ix, _F0, tmax)
    n5, f5 = _axis(nf, q, 5, ox, ix, _F0, tmax)
    n6, f6 = _axis(nf, q, 6, ox, ix, _F0, tmax)
    n7, f7 = _axis(nf, q, 7, ox, ix, _F0, tmax)
    n0, f0 = _axis(nf, q, 8, oy, iy, n0, f0)
    n1, f1 = _axis(nf, q, 9, oy, iy, n1, f1)
    n2, f2 = _axis(nf, q, 10, oy, iy, n2, f2)
    n3, f3 = _axis(nf, q, 11, oy, iy, n3, f3)
    n4, f4 = _axis(nf, q, 12, oy, iy, n4, f4)
    n5, f5 = _axis(nf, q, 13, oy, iy, n5, f5)
    n6, f6 = _axis(nf, q, 14, oy, iy, n6, f6)
    n7, f7 = _axis(nf, q, 15, oy, iy, n7, f7)
    n0, f0 = _axis(nf, q, 16, oz, iz, n0, f0)
    n1, f1 = _axis(nf, q, 17, oz, iz, n1, f1)
    n2, f2 = _axis(nf, q, 18, oz, iz, n2, f2)
    n3, f3 = _axis(nf, q, 19, oz, iz, n3, f3)
    n4, f4 = _axis(nf, q, 20, oz, iz, n4, f4)
    n5, f5 = _axis(nf, q, 21, oz, iz, n5, f5)
    n6, f6 = _axis(nf, q, 22, oz, iz, n6, f6)
    n7, f7 = _axis(nf, q, 23, oz, iz, n7, f7)
    dist[0], n0, f0 = _widen(n0, f0, s)
    dist[1], n1, f1 = _widen(n1, f1, s)
    dist[2], n2, f2 = _widen(n2, f2, s)
    dist[3], n3, f3 = _widen(n3, f3, s)
    dist[4], n4, f4 = _widen(n4, f4, s)
    dist[5], n5, f5 = _widen(n5, f5, s)
    dist[6], n6, f6 = _widen(n6, f6, s)
    dist[7], n7, f7 = _widen(n7, f7, s)
    return _le_bits8(n0, n1, n2, n3, n4, n5, n6, n7, f0, f1, f2, f3, f4, f5, f6, f7)


@njit(**_INLINE)
def _slots(ni, row):
    """How many of row's eight slots hold a child (for the count of boxes tested; -2 marks an empty one)."""
    k = row * _ROW + np.uint64(56)
    return _count_ne8(ni[k], ni[k + np.uint64(1)], ni[k + np.uint64(2)], ni[k + np.uint64(3)], ni[k + np.uint64(4)],
                      ni[k + np.uint64(5)], ni[k + np.uint64(6)], ni[k + np.uint64(7)], np.int32(-2))


@njit(**_INLINE)
def _prim_t(ox, oy, oz, dx, dy, dz, okx, oky, okz, kx, ky, kz, sx, sy, sz, k, j, nsph, sph, tris, tmax):
    """Distance to primitive k (row j of ``tris``: the leaf-ordered triangles, or the scene's own without a
    hierarchy): a sphere's first root ahead, or inf."""
    if k < nsph:
        t0, t1 = _sphere_roots(ox, oy, oz, dx, dy, dz, sph, k)
        return t0 if t0 > 0.0 else t1
    return _triangle(okx, oky, okz, kx, ky, kz, sx, sy, sz, tris, j, tmax)


@njit(**_INLINE)
def _closest_one(ox, oy, oz, dx, dy, dz, nf, ni, order, ltri, use_bvh, nsph, sph, tri, planes, stack, scnt,
                 snear, dist):
    """The nearest hit of one ray: (t, primitive number, nodes visited, primitive tests); (inf, -1) on a miss.

    The hierarchy is eight-wide (see ``hierarchy.eight_wide``): nf/ni are flat float32 and int32 views of
    the same 64-word rows, indexed unsigned (no negative-index wraparound, no stride loads); row 0 holds
    the root alone; ``ltri`` holds the triangles slot by slot (ltri[j] is triangle order[j] - nsph). The
    boxes are tested in float32, widened so that none the ray enters is missed (``_widen``); the hit itself
    is found in float64. The stack keeps each waiting child's row (or first slot), kind and entry distance.
    A row whose ray enters one or two children takes the nearer next without sorting; more are sorted. A child
    put on the stack is fetched into the cache meanwhile (``_fetch_child``: random rays 1.04x, primary the same).
    """
    ix, iy, iz, kx, ky, kz, sx, sy, sz, okx, oky, okz = _setup(ox, oy, oz, dx, dy, dz, use_bvh,
                                                               tri.shape[0] > 0 and not use_bvh)
    unsheared = use_bvh and tri.shape[0] > 0   # then the shear waits for the first leaf (``_setup``)
    nb = nsph + tri.shape[0]
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
    if not use_bvh:
        for k in range(nb):
            tests += 1
            t = _prim_t(ox, oy, oz, dx, dy, dz, okx, oky, okz, kx, ky, kz, sx, sy, sz, k, k - nsph, nsph, sph, tri, best)
            if 0.0 < t < best:
                best = t
                prim = k
        return best, prim, nodes, tests
    nodes += 1
    t = _root(nf, ox, oy, oz, ix, iy, iz, best)  # row 0 holds the root alone
    if t == math.inf:
        return best, prim, nodes, tests
    ox32, oy32, oz32, ix32, iy32, iz32, s32 = _ray32(ox, oy, oz, ix, iy, iz)  # only for rays that enter the root
    t32 = _up32(best)
    stack[0] = ni[48]
    scnt[0] = ni[56]
    snear[0] = t
    sp = 1
    q = 0
    cnt = 0
    go = False  # True: (q, cnt) is the next node, taken without a trip through the stack
    while go or sp > 0:
        if not go:
            sp -= 1
            if snear[np.uint64(sp)] > best:
                continue
            q = stack[np.uint64(sp)]
            cnt = scnt[np.uint64(sp)]
        go = False
        if cnt >= 0:  # a leaf
            if unsheared:
                kx, ky, kz, sx, sy, sz, okx, oky, okz = _shear(ox, oy, oz, dx, dy, dz)
                unsheared = False
            for j in range(q, q + cnt):
                k = order[j]
                tests += 1
                t = _prim_t(ox, oy, oz, dx, dy, dz, okx, oky, okz, kx, ky, kz, sx, sy, sz, k, j, nsph, sph, ltri, best)
                if 0.0 < t < best:
                    best = t
                    prim = k
                    t32 = _up32(best)
            continue
        row = np.uint64(q)  # unsigned: no negative-index wraparound on the row's loads
        mask = _slabs8(nf, row, ox32, oy32, oz32, ix32, iy32, iz32, t32, s32, dist)
        nodes += _slots(ni, row)
        if mask == 0:
            continue
        a = np.uint64(_lowest(mask))             # the first two children the ray enters, in slot order
        rest = mask & (mask - np.uint32(1))
        if rest == 0:                            # the one child is next
            q = ni[row * _ROW + np.uint64(48) + a]
            cnt = ni[row * _ROW + np.uint64(56) + a]
            go = True
            continue
        b = np.uint64(_lowest(rest))
        rest &= rest - np.uint32(1)
        if rest == 0:                            # the nearer is next, the other waits (on a tie, the lower slot first)
            near, far = (b, a) if dist[b] < dist[a] else (a, b)
            far_t = dist[far]
            stack[np.uint64(sp)] = ni[row * _ROW + np.uint64(48) + far]
            scnt[np.uint64(sp)] = ni[row * _ROW + np.uint64(56) + far]
            _fetch_child(nf, ltri, stack[np.uint64(sp)], scnt[np.uint64(sp)])
            snear[np.uint64(sp)] = far_t
            sp += 1
            q = ni[row * _ROW + np.uint64(48) + near]
            cnt = ni[row * _ROW + np.uint64(56) + near]
            go = True
            continue
        m = 0                                    # more: the entered ones, in slot order, to dist[8:16] and [16:24],
        while mask != 0:                         # then an insertion sort by distance (stable: slots ascend on ties)
            c = np.uint64(_lowest(mask))
            mask &= mask - np.uint32(1)
            dist[np.uint64(8 + m)] = dist[c]
            dist[np.uint64(16 + m)] = c
            m += 1
        for i in range(9, 8 + m):
            dv, cv = dist[i], dist[i + 8]
            j = i - 1
            while j >= 8 and dist[j] > dv:
                dist[j + 1] = dist[j]
                dist[j + 9] = dist[j + 8]
                j -= 1
            dist[j + 1] = dv
            dist[j + 9] = cv
        for i in range(7 + m, 8, -1):            # the others wait, far to near
            c = np.uint64(dist[i + 8])
            stack[np.uint64(sp)] = ni[row * _ROW + np.uint64(48) + c]
            scnt[np.uint64(sp)] = ni[row * _ROW + np.uint64(56) + c]
            _fetch_child(nf, ltri, stack[np.uint64(sp)], scnt[np.uint64(sp)])
            snear[np.uint64(sp)] = dist[i]
            sp += 1
        c = np.uint64(dist[16])                  # the nearest is next
        q = ni[row * _ROW + np.uint64(48) + c]
        cnt = ni[row * _ROW + np.uint64(56) + c]
        go = True
    return best, prim, nodes, tests


@njit(**_INLINE)
def _normal(prim, t, ox, oy, oz, dx, dy, dz, nsph, nb, sph, planes, tri_normal):
    """The unit geometric normal at the hit t of primitive prim (zero on a miss)."""
    if prim < 0:
        return 0.0, 0.0, 0.0
    if prim < nsph:
        r = sph[prim, 3]
        nx = (ox + t * dx - sph[prim, 0]) / r
        ny = (oy + t * dy - sph[prim, 1]) / r
        nz = (oz + t * dz - sph[prim, 2]) / r
        length = math.sqrt(nx ** 2 + ny ** 2 + nz ** 2)
        return nx / length, ny / length, nz / length
    if prim < nb:
        return tri_normal[prim - nsph, 0], tri_normal[prim - nsph, 1], tri_normal[prim - nsph, 2]
    return planes[prim - nb, 3], planes[prim - nb, 4], planes[prim - nb, 5]


@njit(**_JIT)
def closest(O, D, nf, ni, order, ltri, use_bvh, nsph, sph, tri, planes, tri_normal, out_t, out_prim,
            out_n, stats, stack, scnt, snear, dist, rays):
    """Closest hit of each ray: t (inf on a miss), primitive number (-1), unit normal; stats[i] = (nodes, tests).

    The last five arguments are one thread's ``scratch()``.
    """
    nb = nsph + tri.shape[0]
    for i in range(O.shape[0]):
        ox, oy, oz = O[i, 0], O[i, 1], O[i, 2]
        dx, dy, dz = D[i, 0], D[i, 1], D[i, 2]
        best, prim, nodes, tests = _closest_one(ox, oy, oz, dx, dy, dz, nf, ni, order, ltri, use_bvh, nsph, sph, tri,
                                                planes, stack, scnt, snear, dist)
        out_t[i] = best
        out_prim[i] = prim
        out_n[i, 0], out_n[i, 1], out_n[i, 2] = _normal(prim, best, ox, oy, oz, dx, dy, dz, nsph, nb, sph, planes,
                                                        tri_normal)
        stats[i, 0] = nodes
        stats[i, 1] = tests


@njit(**_INLINE)
def _material(k, x0, x1, x2, nb, prim_mat, planes, pframe, checker, checker_mat):
    """The material of primitive k at the point x: its own, or a checkerboard plane's odd squares'."""
    m = prim_mat[k]
    p = k - nb
    if p >= 0 and checker[p] > 0.0:
        rx, ry, rz = x0 - planes[p, 0], x1 - planes[p, 1], x2 - planes[p, 2]
        a = math.floor((rx * pframe[p, 0] + ry * pframe[p, 1] + rz * pframe[p, 2]) / checker[p])
        b = math.floor((rx * pframe[p, 3] + ry * pframe[p, 4] + rz * pframe[p, 5]) / checker[p])
        if (a + b) % 2 == 1:
            m = checker_mat[p]
    return m


@njit(**_INLINE)
def _attenuate(T0, T1, T2, k, t, ox, oy, oz, dx, dy, dz, nb, prim_mat, trans, planes, pframe, checker, checker_mat):
    """(T0, T1, T2) times the transmittance of primitive k crossed at t, and whether it is now zero."""
    m = _material(k, ox + t * dx, oy + t * dy, oz + t * dz, nb, prim_mat, planes, pframe, checker, checker_mat)
    T0 *= trans[m, 0]
    T1 *= trans[m, 1]
    T2 *= trans[m, 2]
    return T0, T1, T2, not (T0 > 0.0 or T1 > 0.0 or T2 > 0.0)


@njit(**_INLINE)
def _cross(T0, T1, T2, k, j, ox, oy, oz, dx, dy, dz, shear, tmax, nsph, sph, tris, nb, prim_mat, trans, planes,
           pframe, checker, checker_mat):
    """A shadow ray against primitive k (row j of ``tris``): (T0, T1, T2) times the transmittance of each
    crossing on (0, tmax), nearer first for a sphere, and whether the light is now blocked. ``shear``: the
    watertight test's axes, shear and permuted origin (``_shear``), in one tuple (numba inlines calls of at
    most 30 arguments)."""
    if k < nsph:
        t0, t1 = _sphere_roots(ox, oy, oz, dx, dy, dz, sph, k)
        if 0.0 < t0 < tmax:
            T0, T1, T2, blocked = _attenuate(T0, T1, T2, k, t0, ox, oy, oz, dx, dy, dz, nb, prim_mat, trans,
                                             planes, pframe, checker, checker_mat)
            if blocked:
                return 0.0, 0.0, 0.0, True
        if 0.0 < t1 < tmax:
            return _attenuate(T0, T1, T2, k, t1, ox, oy, oz, dx, dy, dz, nb, prim_mat, trans, planes, pframe,
                              checker, checker_mat)
        return T0, T1, T2, False
    kx, ky, kz, sx, sy, sz, okx, oky, okz = shear
    t = _triangle(okx, oky, okz, kx, ky, kz, sx, sy, sz, tris, j, tmax)
    if t < tmax:
        return _attenuate(T0, T1, T2, k, t, ox, oy, oz, dx, dy, dz, nb, prim_mat, trans, planes, pframe, checker,
                          checker_mat)
    return T0, T1, T2, False


@njit(**_INLINE)
def _transmit_one(ox, oy, oz, dx, dy, dz, tmax, nf, ni, order, ltri, use_bvh, nsph, sph, tri, planes, pframe,
                  checker, checker_mat, prim_mat, trans, stack, scnt, dist):
    """One shadow ray: the product (T0, T1, T2) of the transmittances crossed on (0, tmax), zero once an
    opaque surface is crossed (any hit: the search stops there), and (nodes, tests).

    Without a hierarchy the primitives are taken in one plain loop, as ``_closest_one`` does: through the
    traversal's loop (a node at a time, none on the stack) the whitted scene's shadow rays took 1.2-1.5x as long.
    """
    ix, iy, iz, kx, ky, kz, sx, sy, sz, okx, oky, okz = _setup(ox, oy, oz, dx, dy, dz, use_bvh, tri.shape[0] > 0)
    shear = (kx, ky, kz, sx, sy, sz, okx, oky, okz)
    nb = nsph + tri.shape[0]
    T0, T1, T2 = 1.0, 1.0, 1.0
    nodes = 0
    tests = 0
    blocked = False
    for p in range(planes.shape[0]):
        tests += 1
        dn = dx * planes[p, 3] + dy * planes[p, 4] + dz * planes[p, 5]
        if dn != 0.0:
            t = ((planes[p, 0] - ox) * planes[p, 3] + (planes[p, 1] - oy) * planes[p, 4]
                 + (planes[p, 2] - oz) * planes[p, 5]) / dn
            if 0.0 < t < tmax:
                T0, T1, T2, blocked = _attenuate(T0, T1, T2, nb + p, t, ox, oy, oz, dx, dy, dz, nb, prim_mat, trans,
                                                 planes, pframe, checker, checker_mat)
                if blocked:
                    return 0.0, 0.0, 0.0, nodes, tests
    if not use_bvh:             # every primitive in turn
        for k in range(nb):
            tests += 1
            T0, T1, T2, blocked = _cross(T0, T1, T2, k, k - nsph, ox, oy, oz, dx, dy, dz, shear, tmax, nsph, sph, tri,
                                         nb, prim_mat, trans, planes, pframe, checker, checker_mat)
            if blocked:
                return 0.0, 0.0, 0.0, nodes, tests
        return T0, T1, T2, nodes, tests
    nodes += 1
    if _root(nf, ox, oy, oz, ix, iy, iz, tmax) == math.inf:   # row 0 holds the root alone
        return T0, T1, T2, nodes, tests
    ox32, oy32, oz32, ix32, iy32, iz32, s32 = _ray32(ox, oy, oz, ix, iy, iz)  # only for rays that enter it
    t32 = _up32(tmax)
    stack[0] = ni[48]
    scnt[0] = ni[56]
    sp = 1
    while sp > 0:
        sp -= 1
        q = stack[np.uint64(sp)]
        cnt = scnt[np.uint64(sp)]
        if cnt < 0:                    # a row: its children wait on the stack, the last slot on top
            row = np.uint64(q)
            mask = _slabs8(nf, row, ox32, oy32, oz32, ix32, iy32, iz32, t32, s32, dist)
            nodes += _slots(ni, row)
            for c in range(8):
                stack[np.uint64(sp)] = ni[row * _ROW + np.uint64(48 + c)]
                scnt[np.uint64(sp)] = ni[row * _ROW + np.uint64(56 + c)]
                sp += (mask >> np.uint32(c)) & np.uint32(1)
            continue
        for j in range(q, q + cnt):    # a leaf
            tests += 1
            T0, T1, T2, blocked = _cross(T0, T1, T2, order[j], j, ox, oy, oz, dx, dy, dz, shear, tmax, nsph, sph,
                                         ltri, nb, prim_mat, trans, planes, pframe, checker, checker_mat)
            if blocked:
                return 0.0, 0.0, 0.0, nodes, tests
    return T0, T1, T2, nodes, tests


@njit(**_JIT)
def transmission(O, D, TMAX, nf, ni, order, ltri, use_bvh, nsph, sph, tri, planes, pframe,
                 checker, checker_mat, prim_mat, trans, out, stats, stack, scnt, snear, dist, rays):
    """Shadow rays: out[i] = product of the transmittances crossed on (0, TMAX[i]); stops at an opaque one.

    The last five arguments are one thread's ``scratch()``.
    """
    for i in range(O.shape[0]):
        out[i, 0], out[i, 1], out[i, 2], nodes, tests = _transmit_one(
            O[i, 0], O[i, 1], O[i, 2], D[i, 0], D[i, 1], D[i, 2], TMAX[i], nf, ni, order, ltri, use_bvh, nsph, sph,
            tri, planes, pframe, checker, checker_mat, prim_mat, trans, stack, scnt, dist)
        stats[i, 0] = nodes
        stats[i, 1] = tests


@njit(**_JIT)
def camera(eye, forward, right, up, tan_x, tan_y, width, height, O, D):
    """W1's camera rays, in the numpy version's operations and order (so bit for bit the same rays)."""
    for j in range(height):
        y = (1.0 - 2.0 * (j + 0.5) / height) * tan_y
        for i in range(width):
            x = (2.0 * (i + 0.5) / width - 1.0) * tan_x
            k = j * width + i
            dx = (forward[0] + x * right[0]) + y * up[0]
            dy = (forward[1] + x * right[1]) + y * up[1]
            dz = (forward[2] + x * right[2]) + y * up[2]
            length = math.sqrt(dx * dx + dy * dy + dz * dz)
            D[k, 0], D[k, 1], D[k, 2] = dx / length, dy / length, dz / length
            O[k, 0], O[k, 1], O[k, 2] = eye[0], eye[1], eye[2]


# --- a whole Whitted frame, one camera ray at a time -------------------------------------------------
# The same steps as the numpy wavefront of tracer.trace (handout §W11), in nearly the same floating-point
# operations, so the two agree to rounding: a pixel's contributions are summed depth first here, bounce by
# bounce there; unit vectors are scaled by one reciprocal instead of three divisions, and whole Phong
# exponents are taken by repeated squaring (``_power``). Where a decision hangs on a sign (a light in
# front of the surface, a side to spawn to) the two see the same (the tests compare the rays each casts).

#: Columns of the material rows the frame kernel reads (``frame_arrays``).
M_AMBIENT, M_DIFFUSE, M_SPECULAR, M_SHININESS, M_EMISSION = 0, 3, 6, 9, 10
M_REFLECT, M_TRANSMIT, M_IOR, M_FRESNEL, M_WIDTH = 13, 16, 19, 20, 21
#: Columns of the light rows: position, diffuse, specular, attenuation (constant, linear, quadratic),
#: the emitting side of an area light and 1 where it has one.
L_POS, L_DIFFUSE, L_SPECULAR, L_ATT, L_NORMAL, L_AREA, L_WIDTH = 0, 3, 6, 9, 12, 15, 16


@njit(**_INLINE)
def _spawn(px, py, pz, nx, ny, nz, dx, dy, dz, offset):
    """``cs451.tracescene.spawn`` for one ray: off the surface by (1 + max|p|)·offset to the side it leaves by."""
    side = nx * dx + ny * dy + nz * dz
    s = 1.0 if side >= 0.0 else -1.0     # sign(0) counts as +1, as spawn does
    scale = (1.0 + max(abs(px), abs(py), abs(pz))) * offset
    return px + nx * (s * scale), py + ny * (s * scale), pz + nz * (s * scale)


@njit(**_INLINE)
def _push(rays, top, px, py, pz, nx, ny, nz, dx, dy, dz, w0, w1, w2, depth, offset):
    """Put a secondary ray on the waiting stack: its direction normalised, its origin spawned off the surface."""
    inv = 1.0 / math.sqrt(dx * dx + dy * dy + dz * dz)
    dx, dy, dz = dx * inv, dy * inv, dz * inv
    rays[top, 0], rays[top, 1], rays[top, 2] = _spawn(px, py, pz, nx, ny, nz, dx, dy, dz, offset)
    rays[top, 3], rays[top, 4], rays[top, 5] = dx, dy, dz
    rays[top, 6], rays[top, 7], rays[top, 8], rays[top, 9] = w0, w1, w2, depth
    return top + 1


@njit(**_INLINE)
def _power(x, s):
    """x ** s, by repeated squaring where s is a whole number below 2¹⁶ (as Phong exponents are): within a
    few ulps of pow (so the frame agrees with the numpy path to rounding) and several times faster."""
    if not (s == math.floor(s) and 0.0 <= s < 65536.0):
        return x ** s
    n = int(s)
    r = 1.0
    while n > 0:
        if n & 1:
            r *= x
        x *= x
        n >>= 1
    return r


@njit(**_INLINE)
def _fresnel(cos_i, eta):
    """W10 for one ray: unpolarised Fresnel reflectance, 1 under total internal reflection."""
    cos_i = min(max(cos_i, 0.0), 1.0)
    sin2_t = eta * eta * (1.0 - cos_i * cos_i)
    if sin2_t >= 1.0:
        return 1.0
    cos_t = math.sqrt(max(0.0, 1.0 - sin2_t))
    rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    f = 0.5 * (rs * rs + rp * rp)
    return 1.0 if math.isnan(f) else f


@njit(**_JIT)
def frame(O, D, nf, ni, order, ltri, use_bvh, nsph, sph, tri, planes, tri_normal, pframe, checker, checker_mat,
          prim_mat, trans, mats, lights, ambient, background, max_depth, min_weight, offset, out, counts,
          stack, scnt, snear, dist, rays):
    """The colour out[i] seen along each camera ray (W11, per ray): closest hit, emission and ambient, each
    light through its shadow ray, then the reflected and transmitted rays, depth first on a small stack.

    counts[i] = (shadow, reflection, transmission, nodes visited, primitive tests) for camera ray i. The
    last five arguments are one thread's ``scratch(max_depth)``: ``rays`` holds the waiting rays.
    """
    nb = nsph + tri.shape[0]
    cut = max(min_weight, 1e-300)
    for i in range(O.shape[0]):
        c0, c1, c2 = 0.0, 0.0, 0.0
        n_shadow, n_reflect, n_transmit, nodes, tests = 0, 0, 0, 0, 0
        rays[0, 0], rays[0, 1], rays[0, 2] = O[i, 0], O[i, 1], O[i, 2]
        rays[0, 3], rays[0, 4], rays[0, 5] = D[i, 0], D[i, 1], D[i, 2]
        rays[0, 6], rays[0, 7], rays[0, 8], rays[0, 9] = 1.0, 1.0, 1.0, 0.0
        top = 1
        while top > 0:
            top -= 1
            ox, oy, oz = rays[top, 0], rays[top, 1], rays[top, 2]
            dx, dy, dz = rays[top, 3], rays[top, 4], rays[top, 5]
            b0, b1, b2 = rays[top, 6], rays[top, 7], rays[top, 8]
            depth = int(rays[top, 9])
            t, prim, nv, nt = _closest_one(ox, oy, oz, dx, dy, dz, nf, ni, order, ltri, use_bvh, nsph, sph, tri,
                                           planes, stack, scnt, snear, dist)
            nodes += nv
            tests += nt
            if prim < 0:
                c0 += b0 * background[0]
                c1 += b1 * background[1]
                c2 += b2 * background[2]
                continue
            nx, ny, nz = _normal(prim, t, ox, oy, oz, dx, dy, dz, nsph, nb, sph, planes, tri_normal)
            px, py, pz = ox + t * dx, oy + t * dy, oz + t * dz
            m = _material(prim, px, py, pz, nb, prim_mat, planes, pframe, checker, checker_mat)
            cos = -(dx * nx + dy * ny + dz * nz)
            entering = cos >= 0.0
            if not entering:                   # the normal on the ray's side
                nx, ny, nz = -nx, -ny, -nz
            l0 = mats[m, M_EMISSION] + mats[m, M_AMBIENT] * ambient[0]
            l1 = mats[m, M_EMISSION + 1] + mats[m, M_AMBIENT + 1] * ambient[1]
            l2 = mats[m, M_EMISSION + 2] + mats[m, M_AMBIENT + 2] * ambient[2]
            kd0, kd1, kd2 = mats[m, M_DIFFUSE], mats[m, M_DIFFUSE + 1], mats[m, M_DIFFUSE + 2]
            ks0, ks1, ks2 = mats[m, M_SPECULAR], mats[m, M_SPECULAR + 1], mats[m, M_SPECULAR + 2]
            shiny = kd0 > 0.0 or kd1 > 0.0 or kd2 > 0.0 or ks0 > 0.0 or ks1 > 0.0 or ks2 > 0.0
            for k in range(lights.shape[0] if shiny else 0):
                # TraceScene.light_toward
                vx, vy, vz = lights[k, L_POS] - px, lights[k, L_POS + 1] - py, lights[k, L_POS + 2] - pz
                r = math.sqrt(vx * vx + vy * vy + vz * vz)
                inv = 1.0 / (r if r > 0.0 else 1.0)
                lx, ly, lz = vx * inv, vy * inv, vz * inv
                att = 1.0 / (lights[k, L_ATT] + lights[k, L_ATT + 1] * r + lights[k, L_ATT + 2] * r * r)
                if lights[k, L_AREA] > 0.0:
                    att = att * max(-(lx * lights[k, L_NORMAL] + ly * lights[k, L_NORMAL + 1]
                                      + lz * lights[k, L_NORMAL + 2]), 0.0)
                if not r > 0.0:
                    att = 0.0
                ld0, ld1, ld2 = lights[k, L_DIFFUSE] * att, lights[k, L_DIFFUSE + 1] * att, lights[k, L_DIFFUSE + 2] * att
                ls0, ls1, ls2 = (lights[k, L_SPECULAR] * att, lights[k, L_SPECULAR + 1] * att,
                                 lights[k, L_SPECULAR + 2] * att)
                n_dot_l = nx * lx + ny * ly + nz * lz
                if not (n_dot_l > 0.0 and (ld0 > 0.0 or ld1 > 0.0 or ld2 > 0.0 or ls0 > 0.0 or ls1 > 0.0 or ls2 > 0.0)):
                    continue                   # no shadow ray toward a light behind the surface
                # the shadow ray (W7), from the spawned point to the light sample
                sx, sy, sz = _spawn(px, py, pz, nx, ny, nz, lx, ly, lz, offset)
                wx, wy, wz = lights[k, L_POS] - sx, lights[k, L_POS + 1] - sy, lights[k, L_POS + 2] - sz
                length = math.sqrt(wx * wx + wy * wy + wz * wz)
                inv = 1.0 / (length if length > 0.0 else 1.0)
                T0, T1, T2, nv, nt = _transmit_one(sx, sy, sz, wx * inv, wy * inv, wz * inv, length, nf, ni, order, ltri,
                                                   use_bvh, nsph, sph, tri, planes, pframe, checker, checker_mat,
                                                   prim_mat, trans, stack, scnt, dist)
                n_shadow += 1
                nodes += nv
                tests += nt
                if T0 == 0.0 and T1 == 0.0 and T2 == 0.0:
                    continue                   # in shadow: the terms below would add exact zeros
                # local shading (W6), Lambert plus Blinn-Phong toward the eye (-d)
                hx, hy, hz = lx - dx, ly - dy, lz - dz
                inv = 1.0 / max(math.sqrt(hx * hx + hy * hy + hz * hz), 1e-300)
                hx, hy, hz = hx * inv, hy * inv, hz * inv
                n_dot_h = max(nx * hx + ny * hy + nz * hz, 0.0)
                spec = _power(n_dot_h, mats[m, M_SHININESS])
                lam = max(n_dot_l, 0.0)
                l0 += kd0 * (ld0 * T0) * lam + ks0 * (ls0 * T0) * spec
                l1 += kd1 * (ld1 * T1) * lam + ks1 * (ls1 * T1) * spec
                l2 += kd2 * (ld2 * T2) * lam + ks2 * (ls2 * T2) * spec
            c0 += b0 * l0
            c1 += b1 * l1
            c2 += b2 * l2
            if depth == max_depth:
                continue
            kr0, kr1, kr2 = mats[m, M_REFLECT], mats[m, M_REFLECT + 1], mats[m, M_REFLECT + 2]
            kt0, kt1, kt2 = mats[m, M_TRANSMIT], mats[m, M_TRANSMIT + 1], mats[m, M_TRANSMIT + 2]
            ior = mats[m, M_IOR]
            eta = 1.0 / ior if entering else ior
            f = 0.0
            tx, ty, tz = 0.0, 0.0, 0.0
            if kt0 > 0.0 or kt1 > 0.0 or kt2 > 0.0:       # glass: refraction (W9), Fresnel (W10)
                cos_i = -(dx * nx + dy * ny + dz * nz)
                sin2_t = eta * eta * max(0.0, 1.0 - cos_i * cos_i)
                if sin2_t > 1.0:
                    f = 1.0                    # total internal reflection: all of kt is reflected
                else:
                    cos_t = math.sqrt(max(0.0, 1.0 - sin2_t))
                    g = eta * cos_i - cos_t
                    tx, ty, tz = eta * dx + g * nx, eta * dy + g * ny, eta * dz + g * nz
                    if mats[m, M_FRESNEL] > 0.0:
                        f = _fresnel(abs(cos), eta)
            wr0, wr1, wr2 = b0 * (kr0 + kt0 * f), b1 * (kr1 + kt1 * f), b2 * (kr2 + kt2 * f)
            wt0, wt1, wt2 = b0 * kt0 * (1.0 - f), b1 * kt1 * (1.0 - f), b2 * kt2 * (1.0 - f)
            if max(wt0, wt1, wt2) >= cut:     # the β cut-off
                top = _push(rays, top, px, py, pz, nx, ny, nz, tx, ty, tz, wt0, wt1, wt2, depth + 1, offset)
                n_transmit += 1
            if max(wr0, wr1, wr2) >= cut:
                g = 2.0 * (dx * nx + dy * ny + dz * nz)
                top = _push(rays, top, px, py, pz, nx, ny, nz, dx - g * nx, dy - g * ny, dz - g * nz, wr0, wr1, wr2,
                            depth + 1, offset)
                n_reflect += 1
        out[i, 0], out[i, 1], out[i, 2] = c0, c1, c2
        counts[i, 0], counts[i, 1], counts[i, 2], counts[i, 3], counts[i, 4] = (n_shadow, n_reflect, n_transmit,
                                                                                 nodes, tests)
