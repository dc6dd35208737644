"""Stage 2's grading tolerances, one table, each with why it has its value (docs/tolerances.md has the image tests').

Used by the stage's checks and tests (``autograder/whitted/``) and printed in their descriptions.
"""
from __future__ import annotations

from ..base import Tolerance

FLOAT64 = Tolerance(1e-9, "a result of a few float64 operations against exact (rational) arithmetic or a closed form "
                          "(camera origins, roots, t, reflection, refraction, Fresnel, shading): rounding is ~1e-16 a "
                          "step and the worst conditioning in the tests ~1e5, while a mistake of substance (a sign, a "
                          "missing term, the wrong root) is off by far more than 1e-6")
FLOAT64_ATOL = Tolerance(1e-12, "the same for values that should be 0 (absolute): a colour channel with no light")
NDC = Tolerance(1e-6, "where a camera ray crosses the image plane, in normalised device coordinates: a pixel is 2/width "
                      "(~1e-2) wide, so a ray through a pixel's corner instead of its centre is off by ~5e-3")
HITS = Tolerance(1e-6, "t and normals of closest hits against the reference's, and the normals' length: traversal order "
                       "and the triangle formula change them by ~1e-12 (tests/whitted/test_whitted_robust.py measures 4e-14)")
SAME_PRIMITIVE = Tolerance(0.99, "the share of rays that must hit the reference's primitive: a ray through a shared edge or "
                                 "tangent to a sphere may rightly hit either side")
DEPTH = Tolerance(5e-3, "a hit's depth against pyrender's depth buffer (relative): the buffer's 24 bits over the scene's "
                        "near-far range, with margin")
DEPTH_BAD = Tolerance(0.02, "the share of pixels whose depth may disagree with pyrender's: silhouette pixels, where the "
                            "rasteriser's coverage rule and a ray through the centre may differ")
ANSWER_DIGITS = Tolerance(1e-9, "a submission's query (W8-W10, asked by its trace) is the reference's when they agree to "
                                "this after rounding: far above the rounding of a correct trace's rays, far below any "
                                "two different rays of a frame")
