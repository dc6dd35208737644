"""Stage 1's grading tolerances, one table, each with why it has its value (docs/tolerances.md has the image tests')."""
from __future__ import annotations

from ..base import Tolerance

MATRIX_RTOL = Tolerance(1e-6, "a matrix entry against the formula (relative): float32 uploads aside, a correct float64 "
                              "matrix is exact to ~1e-15; a wrong sign, a transposition or degrees for radians is off "
                              "by order 1")
MATRIX_ATOL = Tolerance(1e-9, "a matrix entry that should be 0: the same, absolute (cos(π/2) is 6e-17, not 0)")
UNIT = Tolerance(1e-5, "the mesh's normals unit and radial: freeglut's own normals, the truth, are computed in float32 "
                       "(~1e-6 off)")
POSITION = Tolerance(1e-6, "a vertex against freeglut's, relative to the radius: float32 sine and cosine (~1e-7)")
DEGENERATE = Tolerance(1e-12, "a triangle whose area is under this times the radius² is degenerate (a pole's quad "
                              "collapsed): float64 area of a real triangle of the coarsest test mesh is ~1e-2")
PROJECTION = Tolerance(1e-6, "the reshape's aspect ratio and field of view against the window's (relative): exact in "
                             "float64 but for rounding")
SAME_QUERY = Tolerance(1e-12, "a submission's perspective query is the one the reference answered when its four numbers "
                              "agree to this (relative): they are copied, not computed")
