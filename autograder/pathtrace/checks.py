"""Stage 5's checks: the arrays a submission returned against the truth, exactly where a sample has one value and
statistically where only its mean does. Shipped to students: nothing here computes an answer."""
from __future__ import annotations

import functools
import math
from statistics import NormalDist
from typing import Callable

import numpy as np

from cs451.grading.checks import output
from cs451.grading.spec import Verdict
from cs451.stages.pathtrace import tolerances as TOL

#: the standard normal's quantile each statistical test allows (two-sided, TOL.SIGMAS)
Z = NormalDist().inv_cdf(1.0 - TOL.SIGMAS / 2.0)


def judged(passed: str) -> Callable[[Callable[..., str | None]], Callable[..., Verdict]]:
    """A check written as "the problem, or None" made a Verdict: full marks with ``passed``, else none with the problem."""
    def wrap(fn: Callable[..., str | None]) -> Callable[..., Verdict]:
        @functools.wraps(fn)
        def check(out, expected, p, **kwargs) -> Verdict:
            problem = fn(out, expected, p, **kwargs)
            return Verdict(0.0, problem) if problem else Verdict(1.0, passed)
        return check
    return wrap


def _frame(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Any two unit vectors that make a right-handed frame with the unit normal n (where φ is measured from)."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    t1 = np.cross(n, helper)
    t1 /= np.linalg.norm(t1)
    return t1, np.cross(n, t1)


def chi_square_z(counts: np.ndarray) -> float:
    """How many standard errors above its mean a uniform histogram's χ² is (Wilson-Hilferty's normal form)."""
    k = counts.size - 1
    expected = counts.sum() / counts.size
    chi2 = float(((counts - expected) ** 2 / expected).sum())
    return ((chi2 / k) ** (1 / 3) - (1 - 2 / (9 * k))) / math.sqrt(2 / (9 * k))


@judged("unit directions about their normals, the same for the same u")
def directions_unit(out, expected, p):
    n = np.repeat(np.asarray(p["normals"], float), p["samples"], axis=0)
    d = output(out, "directions", n.shape, "the directions")
    length = np.linalg.norm(d, axis=1)
    if not np.allclose(length, 1.0, atol=TOL.UNIT):
        k = int(np.argmax(np.abs(length - 1)))
        return f"direction {k} has length {length[k]:.9g}: directions must be unit vectors"
    below = np.einsum("ij,ij->i", d, n) < -TOL.UNIT
    if below.any():
        k = int(np.argmax(below))
        return f"direction {k} points below its surface (d·n = {float(d[k] @ n[k]):.3g}): it must lie about the normal"
    if not bool(np.asarray(out.get("repeatable", True))):
        return "the same normals and u gave other directions: draw no random numbers of your own, use u"


@judged("cos²θ and φ uniform about every normal: the density is cos θ/π")
def cosine_distributed(out, expected, p, bins: int = 8):
    """Per normal, cos²θ and φ (about any fixed frame of the normal) are uniform for a cos θ/π density: a χ² test
    over bins × bins cells of the pair, at TOL.SIGMAS."""
    n = np.repeat(np.asarray(p["normals"], float), p["samples"], axis=0)
    d = output(out, "directions", n.shape, "the directions")
    for normal in np.unique(n, axis=0):
        mine = np.all(n == normal, axis=1)
        t1, t2 = _frame(normal / np.linalg.norm(normal))
        cos = np.clip(d[mine] @ normal, 0, 1)
        phi = np.mod(np.arctan2(d[mine] @ t2, d[mine] @ t1), 2 * np.pi)
        counts, _, _ = np.histogram2d(cos ** 2, phi, bins=bins, range=[[0, 1], [0, 2 * np.pi]])
        z = chi_square_z(counts)
        if z > Z:
            mean_cos = float(cos.mean())
            return (f"about the normal {np.round(normal, 3).tolist()}, the directions are not cos θ/π distributed "
                    f"(χ² {z:.1f} standard errors high; mean cos θ {mean_cos:.3f}, expected 2/3)")


@judged("every sample as its formula gives it")
def samples_match(out, expected, p):
    """Each sample's value as its formula gives it for the same random numbers."""
    return _differs(out, expected)


def _differs(out, expected, key: str = "radiance") -> str | None:
    want = np.asarray(expected[key], float)
    got = output(out, key, want.shape, f"the {key}")
    bad = ~np.isclose(got, want, rtol=TOL.FLOAT64, atol=TOL.FLOAT64_ATOL)
    if bad.any():
        k = int(np.argwhere(bad)[0][0])
        return f"sample {k}: {np.round(got[k], 9).tolist()}, expected {np.round(want[k], 9).tolist()}"


@judged("the samples' mean is the direct light within its statistical error")
def mean_matches(out, expected, p, samples: int):
    """Per point, the mean of its samples within Z standard errors of the closed form."""
    want = np.asarray(expected["radiance"], float)
    got = output(out, "radiance", (len(want) * samples, 3), "the radiance").reshape(len(want), samples, 3)
    mean, error = got.mean(axis=1), got.std(axis=1, ddof=1) / math.sqrt(samples)
    off = np.abs(mean - want) > Z * error + TOL.FLOAT64_ATOL
    if off.any():
        k = int(np.argwhere(off)[0][0])
        return (f"point {k}: the mean of {samples} samples is {np.round(mean[k], 5).tolist()} ± "
                f"{np.round(error[k], 5).tolist()}, but the light it reflects is {np.round(want[k], 5).tolist()}")


@judged("a shadow ray exactly where the surface and the light face each other")
def shadow_rays_where_lit(out, expected, p):
    want = int(expected["lit"])
    got = int(output(out, "shadow", (), "the shadow counter"))
    if got != want:
        return f"{got} shadow rays, expected {want}: one where the surface and the light face each other, none elsewhere"


@judged("alive and the weights exactly as the rule gives them")
def roulette_matches(out, expected, p):
    alive = np.asarray(expected["alive"], bool)
    got = output(out, "alive", alive.shape, "alive").astype(bool)
    if not np.array_equal(got, alive):
        k = int(np.argmax(got != alive))
        return f"path {k} (β {np.round(p['weights'][k], 4).tolist()}, u {p['u'][k]:.4f}): alive {bool(got[k])}, expected {bool(alive[k])}"
    return _differs(out, expected, key="weights")


def like_radiosity(out, expected, p) -> Verdict:
    """Per surface and channel, the mean radiance within Z standard errors of stage 4's, plus radiosity's own
    discretisation error (TOL.RADIOSITY_BIAS)."""
    want = np.asarray(expected["radiance"], float)
    mean = output(out, "mean", want.shape, "the mean radiance")
    error = output(out, "error", want.shape, "its standard error")
    bounces = int(output(out, "bounce", (), "the bounce counter"))
    paths = len(p["polygons"]) * int(p["samples"])
    ceiling = TOL.PATH_SPREAD * want.max(axis=1, keepdims=True)
    if not np.all(np.abs(error) <= ceiling):
        k = int(np.argwhere(~(np.abs(error) <= ceiling))[0][0])
        return Verdict(0.0, f"surface {p['polygons'][k]}: radiance {np.round(mean[k], 4).tolist()} ± "
                            f"{np.round(error[k], 4).tolist()}: the paths spread far more than a correct path tracer's "
                            f"(a standard error above {TOL.PATH_SPREAD:.0%} of radiosity's "
                            f"{np.round(want[k], 4).tolist()}); does a path's weight β shrink at each bounce?")
    if bounces < int(p["samples"]):
        return Verdict(0.0, f"scene.counters['bounce'] is {bounces} for {paths} paths aimed at surfaces (add every "
                            f"ray cast from a bounce)")
    allowed = Z * np.abs(error) + TOL.RADIOSITY_BIAS * want
    off = np.abs(mean - want) > allowed
    worst = float(np.max(np.abs(mean - want) / np.maximum(want, 1e-300)))
    if off.any():
        k = int(np.argwhere(off)[0][0])
        return Verdict(0.0, f"surface {p['polygons'][k]}: radiance {np.round(mean[k], 4).tolist()} ± "
                            f"{np.round(error[k], 4).tolist()}, radiosity's {np.round(want[k], 4).tolist()}")
    return Verdict(1.0, f"every surface within its allowance of radiosity (largest difference {worst:.1%})")


@judged("every path brings some light")
def lone_paths_lit(out, expected, p):
    """Under the light with nothing in between, every path's first bounce sees the light (P2 is positive)."""
    k = len(p["origins"])
    radiance = output(out, "radiance", (k, 3), "the radiance")
    dark = np.flatnonzero(~np.all(np.isfinite(radiance) & (radiance > 0), axis=1))
    if len(dark):
        return (f"ray {int(dark[0])}, traced alone, brings {np.round(radiance[dark[0]], 6).tolist()}: a path onto a lit "
                f"floor adds the direct light at its first bounce, even when it is the only path")
    camera, bounce = int(output(out, "camera", (), "the camera counter")), int(output(out, "bounce", (), "the bounce counter"))
    if camera != k or bounce < k:
        return f"counters camera {camera} and bounce {bounce} for {k} paths that each bounce at least once"


@judged("the roulette ends as many paths as it should")
def roulette_thins(out, expected, p):
    """With the roulette from bounce 1 and at most 2 bounces, a path goes on after bounce 1 with probability at most
    a (the largest albedo), and after bounce 2 at most a again: at most a·n + a²·n bounce rays on average."""
    scene = p["scene"]
    a = max(max(m["diffuse"]) for m in scene["materials"].values())
    n = len(p["polygons"]) * int(p["samples"])
    bound = (a + a * a + TOL.ROULETTE_SLACK) * n
    bounces = int(output(out, "bounce", (), "the bounce counter"))
    mean = output(out, "mean", (len(p["polygons"]), 3), "the mean radiance")
    if bounces < 1 or not np.isfinite(mean).all() or not mean.sum() > 0:
        return (f"{bounces} bounce rays and a total mean radiance of {float(np.nansum(mean)):.3g}: paths in a lit box "
                f"bring light, and some go on after bounce 1")
    if bounces > bound:
        return (f"{bounces} bounce rays for {n} paths in a box of albedo at most {a:g}, with the roulette from bounce "
                f"{p['roulette_depth']}: at most {bound:.0f} expected (play the roulette from bounce "
                f"scene.roulette_depth on; the first surface a camera ray meets is bounce 1)")


@judged("L_e on the light's front, 0 elsewhere")
def rays_match(out, expected, p):
    camera = int(output(out, "camera", (), "the camera counter"))
    if camera != len(p["origins"]):
        return f"scene.counters['camera'] is {camera} for {len(p['origins'])} rays (add the rays radiance() is given)"
    return _differs(out, expected)
