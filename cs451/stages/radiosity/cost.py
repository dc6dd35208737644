"""What a radiosity render costs, estimated from the scene's options alone before any work (``Stage.estimate``):
the patches R1's rule makes, their form factors, and the hemicubes drawn at a time (see :mod:`cs451.limits`)."""
from __future__ import annotations

import numpy as np

from ...limits import Cost
from ...patches import scene_polygons
from ...scene import Scene
from .reciprocity import MATRICES

#: bytes per patch beyond its row of form factors: geometry, solver state, vertices (with margin)
PATCH_BYTES = 4096


def patch_count(scene: Scene, patch_size: float) -> float:
    """How many patches R1's rule (handout §R1: ⌈longest opposite edge / max_edge⌉ each way) makes of the scene."""
    quads, _, _ = scene_polygons(scene)
    if patch_size <= 0:
        return float(len(quads))
    edge = lambda a, b: np.linalg.norm(quads[:, a] - quads[:, b], axis=1)
    nu = np.maximum(1, np.ceil(np.maximum(edge(1, 0), edge(2, 3)) / patch_size))
    nv = np.maximum(1, np.ceil(np.maximum(edge(3, 0), edge(2, 1)) / patch_size))
    return float((nu * nv).sum())


def estimate(scene: Scene, size: tuple[int, int] | None = None) -> list:
    """The memory a render needs, from the options alone: the patches R1's rule makes with their n × n form factors
    (more matrices with reciprocity), and the hemicubes drawn at a time."""
    from ..hemicube import hemicube_bytes              # the stage it builds on, when an estimate is asked for
    from .. import get_stage                            # the registry: this package's interface imports this module
    opts = get_stage("radiosity").options(scene)
    n = patch_count(scene, opts.patch_size)
    batch = 1 if opts.solver == "progressive" and not opts.reciprocity else 256
    matrices = 1 + MATRICES if opts.reciprocity else 1       # the engine's rows, and the correction's arrays
    return [Cost("options.radiosity.patch_size", 8.0 * matrices * n * n + PATCH_BYTES * n,
                 f"{n:,.0f} patches and their form factors (patch_size {opts.patch_size:g}"
                 f"{', reciprocity: ' + str(matrices) + ' matrices' if opts.reciprocity else ''})"),
            Cost("options.radiosity.resolution", hemicube_bytes(opts.resolution, batch),
                 f"{batch} hemicube(s) of resolution {opts.resolution} at a time")]
