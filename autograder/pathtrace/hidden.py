"""Stage 5 hidden tests: other normals, another blocker, other weights, and a Cornell box in other colours. Not
shipped to students; each has a public test of the same form."""
from __future__ import annotations

import copy

import numpy as np

from autograder.pathtrace.public import (CORNELL, cosine_test, direct_test, open_scene, radiosity_test,
                                         roulette_test)

_rng = np.random.default_rng(105)


def _recoloured() -> dict:
    """The Cornell box with its walls in other colours and a whiter, dimmer light: radiosity solves it again."""
    scene = copy.deepcopy(CORNELL)
    scene["materials"]["red"]["diffuse"] = [0.1, 0.2, 0.6]
    scene["materials"]["green"]["diffuse"] = [0.6, 0.5, 0.1]
    scene["materials"]["white"]["diffuse"] = [0.6, 0.6, 0.6]
    scene["lights"][0]["radiance"] = [10, 10, 10]
    return scene


def _tilted_blocker() -> dict:
    scene = open_scene()
    scene["objects"][1]["vertices"] = [[-0.5, 0.4, 0.1], [-0.5, 0.6, 0.6], [0.1, 0.6, 0.6], [0.1, 0.4, 0.1]]
    return scene


_n = _rng.normal(size=(4, 3))
_points = np.c_[_rng.uniform(-0.9, 0.9, 30), np.zeros(30), _rng.uniform(-0.9, 0.9, 30)].round(4).tolist()
_beta = np.r_[_rng.uniform(0, 3, (20, 3)), np.zeros((1, 3)), [[0.999999, 0, 0]]].round(6)

TESTS = [
    cosine_test("P1 cosine_sample: cos θ/π about four random normals", 5,
                (_n / np.linalg.norm(_n, axis=1, keepdims=True)).tolist(), 20_000, 101),
    direct_test("P2 direct_light: each sample by its formula, behind a tilted blocker", 5, _tilted_blocker(), _points,
                [[0, 1, 0]] * 30, _rng.uniform(0.1, 0.9, (30, 3)).round(3).tolist(), 102),
    roulette_test("P3 roulette: weights above 1 go on unchanged, zero ends", 5, _beta.tolist(),
                  _rng.random(len(_beta)).round(6).tolist()),
    radiosity_test("P4 radiance: a Cornell box in other colours, against radiosity", 10, _recoloured(), 8000, 103),
]
