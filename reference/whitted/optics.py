"""W8, W9, W10: perfect reflection, refraction by Snell's law, and Fresnel's reflectance.

Directions are (n, 3) unit vectors pointing the way light travels; normals are (n, 3)
unit vectors facing the incoming ray (``dot(d, n) <= 0``).
"""
from __future__ import annotations

import numpy as np


def reflect(directions: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """The mirror direction of each ray (n, 3) about its normal."""
    # BEGIN SOLUTION W8: r = d − 2 (d·n) n (handout §W8)
    d = np.asarray(directions, dtype=np.float64)
    n = np.asarray(normals, dtype=np.float64)
    return d - 2.0 * np.einsum("ij,ij->i", d, n)[:, None] * n
    # END SOLUTION


def refract(directions: np.ndarray, normals: np.ndarray, eta) -> tuple[np.ndarray, np.ndarray]:
    """Refracted directions and a mask of total internal reflection: ``(t (n, 3), tir (n,) bool)``.

    ``eta`` (a number or (n,)) is n₁/n₂, the index on the incoming side over the index on the
    far side. Where ``tir`` is true there is no refracted ray and that row of ``t`` is zero.
    """
    # BEGIN SOLUTION W9: Snell's law in vector form; TIR where sin²θt > 1 (handout §W9)
    d = np.asarray(directions, dtype=np.float64)
    n = np.asarray(normals, dtype=np.float64)
    eta = np.broadcast_to(np.asarray(eta, dtype=np.float64), (len(d),))
    cos_i = -np.einsum("ij,ij->i", d, n)
    sin2_t = eta * eta * np.maximum(0.0, 1.0 - cos_i * cos_i)
    tir = sin2_t > 1.0
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - sin2_t))
    t = eta[:, None] * d + (eta * cos_i - cos_t)[:, None] * n
    t[tir] = 0.0
    return t, tir
    # END SOLUTION


def fresnel(cos_i, eta) -> np.ndarray:
    """Fresnel's reflectance for unpolarised light, (n,): the mean of the s and p reflectances.

    ``cos_i`` (n,) is the cosine of the angle of incidence (≥ 0), ``eta`` (number or (n,)) is
    n₁/n₂ as in :func:`refract`. Total internal reflection gives 1.
    """
    # BEGIN SOLUTION W10: r_s and r_p from cosθi and cosθt, then their squares' mean (handout §W10)
    cos_i = np.clip(np.asarray(cos_i, dtype=np.float64), 0.0, 1.0)
    eta = np.broadcast_to(np.asarray(eta, dtype=np.float64), cos_i.shape)
    sin2_t = eta * eta * (1.0 - cos_i * cos_i)
    tir = sin2_t >= 1.0
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - sin2_t))
    with np.errstate(divide="ignore", invalid="ignore"):
        rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
        rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    return np.where(tir, 1.0, np.nan_to_num(0.5 * (rs * rs + rp * rp), nan=1.0))
    # END SOLUTION
