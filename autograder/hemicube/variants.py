"""Stage 3's fresh cases: each public test's case with new numbers of the same kind. Not shipped to students.

Graded instead of the shipped cases wherever the kit grades with its hidden tests (see
``autograder/sphere/variants.py``). Each keeps its case's purpose: a hemicube turned about its
normal stays turned (by another angle), a back face stays a back face, patches no cell sees stay
unseen, a repeated corner stays repeated, a closed box stays closed. Scenes are stretched along
their axes rather than only moved, so that no answer of a shipped case is the answer of a fresh one.
"""
from __future__ import annotations

import numpy as np

from cs451.grading.spec import Case

from autograder.fresh import Similarity, num, rotation, rotation_about
from autograder.hemicube import truth as truths


#: H5 sums the hemicube's own cells, so its closed-form tests pass only where the hemicube's aliasing stays inside
#: their tolerance, which depends on the exact geometry: the fresh cases come from these, each measured with the
#: reference's hemicube at resolution 128 (as the tests run) to be no farther from its closed form than the shipped
#: case is (1.4% of the 3% allowed for the small squares; 0.1% of the 0.2% for the disk), and checked again by
#: tests/test_attacks_round3_replay.py. (side, distance) of the small opposed squares, rotated hemicube:
SMALL_SQUARES = (
    (0.16, 0.9), (0.16, 1.0), (0.17, 1.05), (0.18, 0.9), (0.18, 1.0), (0.18, 1.1), (0.18, 1.15), (0.19, 0.9),
    (0.19, 0.95), (0.19, 1.0), (0.19, 1.05), (0.19, 1.15), (0.2, 0.95), (0.2, 1.05), (0.2, 1.15), (0.21, 0.95),
    (0.21, 1.0), (0.21, 1.05), (0.21, 1.1), (0.21, 1.15), (0.22, 0.95), (0.22, 1.1), (0.23, 0.9), (0.23, 1.0),
    (0.23, 1.15), (0.24, 1.05), (0.25, 1.1),
)
#: (radius, height) of the 256-gon over the point:
DISKS = (
    (0.8, 0.85), (0.8, 0.9), (0.8, 0.95), (0.8, 1.0), (0.8, 1.05), (0.8, 1.1), (0.85, 0.85), (0.85, 0.9),
    (0.85, 1.0), (0.85, 1.15), (0.9, 0.85), (0.9, 0.9), (0.9, 0.95), (0.9, 1.0), (0.9, 1.05), (0.9, 1.1),
    (0.9, 1.15), (0.95, 0.85), (0.95, 0.9), (0.95, 0.95), (0.95, 1.0), (0.95, 1.05), (0.95, 1.1), (0.95, 1.15),
    (1.0, 0.85), (1.0, 0.9), (1.0, 0.95), (1.0, 1.05), (1.0, 1.1), (1.0, 1.15), (1.05, 0.85), (1.05, 0.9),
    (1.05, 0.95), (1.05, 1.0), (1.05, 1.05), (1.05, 1.1), (1.05, 1.15), (1.1, 0.85), (1.1, 0.9), (1.1, 0.95),
    (1.1, 1.0), (1.1, 1.05), (1.1, 1.1), (1.1, 1.15), (1.15, 0.85), (1.15, 0.9), (1.15, 0.95), (1.15, 1.0),
    (1.15, 1.05), (1.15, 1.1), (1.15, 1.15), (1.2, 0.85), (1.2, 0.9), (1.2, 0.95), (1.2, 1.0), (1.2, 1.05),
    (1.2, 1.1), (1.2, 1.15),
)


def tables(p: dict, rng: np.random.Generator) -> Case:
    """Another even resolution of the same size class."""
    r = p["resolution"]
    choices = [c for c in ((6, 10, 12, 14) if r <= 16 else (48, 56, 72, 80)) if c != r]
    res = int(rng.choice(choices))
    return Case({"resolution": res}, f"resolution {res}")


def tetrahedron(p: dict, rng: np.random.Generator) -> Case:
    """Another resolution of the same size class, odd ones included (a face has no halves)."""
    r = p["resolution"]
    res = int(rng.choice([c for c in ((5, 7, 9, 10, 12) if r <= 16 else (45, 50, 63, 80)) if c != r]))
    return Case({"resolution": res}, f"resolution {res}")


def views(p: dict, rng: np.random.Generator) -> Case:
    """The patch moved; the same normal; an up vector along an axis stays so, a turned one turns by another angle."""
    center = np.asarray(p["center"], float)
    center = np.round(center + rng.uniform(-1, 1, 3) * max(1.0, 0.1 * float(np.abs(center).max())), 4).tolist()
    up = np.asarray(p["up"], float)
    if np.count_nonzero(np.abs(up) > 1e-12) > 1:
        turned = rotation_about(p["normal"], np.radians(rng.uniform(10, 80)))
        up = np.round(turned @ up, 12)
    up = up.tolist()
    return Case({"center": center, "normal": p["normal"], "up": up}, f"center {center}, normal {p['normal']}, up {up}")


def projections(p: dict, rng: np.random.Generator) -> Case:
    near, far = num(rng.uniform(0.005, 0.5), 5), num(rng.uniform(20, 500), 3)
    return Case({"near": near, "far": far}, f"near {near:g}, far {far:g}")


def _stretched(quads: list, rng: np.random.Generator) -> tuple[list, list]:
    """The quads stretched along each axis by its own factor and moved: planar quads stay planar, facing stays."""
    factors = rng.uniform(0.75, 1.3, 3)
    moved = np.asarray(quads, float) * factors + rng.uniform(-0.3, 0.3, 3) * np.abs(np.asarray(quads)).max()
    return np.round(moved, 6).tolist(), np.round(factors, 3).tolist()


