"""Stage 2's checks: they compare a submission's arrays with the truths' (``expected``) and compute no answer.

Shipped to students with the public tests. Every shape is checked against the
test's parameters before any work is done on an answer, so an answer of the
wrong size fails at once instead of costing the grader time.
"""
from __future__ import annotations

import numpy as np

from cs451 import tracescene
from cs451.grading.checks import output
from cs451.grading.spec import Verdict
from cs451.stages.whitted import tolerances as TOL


def ray_count(p: dict) -> int:
    """How many rays a test sends: one per origin."""
    return len(np.asarray(p["origins"], float).reshape(-1, 3))


def _few(bad: list[str]) -> str | None:
    return "; ".join(bad[:3]) + (f" (and {len(bad) - 3} more)" if len(bad) > 3 else "") if bad else None


# --- W1 ------------------------------------------------------------------------------------

def camera_origins(out, expected, p):
    n = p["width"] * p["height"]
    origins = output(out, "origins", (n, 3), "origins")
    eye = np.asarray(expected["eye"], float)
    if not np.allclose(origins, eye, rtol=TOL.FLOAT64, atol=TOL.FLOAT64 * (1 + np.abs(eye).max())):
        return "every ray must start at the eye"


def camera_unit(out, expected, p):
    d = output(out, "directions", (p["width"] * p["height"], 3), "directions")
    length = np.linalg.norm(d, axis=1)
    if not np.allclose(length, 1.0, atol=TOL.FLOAT64):
        return f"directions must be unit vectors (lengths from {length.min():.6g} to {length.max():.6g})"


def camera_pixels(out, expected, p):
    w = p["width"]
    d = output(out, "directions", (p["width"] * p["height"], 3), "directions")
    eye = np.asarray(expected["eye"], float)
    x = np.c_[eye + d, np.ones(len(d))] @ np.asarray(expected["clip_from_world"], float).T  # 1 unit along each ray
    if np.any(x[:, 3] <= 0):
        return "some rays point behind the camera"
    ndc = x[:, :2] / x[:, 3:4]
    want = np.asarray(expected["ndc"], float)
    err = np.abs(ndc - want).max(axis=1)
    if err.max() > TOL.NDC:
        k = int(np.argmax(err))
        return (f"ray {k} (column {k % w}, row {k // w}) goes through NDC {ndc[k].round(5).tolist()}, "
                f"expected the pixel centre {want[k].round(5).tolist()} (rows from the top)")


# --- W2, W3 --------------------------------------------------------------------------------------

def sphere_roots(out, expected, p, rel: float = TOL.FLOAT64):
    n = ray_count(p)
    got0, got1 = output(out, "t0", (n,), "t0"), output(out, "t1", (n,), "t1")
    want0, want1 = np.asarray(expected["t0"], float), np.asarray(expected["t1"], float)
    bad = []
    for i in range(n):
        want, got = (want0[i], want1[i]), (got0[i], got1[i])
        if np.isinf(want[0]) != np.isinf(got[0]) or np.isinf(want[1]) != np.isinf(got[1]):
            bad.append(f"ray {i}: {'a miss' if np.isinf(want[0]) else 'a hit'} expected, got t = {got}")
            continue
        if not np.isinf(want[0]):
            scale = rel * max(abs(want[1]), p["radius"])
            if abs(got[0] - want[0]) > scale or abs(got[1] - want[1]) > scale:
                bad.append(f"ray {i}: t = ({got[0]:.12g}, {got[1]:.12g}), exact ({want[0]:.12g}, {want[1]:.12g})")
    return _few(bad)


def triangle_hits(out, expected, p, rel: float = TOL.FLOAT64):
    """Every ray not exactly on an edge has the exact t (inf on a miss)."""
    n = ray_count(p)
    got = output(out, "t", (n,), "t")
    want, edge = np.asarray(expected["t"], float), np.asarray(expected["edge"], bool)
    bad = []
    for i in range(n):
        if edge[i]:
            continue  # exactly on an edge: either answer is right here (the watertight tests check edges)
        if np.isinf(want[i]) != np.isinf(got[i]) or (not np.isinf(want[i]) and abs(got[i] - want[i]) > rel * max(1.0, abs(want[i]))):
            bad.append(f"ray {i}: t = {got[i]:.12g}, exact {want[i]:.12g}")
    return _few(bad)


