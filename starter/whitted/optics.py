"""W8, W9, W10: perfect reflection, refraction by Snell's law, and Fresnel's reflectance.

Directions are (n, 3) unit vectors pointing the way light travels; normals are (n, 3)
unit vectors facing the incoming ray (``dot(d, n) <= 0``).
"""
from __future__ import annotations

import numpy as np


def reflect(directions: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """The mirror direction of each ray (n, 3) about its normal."""
    # TODO W8: r = d − 2 (d·n) n (handout §W8)
    raise NotImplementedError("W8: r = d − 2 (d·n) n (handout §W8)")


def refract(directions: np.ndarray, normals: np.ndarray, eta) -> tuple[np.ndarray, np.ndarray]:
    """Refracted directions and a mask of total internal reflection: ``(t (n, 3), tir (n,) bool)``.

    ``eta`` (a number or (n,)) is n₁/n₂, the index on the incoming side over the index on the
    far side. Where ``tir`` is true there is no refracted ray and that row of ``t`` is zero.
    """
    # TODO W9: Snell's law in vector form; TIR where sin²θt > 1 (handout §W9)
    raise NotImplementedError("W9: Snell's law in vector form; TIR where sin²θt > 1 (handout §W9)")


def fresnel(cos_i, eta) -> np.ndarray:
    """Fresnel's reflectance for unpolarised light, (n,): the mean of the s and p reflectances.

    ``cos_i`` (n,) is the cosine of the angle of incidence (≥ 0), ``eta`` (number or (n,)) is
    n₁/n₂ as in :func:`refract`. Total internal reflection gives 1.
    """
    # TODO W10: r_s and r_p from cosθi and cosθt, then their squares' mean (handout §W10)
    raise NotImplementedError("W10: r_s and r_p from cosθi and cosθt, then their squares' mean (handout §W10)")