def item_buffer(p: dict, rng: np.random.Generator) -> Case:
    """The same scene stretched along its axes, from the same patch, at another resolution of the same class."""
    quads, factors = _stretched(p["quads"], rng)
    res = int(rng.choice([48, 56, 72] if p["resolution"] <= 64 else [96, 112, 120]))
    return Case({**p, "quads": quads, "resolution": res},
                f"the scene stretched by {factors} along x, y, z, from patch {p['patch']}, resolution {res}")


def row_from_items(p: dict, rng: np.random.Generator, unseen: bool) -> Case:
    """Other random item buffers: a few patches at a middle resolution, or many at resolution 4 with the last
    ones in no cell."""
    from autograder.hemicube.public import random_items
    seed = int(rng.integers(1 << 30))
    if unseen:
        n, hidden = int(rng.integers(40, 81)), int(rng.integers(5, 16))
        params, shown = random_items(4, n, seed, hidden), f"resolution 4, {n} patches, the last {hidden} never seen"
    else:
        r, n = int(rng.choice([12, 14, 18, 20])), int(rng.integers(5, 13))
        params, shown = random_items(r, n, seed), f"resolution {r}, {n} patches"
    return Case(params, f"random item buffers at {shown} (seed {seed})")


def known_row(p: dict, rng: np.random.Generator, kind: str, task: str, rtol: float) -> Case:
    """The same configuration with other sizes, against its closed form at those sizes."""
    from autograder.hemicube.public import known_row_test
    if kind == "c11":
        if task == "H5":
            size, distance = SMALL_SQUARES[int(rng.integers(len(SMALL_SQUARES)))]
        else:
            size, distance = num(p["quads"][0][1][0] * rng.uniform(0.8, 1.25)), num(rng.uniform(0.85, 1.2))
        quads, want = truths.opposed_squares(size, distance), truths.howell_c11(size, size, distance)
        shown = f"squares of side {size:g}, {distance:g} apart (Howell C-11, F = {want:.5f})"
        entries = [[1]]
    elif kind == "c14":
        size, height = num(rng.uniform(0.8, 1.25)), num(rng.uniform(0.8, 1.25))
        quads, want = truths.perpendicular_squares(size, height), truths.howell_c14(size, size, height)
        shown = f"a {size:g} square and a {size:g} × {height:g} rectangle at right angles (Howell C-14, F = {want:.5f})"
        entries = [[1]]
    else:
        radius, height = DISKS[int(rng.integers(len(DISKS)))]
        sides = len(p["quads"]) - 1
        quads = truths.small_patch_under_disk(0.01, radius, height, sides)
        want = truths.polygon_disk(radius, height, sides)
        shown = f"a point under a coaxial {sides}-gon of radius {radius:g} at height {height:g} (F = {want:.5f})"
        entries = [list(range(1, sides + 1))]
    # H6 fixes the trusted hemicube row of two opposed squares: from an unrotated hemicube, whose cell edges line up
    # with the squares' edges at some sizes, that row aliases, and the reference's own fix lands 2.2-2.6% off the
    # closed form on 10 of 80 fresh cases (0.2% allowed); from rotated hemicubes all 80 are within 0.011%.
    rotate = True if (kind, task) == ("c11", "H6") else p["rotate"]
    test = known_row_test("fresh", task, 1, quads, p["rows"][0], entries, [want], rtol, resolution=p["resolution"],
                          rotate=rotate)
    return Case(test.params, shown, test.check)


def closure(p: dict, rng: np.random.Generator) -> Case:
    """A closed box of other proportions, turned: every row still sums to 1."""
    box = np.asarray(p["quads"], float) * rng.uniform(0.6, 1.6, 3)
    box = box @ rotation(rng).T
    return Case({**p, "quads": np.round(box, 9).tolist()},
                f"a closed box of {len(p['quads']) // 6} patches a face, stretched and turned")


def contour(p: dict, rng: np.random.Generator) -> Case:
    """Another polygon above the point (a square of another size and height, or another triangle with its corner
    repeated), seen from a point moved in the plane, the whole turned and moved."""
    polygon = np.asarray(p["polygon"], float)
    repeated = bool(np.allclose(polygon[-1], polygon[-2]))
    if repeated:
        tri = np.c_[rng.uniform(-1, 1, (3, 2)), rng.uniform(0.6, 1.8, 3)]
        shipped = np.cross(polygon[1] - polygon[0], polygon[2] - polygon[0])[2]
        if np.sign(np.cross(tri[1] - tri[0], tri[2] - tri[0])[2]) != np.sign(shipped):   # wound as the shipped one
            tri = tri[::-1]
        polygon = np.r_[tri, tri[-1:]]
        what = "a triangle stored as a quad (repeated corner)"
    else:
        size, height = rng.uniform(0.6, 1.5), rng.uniform(0.6, 1.6)
        polygon = np.asarray(truths.square(0, 0, height, size, False), float)
        what = f"a square of side {size:.3g} at height {height:.3g}"
    point = np.r_[rng.uniform(-0.3, 0.9, 2), 0.0]
    move = Similarity(rng)
    return Case({"point": move.point(point), "normal": move.vector(p["normal"]),
                 "polygon": [move.point(v) for v in polygon]},
                f"{what}, above the point ({point[0]:.3g}, {point[1]:.3g}, 0), the whole turned and moved")