def no_gaps(out, expected, p, rays: int, triangles: int):
    """Rays aimed at points of a fan on its shared edges and vertices (each reaches its point at t = 1), each
    paired with every triangle: each must hit at least one triangle there, and any other hit where exact
    arithmetic puts it (rounding can move a ray off a vertex in exact arithmetic, so t = 1 is the yardstick)."""
    t = output(out, "t", (rays * triangles,), "t").reshape(rays, triangles)
    want = np.asarray(expected["t"], float).reshape(rays, triangles)
    edge = np.asarray(expected["edge"], bool).reshape(rays, triangles)
    at_target = np.isfinite(t) & (np.abs(t - 1.0) <= TOL.FLOAT64)
    leaks = int((~at_target.any(axis=1)).sum())
    if leaks:
        return f"{leaks} of {rays} rays through shared edges or vertices hit none of the triangles (a gap) at t = 1"
    checkable = np.isfinite(t) & np.isfinite(want) & ~edge
    diff = np.abs(np.where(checkable, t, 0.0) - np.where(checkable, want, 0.0))
    wrong = checkable & (diff > TOL.FLOAT64 * np.maximum(1.0, np.abs(np.where(checkable, want, 1.0))))
    if wrong.any():
        i, j = np.argwhere(wrong)[0]
        return f"ray {int(i)} hits triangle {int(j)} at t = {t[i, j]:.12g}, but exactly it is at {want[i, j]:.12g}"


def grid_hits(out, expected, p, rays: int, triangles: int):
    """Rays straight down onto a grid whose coordinates and edge functions are exact in floating point: each ray
    hits at least one triangle (watertight), and no triangle it passes outside of, where a test that misjudges the
    sign of an edge function near 0 reports a hit."""
    gap = no_gaps(out, expected, p, rays, triangles)
    if gap:
        return gap
    t = output(out, "t", (rays * triangles,), "t").reshape(rays, triangles)
    want = np.asarray(expected["t"], float).reshape(rays, triangles)
    edge = np.asarray(expected["edge"], bool).reshape(rays, triangles)
    phantom = np.isfinite(t) & np.isinf(want) & ~edge
    if phantom.any():
        i, j = np.argwhere(phantom)[0]
        return f"ray {int(i)} hits triangle {int(j)} at t = {t[i, j]:.12g}, but it passes outside that triangle"


# --- W4 ----------------------------------------------------------------------------------------------

def _hierarchy(out, expected):
    lo, hi = np.asarray(expected["box_lo"], float), np.asarray(expected["box_hi"], float)
    n = len(lo)
    nodes = np.asarray(out.get("child", np.zeros(0))).shape
    if len(nodes) != 1 or not 1 <= nodes[0] <= 2 * n - 1:
        raise ValueError(f"{nodes[0] if len(nodes) == 1 else nodes} nodes for {n} primitives "
                         f"(a hierarchy over n primitives has 1 to 2n − 1 nodes)")
    bvh = {k: np.asarray(out[k]) for k in tracescene.BVH_KEYS if k in out}
    return bvh, lo, hi


def bvh_valid(out, expected, p):
    bvh, lo, hi = _hierarchy(out, expected)
    return "; ".join(tracescene.bvh_problems(bvh, lo, hi)[:3]) or None


def bvh_root(out, expected, p):
    bvh, lo, hi = _hierarchy(out, expected)
    root_lo, root_hi = output(out, "lo", (None, 3))[0], output(out, "hi", (None, 3))[0]
    if not (np.allclose(root_lo, lo.min(axis=0)) and np.allclose(root_hi, hi.max(axis=0))):
        return "node 0 must be the root, whose box is the union of all primitives' boxes"


def bvh_shallow(out, expected, p, max_depth: int = 64):
    bvh, lo, hi = _hierarchy(out, expected)
    if tracescene.bvh_problems(bvh, lo, hi):
        return "not a valid hierarchy (see above)"
    depth = tracescene.bvh_depth(bvh)
    if depth > max_depth:
        return f"depth {depth} for {len(lo)} primitives (at most {max_depth}: split the boxes, do not peel them one by one)"


