"""Stage 3's grading tolerances, one table, each with why it has its value (docs/tolerances.md has the image tests')."""
from __future__ import annotations

from ..base import Tolerance

FLOAT64_RTOL = Tolerance(1e-9, "a cell's delta form factor, a view or projection entry, a row entry or Lambert's formula "
                               "against its closed form (relative): a few float64 operations")
FLOAT64_ATOL = Tolerance(1e-12, "the same for entries that should be 0 (absolute)")
CELL_ATOL = Tolerance(1e-15, "a delta form factor that should be 0 (absolute): the cells are ~1/r² ≥ 1e-7")
MIDPOINT_SLACK = Tolerance(1e-9, "added to the midpoint rule's bound (0.6/r²) on how far the cells' sum may be from 1: "
                                 "rounding of the sum")
ROW_ATOL = Tolerance(2e-3, "a form-factor row against the reference's, per entry (absolute): a hemicube's aliasing at "
                           "the tests' resolutions moves an entry by ~1e-3; a wrong view or a missing weight by ~1e-2")
KNOWN_ROW = Tolerance(2e-3, "a hemicube's form factor at resolution 128 against a closed form (Howell's catalogue), "
                            "relative, where the far patch covers thousands of cells: the cells' quantisation of its "
                            "outline is a fraction of a percent of it")
SHARED_EDGE = Tolerance(3e-3, "the same with the proximity fix for two patches sharing an edge (relative): the fix's "
                              "contour integral near the edge is exact, the rest is hemicube cells")
SMALL_SQUARES = Tolerance(0.03, "the same for squares 0.2 wide one apart (relative): the far square covers few cells even "
                                "at resolution 128, so its outline's quantisation is percents of it (hence rotated "
                                "hemicubes, whose cells do not line up with its edges)")
CLOSURE = Tolerance(5e-3, "a row of a closed cube sums to 1 within this: the cells' quantisation of the faces' outlines "
                          "at the tests' resolutions, summed over a row")
