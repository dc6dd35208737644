"""The reference's hierarchy and traversals in plain numpy, every ray of a batch at once: what a clear
vectorised student solution looks like.

The kit's compiled kernels (instructor-side, ``cs451/stages/whitted/accel/``) take the reference's large
batches through its one hook; both give the same hits (``tests/whitted/test_whitted_robust.py`` checks).
"""
# BEGIN SOLUTION
from __future__ import annotations

import numpy as np

from cs451.tracescene import TraceScene

from .intersect import intersect_sphere, intersect_triangle


def median_bvh(lo: np.ndarray, hi: np.ndarray, leaf: int = 4) -> dict[str, np.ndarray]:
    """A hierarchy built level by level, every node of a level split at once at its median
    along the widest axis of its centres (no Python loop over nodes)."""
    n = len(lo)
    cen = 0.5 * (lo + hi)
    order = np.arange(n)
    seg_s, seg_e, seg_node = np.array([0]), np.array([n]), np.array([0])
    child = [np.array([-1])]
    starts, counts = [np.array([0])], [np.array([n])]
    n_nodes = 1
    levels = [seg_node]
    while True:
        split = seg_e - seg_s > leaf
        if not split.any():
            break
        s, e, node = seg_s[split], seg_e[split], seg_node[split]
        size = e - s
        seg_id = np.repeat(np.arange(len(s)), size)
        pos = np.repeat(s, size) + (np.arange(size.sum()) - np.repeat(np.cumsum(size) - size, size))
        c = cen[order[pos]]
        big = np.maximum.reduceat(c, np.cumsum(size) - size) - np.minimum.reduceat(c, np.cumsum(size) - size)
        axis = np.argmax(big, axis=1)
        key = c[np.arange(len(pos)), axis[seg_id]]
        perm = np.lexsort((key, seg_id))
        order[pos] = order[pos][perm]
        mid = s + size // 2
        first = n_nodes + 2 * np.arange(len(s))
        n_nodes += 2 * len(s)
        child.append(np.full(2 * len(s), -1))
        full_child = np.concatenate(child)
        full_child[node] = first
        child = [full_child]
        kids = np.stack([first, first + 1], axis=1).ravel()
        ks = np.stack([s, mid], axis=1).ravel()
        ke = np.stack([mid, e], axis=1).ravel()
        starts.append(ks)
        counts.append(ke - ks)
        seg_s, seg_e, seg_node = ks, ke, kids
        levels.append(kids)
    child_arr = np.concatenate(child)
    start = np.concatenate(starts)
    count = np.concatenate(counts)
    nlo = np.empty((n_nodes, 3))
    nhi = np.empty((n_nodes, 3))
    leaves = np.nonzero(child_arr < 0)[0]
    leaves = leaves[np.argsort(start[leaves])]
    nlo[leaves] = np.minimum.reduceat(lo[order], start[leaves])
    nhi[leaves] = np.maximum.reduceat(hi[order], start[leaves])
    for level in reversed(levels):
        inner = level[child_arr[level] >= 0]
        c = child_arr[inner]
        nlo[inner] = np.minimum(nlo[c], nlo[c + 1])
        nhi[inner] = np.maximum(nhi[c], nhi[c + 1])
    leaf_mask = child_arr < 0
    return {"lo": nlo, "hi": nhi, "child": child_arr, "start": np.where(leaf_mask, start, 0),
            "count": np.where(leaf_mask, count, 0), "order": order}


def _box_near(lo, hi, o, inv, tmax):
    t0 = (lo - o) * inv
    t1 = (hi - o) * inv
    near = np.nanmax(np.minimum(t0, t1), axis=1)
    far = np.nanmin(np.maximum(t0, t1), axis=1)
    near = np.maximum(near, 0.0)
    return np.where(near <= np.minimum(far, tmax) * (1 + 1e-15), near, np.inf)


def _pair_hits(scene: TraceScene, o, d, prim, tmax) -> tuple[np.ndarray, np.ndarray]:
    """Both crossings (t0, t1) of each ray with its primitive; a triangle's t1 is inf."""
    t0 = np.full(len(prim), np.inf)
    t1 = np.full(len(prim), np.inf)
    s = prim < scene.n_spheres
    if s.any():
        k = prim[s]
        t0[s], t1[s] = intersect_sphere(o[s], d[s], scene.sphere_center[k], scene.sphere_radius[k])
    tr = ~s
    if tr.any():
        k = prim[tr] - scene.n_spheres
        t0[tr] = intersect_triangle(o[tr], d[tr], scene.tri_v0[k], scene.tri_v1[k], scene.tri_v2[k])
    return t0, t1