def bvh_tight(out, expected, p):
    """A good split keeps children's boxes small: the summed surface area of the nodes, against a median split's."""
    bvh, lo, hi = _hierarchy(out, expected)
    if tracescene.bvh_problems(bvh, lo, hi):
        return "not a valid hierarchy (see above)"
    e = np.asarray(bvh["hi"], float) - np.asarray(bvh["lo"], float)
    area = e[:, 0] * e[:, 1] + e[:, 1] * e[:, 2] + e[:, 2] * e[:, 0]
    leaf = bvh["child"] < 0
    got = float((area[~leaf].sum() + (area[leaf] * bvh["count"][leaf]).sum()) / max(area[0], 1e-300))
    ref = float(expected["median_cost"])
    if got > 1.5 * ref:
        return f"surface-area cost {got:.1f}, more than 1.5× a plain median split's {ref:.1f}: rays will visit many nodes"


# --- W5 ------------------------------------------------------------------------------------------

def depth_visibility(out, expected, p, rel: float = TOL.DEPTH, max_bad: float = TOL.DEPTH_BAD):
    w, h = p["size"]
    t = output(out, "t", (w * h,), "t")
    hit = np.isfinite(t)
    depth = np.where(hit, t * np.asarray(expected["cos"], float), 0.0)
    covered_any, empty_any = np.asarray(expected["covered_any"], bool), np.asarray(expected["empty_any"], bool)
    lo, hi = np.asarray(expected["lo"], float), np.asarray(expected["hi"], float)
    mismatch = (hit & ~covered_any) | (~hit & ~empty_any)
    both = hit & covered_any
    mismatch |= both & ((depth < lo * (1 - rel)) | (depth > hi * (1 + rel)))
    frac = float(mismatch.mean())
    if frac > max_bad:
        k = int(np.argmax(mismatch))
        return (f"{frac:.1%} of pixels disagree with pyrender's depth buffer (allowed {max_bad:.0%}); e.g. pixel "
                f"{k % w},{k // w}: your depth {depth[k]:.6g}, rasterised {float(expected['raster'][k]):.6g}")


def depth_normals(out, expected, p):
    w, h = p["size"]
    n = output(out, "normals", (w * h, 3), "normals")
    hit = np.isfinite(output(out, "t", (w * h,), "t"))
    length = np.linalg.norm(n[hit], axis=1)
    if hit.any() and not np.allclose(length, 1.0, atol=TOL.HITS):
        return "normals at hits must be unit vectors"


def hits_match(out, expected, params, min_same: float = TOL.SAME_PRIMITIVE, rel: float = TOL.HITS) -> Verdict:
    """The same primitive as the reference's on ≥ min_same of the rays, with t and normal close where it is."""
    want = np.asarray(expected["prim"])
    n = len(want)
    prim = output(out, "prim", (n,), "prim")
    t, normals = output(out, "t", (n,), "t"), output(out, "normals", (n, 3), "normals")
    same = prim == want
    frac = float(same.mean())
    wt = np.asarray(expected["t"], float)
    hit = same & (want >= 0)
    t_bad = int((np.abs(t[hit] - wt[hit]) > rel * np.maximum(np.abs(wt[hit]), 1.0)).sum())
    n_bad = int((np.abs(normals[hit] - np.asarray(expected["normals"])[hit]).max(axis=1) > TOL.HITS).sum()) if hit.any() else 0
    if frac < min_same:
        k = int(np.argmax(~same))
        return Verdict(0.0, f"{1 - frac:.1%} of rays hit another primitive than the reference's "
                            f"(ray {k}: yours {int(prim[k])}, expected {int(want[k])}; -1 is a miss)")
    if t_bad or n_bad:
        return Verdict(0.0, f"{t_bad} rays have t, and {n_bad} rays a normal, unlike the reference's")
    return Verdict(1.0, f"the same primitive as the reference's on {frac:.2%} of rays, t and normals close")


# --- W7, W9 -----------------------------------------------------------------------------------------

def shadow_values(out, expected, p):
    n = len(p["origins"])
    got = output(out, "transmission", (n, 3), "the transmission")
    want = np.asarray(expected["value"], float)
    err = np.abs(got - want).max(axis=1)
    if not np.isfinite(err).all() or err.max() > TOL.FLOAT64:
        i = int(np.argmax(np.where(np.isfinite(err), err, np.inf)))
        return f"segment {i}: {got[i].round(6).tolist()}, expected {want[i].round(6).tolist()}"


