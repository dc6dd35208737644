"""Stage 4's grading tolerances, one table, each with why it has its value (docs/tolerances.md has the image tests')."""
from __future__ import annotations

from ..base import Tolerance

FLOAT64_RTOL = Tolerance(1e-9, "a patch corner, a shot's B and ΔB, the ambient term or a vertex colour against the "
                               "formula (relative): a few float64 operations")
FLOAT64_ATOL = Tolerance(1e-12, "the same for values that should be 0 (absolute)")
AREA = Tolerance(1e-5, "the patches of a quad cover it (relative area): float64 sums of many patches' areas, with "
                       "margin for bilinear patches of a non-planar quad")
EDGE_SLACK = Tolerance(1e-9, "a patch edge may exceed the largest allowed by this (relative): rounding of the division")
LOOP_RTOL = Tolerance(1e-8, "the shooting loop's B and ΔB after many shots (relative): rounding accumulates over the "
                            "shots, ~1e-13 each")
CORNER_ATOL = Tolerance(1e-9, "the vertex positions at the patches' corners (absolute, scene units of ~1-500): copied, "
                              "not computed")
DIRECT_SOLVE = Tolerance(1e-3, "a progressive solve stopped at its tolerance (1e-5 of the emitted power unshot) against "
                               "the direct solve of the same system (sum of |differences|, relative): what is still "
                               "unshot bounds the difference, with margin")
SHOTS = Tolerance(0.25, "a solve takes as many shots as the reference's within this share (from 1/1.25 to 1.25 times): "
                        "ties between patches of equal unshot power may be broken another way, which changes the count "
                        "by a few percent; shooting in another order than the largest first changes it by far more")