def _candidates(scene: TraceScene, o, d, tmax, best=None):
    """(ray, primitive) pairs whose leaf boxes the rays enter, level by level; returns (rays, prims, nodes)."""
    n = len(o)
    if scene.bvh is None:
        rays = np.repeat(np.arange(n), scene.n_bounded)
        return [(rays, np.tile(np.arange(scene.n_bounded), n))], 0
    b = scene.bvh
    with np.errstate(divide="ignore"):
        inv = 1.0 / d
    ray = np.arange(n)
    node = np.zeros(n, np.int64)
    nodes = 0
    out = []
    while len(ray):
        nodes += len(ray)
        limit = tmax[ray] if best is None else best[ray]
        with np.errstate(invalid="ignore"):
            near = _box_near(b["lo"][node], b["hi"][node], o[ray], inv[ray], limit)
        keep = np.isfinite(near)
        ray, node = ray[keep], node[keep]
        leaf = b["child"][node] < 0
        lr, ln = ray[leaf], node[leaf]
        if len(lr):
            cnt = b["count"][ln]
            rep = np.repeat(lr, cnt)
            offset = np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt)
            prims = b["order"][np.repeat(b["start"][ln], cnt) + offset]
            out.append((rep, prims))
            if best is not None:   # closest hit: tighten each ray's bound before going deeper
                _update_best(scene, o, d, rep, prims, best, out)
        ir, inn = ray[~leaf], node[~leaf]
        ray = np.concatenate([ir, ir])
        node = np.concatenate([b["child"][inn], b["child"][inn] + 1])
    return out, nodes


def _update_best(scene, o, d, rays, prims, best, out):
    t0, t1 = _pair_hits(scene, o[rays], d[rays], prims, best[rays])
    t = np.where(t0 > 0, t0, t1)
    ok = (t > 0) & (t < best[rays])
    np.minimum.at(best, rays[ok], t[ok])
    out[-1] = (rays, prims, t)


def closest(scene: TraceScene, o: np.ndarray, d: np.ndarray):
    """Closest hits by wavefront traversal: (t, prim, normals, nodes, tests)."""
    n = len(o)
    best = np.full(n, np.inf)
    prim = np.full(n, -1, np.int64)
    tests = 0
    for p in range(scene.n_planes):
        nrm = scene.plane_normal[p]
        dn = d @ nrm
        with np.errstate(divide="ignore", invalid="ignore"):
            t = ((scene.plane_point[p] - o) @ nrm) / dn
        ok = (dn != 0) & (t > 0) & (t < best)
        best[ok], prim[ok] = t[ok], scene.n_bounded + p
        tests += n
    plane_best = best.copy()
    if scene.bvh is None:
        for k in range(scene.n_bounded):
            rays = np.arange(n)
            t0, t1 = _pair_hits(scene, o, d, np.full(n, k), best)
            t = np.where(t0 > 0, t0, t1)
            ok = (t > 0) & (t < best)
            best[ok], prim[ok] = t[ok], k
            tests += n
        nodes = 0
    else:
        found, nodes = _candidates(scene, o, d, best.copy(), best=best)
        for rays, prims, t in found:
            tests += len(rays)
            win = (t == best[rays]) & (t < plane_best[rays])
            prim[rays[win]] = prims[win]
    hit = prim >= 0
    normals = np.zeros((n, 3))
    x = o[hit] + best[hit, None] * d[hit]
    k = prim[hit]
    nrm = np.zeros((len(k), 3))
    s = k < scene.n_spheres
    nrm[s] = x[s] - scene.sphere_center[k[s]]
    tr = (k >= scene.n_spheres) & (k < scene.n_bounded)
    kt = k[tr] - scene.n_spheres
    nrm[tr] = np.cross(scene.tri_v1[kt] - scene.tri_v0[kt], scene.tri_v2[kt] - scene.tri_v0[kt])
    pl = k >= scene.n_bounded
    nrm[pl] = scene.plane_normal[k[pl] - scene.n_bounded]
    normals[hit] = nrm / np.linalg.norm(nrm, axis=1, keepdims=True)
    return best, prim, normals, nodes, tests


def transmission(scene: TraceScene, o: np.ndarray, d: np.ndarray, dist: np.ndarray):
    """Shadow rays by wavefront traversal: (factor (n, 3), nodes, tests)."""
    n = len(o)
    out = np.ones((n, 3))
    tests = 0

    def attenuate(rays, prims, t):
        ok = (t > 0) & (t < dist[rays])
        if ok.any():
            r = rays[ok]
            m = scene.material_at(prims[ok], o[r] + t[ok, None] * d[r])
            np.multiply.at(out, r, scene.mat_transmittance[m])

    for p in range(scene.n_planes):
        nrm = scene.plane_normal[p]
        dn = d @ nrm
        with np.errstate(divide="ignore", invalid="ignore"):
            t = ((scene.plane_point[p] - o) @ nrm) / dn
        attenuate(np.arange(n), np.full(n, scene.n_bounded + p), np.where(dn != 0, t, np.inf))
        tests += n
    found, nodes = _candidates(scene, o, d, dist)
    for rays, prims in found:
        tests += len(rays)
        t0, t1 = _pair_hits(scene, o[rays], d[rays], prims, dist[rays])
        attenuate(rays, prims, t0)
        attenuate(rays, prims, t1)
    return out, nodes, tests
# END SOLUTION