def shadow_counted(out, expected, p):
    got = int(output(out, "shadow", (), "the shadow counter"))
    if got != len(p["origins"]):
        return f"scene.counters['shadow'] is {got} after {len(p['origins'])} shadow rays"


def refract_mask(out, expected, p):
    tir = np.asarray(expected["tir"], bool)
    got = output(out, "tir", tir.shape, "the TIR mask").astype(bool)
    if not np.array_equal(got, tir):
        i = int(np.argmax(got != tir))
        return f"ray {i}: total internal reflection is {bool(got[i])}, expected {bool(tir[i])}"


def refract_directions(out, expected, p, atol: float = TOL.FLOAT64):
    want, tir = np.asarray(expected["t"], float), np.asarray(expected["tir"], bool)
    got = output(out, "t", want.shape, "the refracted directions")
    if tir.any() and not np.all(got[tir] == 0):
        i = int(np.flatnonzero(tir & np.any(got != 0, axis=1))[0])
        return f"ray {i} is under total internal reflection: its row is {got[i].round(9).tolist()}, not zero"
    err = np.abs(got - want).max(axis=1)
    err[tir] = 0
    if not np.isfinite(err).all() or err.max() > atol:
        i = int(np.argmax(np.where(np.isfinite(err), err, np.inf)))
        return f"ray {i}: refracted direction {got[i].round(9).tolist()}, expected {want[i].round(9).tolist()}"


# --- W11: counters are the submission's own word, so they count only beside a correct image ----------

def counter(out, expected, p, key: str, per_pixel: int | None = None, at_least_one: bool = False):
    got = int(output(out, key, (), f"the {key} counter"))
    n = p["size"][0] * p["size"][1]
    if at_least_one and got <= 0:
        return f"{key} = {got} for {n} pixels, expected some"
    if per_pixel is not None and got != per_pixel * n:
        return f"{key} = {got} for {n} pixels, expected {per_pixel * n}"


def _lens(out, p):
    n = len(np.asarray(p["directions"], float))
    return output(out, "origins", (n, 3), "origins"), output(out, "directions", (n, 3), "directions")


def lens_rays_match(out, expected, p):
    """Each lens ray's origin and direction as the handout's mapping of ``u`` gives them (handout §W12)."""
    bad = []
    for key, got in zip(("origins", "directions"), _lens(out, p)):
        err = np.abs(got - np.asarray(expected[key], float)).max(axis=1)
        bad += [f"ray {k}: {key[:-1]} {np.round(got[k], 6).tolist()}, expected "
                f"{np.round(np.asarray(expected[key], float)[k], 6).tolist()}" for k in np.flatnonzero(~(err <= TOL.FLOAT64))]
    return _few(bad)


def lens_rays_focus(out, expected, p):
    """Every ray starts on the lens disc (the plane through the eye across the view axis) and passes through the
    point where its pinhole ray meets the plane of focus, with a unit direction: what makes that plane sharp."""
    origins, directions = _lens(out, p)
    eye, center = (np.asarray(p["camera"][k], float) for k in ("eye", "center"))
    forward = (center - eye) / np.linalg.norm(center - eye)
    pinhole = np.asarray(p["directions"], float)
    sharp = eye + pinhole * (float(p["focus"]) / (pinhole @ forward))[:, None]
    lens = origins - eye
    off_disc = (np.abs(lens @ forward) > TOL.FLOAT64) | (np.linalg.norm(lens, axis=1) > float(p["aperture"]) + TOL.FLOAT64)
    miss = np.linalg.norm(np.cross(sharp - origins, directions), axis=1)   # distance of the line from the sharp point
    bad = [f"ray {k} starts at {np.round(origins[k], 6).tolist()}, off the lens disc" for k in np.flatnonzero(off_disc)]
    bad += [f"ray {k} is not a unit vector" for k in np.flatnonzero(np.abs(np.linalg.norm(directions, axis=1) - 1) > TOL.FLOAT64)]
    bad += [f"ray {k} passes {miss[k]:.3g} from its pinhole ray's point on the plane of focus"
            for k in np.flatnonzero(~(miss <= TOL.FLOAT64 * max(1.0, float(p["focus"]))))]
    return _few(bad)
