"""The form-factor engine (hemicubes on the rasteriser, and Monte Carlo ray casting); relied on by stage 3's grader, render and bench and by stage 4 (radiosity).

``HemicubeFormFactors(quads, calls)`` computes rows F_i· of the form-factor
matrix of planar patches (``cs451.patches``: (n, 4, 3) quads, counter-clockwise
seen from the front) with the hemicube of Cohen & Greenberg (1985). It holds no
solution: the delta form-factor tables, the five views, the projections, the
item-buffer shaders, the row sum and the point-to-polygon form factor all come
from ``calls``, a stage-3 implementation's answers (the reference's or a student's,
checked: ``cs451.stages.hemicube.calls(impl)``); the engine imports no stage.

How it is fast: the scene's triangles go to the GPU once; every hemicube face
of a batch of patches is one *instance* of a single instanced draw, placed into
its tile of one R32UI atlas (clip distances keep it inside the tile), so a batch
of hundreds of hemicubes costs one draw call and one read-back; each tile is
summed with ``np.bincount`` (the student's H5). Rows are computed only when asked
and cached; only geometry enters, so changing colours, albedos or emission
reuses every row. Patches behind or in a shooter's plane are counted as culled
(the clipper discards them); a patch seen from behind hides what is behind it and
receives nothing (H4).

Proximity: the hemicube treats the shooter as a point at its centre, an error
no resolution fixes when another patch is close to it. With ``proximity="contour"``
the form factor to every close patch j is replaced by the area average over the
shooter (Gauss points) of the exact point-to-polygon form factor (H6, Lambert's
contour formula) times the fraction of j visible from each point: the hemicube's
where nothing can stand between, else by sight lines (:mod:`.visibility`). With
``shooter_split=k`` each row averages k × k hemicubes spread over the shooter.

One module a job: :mod:`.calls` (what the engine asks of a stage-3 implementation),
:mod:`.geometry` (where hemicubes stand), :mod:`.atlas` (the instanced draw and read-back), :mod:`.grids`
(a polygon's patches drawn as one quad, for the trusted engine on a CPU rasteriser),
:mod:`.rows` (rows, caching, the proximity fix, checks), :mod:`.pictures` (for people),
:mod:`.raycast` (Monte Carlo on Embree, for comparison), :mod:`.reciprocity` (computed rows made
reciprocal, A_i F_ij = A_j F_ji, each row keeping its sum: stage 4's ``reciprocity`` option).
"""
from __future__ import annotations

from .atlas import FRAGMENT_INTERFACE, MAX_ATLAS, VERTEX_INTERFACE, ItemBufferRenderer
from .calls import StageCalls
from .geometry import clip_polygon_to_plane, default_near_far, default_up, gauss_points, hemicube_inputs, hemicube_up
from .pictures import formfactor_image, item_buffer_image, palette, unfold
from .raycast import formfactor_matrix_raycast
from .rows import BLIND_ROW_SUM, HemicubeFormFactors

__all__ = ["FRAGMENT_INTERFACE", "MAX_ATLAS", "VERTEX_INTERFACE", "ItemBufferRenderer", "StageCalls",
           "clip_polygon_to_plane", "default_near_far", "default_up", "gauss_points", "hemicube_inputs", "hemicube_up",
           "formfactor_image", "item_buffer_image", "palette", "unfold", "formfactor_matrix_raycast",
           "BLIND_ROW_SUM", "HemicubeFormFactors"]
