"""Stage 3's closed forms (autograder/hemicube/truth.py) against each other and against integration.

The exact form factor between two patches is the area average over the first of the
point-to-polygon form factor to the second, so Gauss quadrature of Lambert's contour
integral is an independent check of Howell's C-11 and C-14, and a many-sided polygon
one of the coaxial disk. Numbers quoted in the issue are pinned to their printed digits.
"""
from __future__ import annotations

import numpy as np
import pytest

from autograder.hemicube import truth


def area_average(shooter: np.ndarray, receiver: np.ndarray, k: int = 24) -> float:
    """F from a planar quad to a polygon: Gauss-Legendre over the shooter of the contour formula."""
    x, w = np.polynomial.legendre.leggauss(k)
    s, ws = 0.5 * (x + 1), 0.5 * w
    a, b, c, d = shooter
    normal = np.cross(b - a, d - a)
    normal /= np.linalg.norm(normal)
    total = area = 0.0
    for si, wi in zip(s, ws):
        for tj, wj in zip(s, ws):
            p = (1 - si) * (1 - tj) * a + si * (1 - tj) * b + si * tj * c + (1 - si) * tj * d
            jac = np.linalg.norm(np.cross((1 - tj) * (b - a) + tj * (c - d), (1 - si) * (d - a) + si * (c - b)))
            total += wi * wj * jac * truth.contour(p, normal, receiver)
            area += wi * wj * jac
    return total / area


def test01_issue_numbers():
    assert round(truth.howell_c11(1, 1, 1), 5) == 0.19982
    assert round(truth.howell_c14(1, 1, 1), 5) == 0.20004


@pytest.mark.parametrize("a,b,c", [(1, 1, 1), (2, 0.5, 1), (0.3, 0.3, 2), (1, 3, 0.5)])
def test02_c11_is_the_area_average_of_the_contour_integral(a, b, c):
    shooter = np.array([[0, 0, 0], [a, 0, 0], [a, b, 0], [0, b, 0]], float)
    receiver = np.array([[0, 0, c], [0, b, c], [a, b, c], [a, 0, c]], float)
    assert area_average(shooter, receiver) == pytest.approx(truth.howell_c11(a, b, c), rel=1e-4)


@pytest.mark.parametrize("l,w,h", [(1, 1, 1), (1, 0.5, 2), (2, 1, 0.3)])
def test03_c14_is_the_area_average_of_the_contour_integral(l, w, h):
    floor = np.array([[0, 0, 0], [w, 0, 0], [w, l, 0], [0, l, 0]], float)     # w along x, the common edge along y
    wall = np.array([[0, 0, 0], [0, l, 0], [0, l, h], [0, 0, h]], float)
    # the integrand is singular along the common edge: a fine rule, and a looser tolerance
    assert area_average(floor, wall, k=48) == pytest.approx(truth.howell_c14(l, w, h), rel=2e-3)


def test04_c14_reciprocity():
    l, w, h = 1.0, 0.5, 2.0
    assert l * w * truth.howell_c14(l, w, h) == pytest.approx(l * h * truth.howell_c14(l, h, w), rel=1e-12)


@pytest.mark.parametrize("radius,height", [(1, 1), (3, 0.7), (0.2, 5)])
def test05_disk_is_the_limit_of_inscribed_polygons(radius, height):
    exact = truth.disk(radius, height)
    coarse, fine = truth.polygon_disk(radius, height, 64), truth.polygon_disk(radius, height, 4096)
    assert coarse < fine < exact
    assert fine == pytest.approx(exact, rel=1e-5)


def test06_contour_is_orientation_free_and_ignores_repeated_corners():
    tri = [[0.2, -0.3, 1.5], [-0.4, 0.5, 0.8], [0.6, 0.9, 2.0]]
    f = truth.contour([0, 0, 0], [0, 0, 1], tri)
    assert f == pytest.approx(truth.contour([0, 0, 0], [0, 0, 1], tri[::-1]))
    assert f == pytest.approx(truth.contour([0, 0, 0], [0, 0, 1], tri + [tri[-1]]))


@pytest.mark.parametrize("r", [2, 8, 32])
def test07_exact_cells_cover_the_hemisphere(r):
    top = sum(truth.exact_cell_top(r, i, j) for i in range(r) for j in range(r))
    side = sum(truth.exact_cell_side(r, i, j) for i in range(r) for j in range(r // 2))
    assert top + 4 * side == pytest.approx(1.0, abs=1e-12)


def test08_delta_form_factors_approach_the_exact_cells():
    errors = []
    for r in (8, 16, 32):
        exact_top = np.array([[truth.exact_cell_top(r, i, j) for i in range(r)] for j in range(r)])
        exact_side = np.array([[truth.exact_cell_side(r, i, j) for i in range(r)] for j in range(r // 2)])
        errors.append(max(np.abs(truth.delta_top(r) / exact_top - 1).max(), np.abs(truth.delta_side(r) / exact_side - 1).max()))
    # the midpoint rule: relative error falls as 1/r²
    assert errors[1] < errors[0] / 3.5 and errors[2] < errors[1] / 3.5
    assert errors[2] < 3e-3


def test_the_inscribed_polygons_form_factor_approaches_the_disks_closed_form():
    """The truth of the disk configurations (quadrature of the contour formula over inscribed polygons) meets
    Howell's disk-to-disk closed form as the polygons get more sides, from below, by about the area they miss."""
    for r1, r2 in ((1.0, 1.0), (0.5, 2.0)):
        disk = truth.disk_to_disk(r1, r2, 1.0)
        errors = []
        for sides in (16, 64):
            quads = truth.coaxial_disks(r1, r2, 1.0, sides)
            errors.append(truth.polygons_form_factor(quads[:sides], truth.regular_polygon(r2, 1.0, sides), k=3) / disk - 1)
        assert errors[0] < errors[1] < 0 and abs(errors[1]) < 1.5e-3 and abs(errors[0]) > 3 * abs(errors[1])

