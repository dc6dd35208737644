"""Stage 5's grading tolerances, one table, each with why it has its value."""
from __future__ import annotations

from ..base import Tolerance

FLOAT64 = Tolerance(1e-9, "a sample's value against its formula for the same random numbers (relative): a few float64 "
                          "operations")
FLOAT64_ATOL = Tolerance(1e-12, "the same for values that should be 0 (absolute)")
UNIT = Tolerance(1e-9, "a sampled direction's length from 1: a rotation of a unit vector in float64")
SIGMAS = Tolerance(5e-6, "the chance that a correct estimator fails one statistical test: each test allows its "
                         "estimate as many standard errors from the truth as a normal variable exceeds this seldom "
                         "(4.6σ two-sided), and the fresh cases draw new random numbers each time")
RADIOSITY_BIAS = Tolerance(0.02, "how far stage 4's radiosity of a wall (patch size 50, rotated hemicubes of "
                                 "resolution 128) may be from the converged light of the wall (relative): piecewise "
                                 "constant radiosity errs near corners, ~0.4% of a wall's mean as measured against "
                                 "Mitsuba 3; a path tracer missing a bounce, a cosine or a 1/p is off by 10% or more")
PATH_SPREAD = Tolerance(0.25, "the largest standard error of a surface's mean radiance a correct path tracer may "
                              "show, relative to the brightest channel of the surface's radiosity: the reference's is "
                              "at most 0.037 on the Cornell box (both colourings) at the tests' 8,000 paths a surface; the allowance "
                              "(SIGMAS) scales with the submission's own standard error only up to this, or an "
                              "estimator that diverges (a weight that grows instead of shrinking) would pass by its "
                              "own huge spread")
ROULETTE_SLACK = Tolerance(0.05, "how far above its mean bound the count of bounce rays may be in the roulette "
                                "test, as a fraction of the paths: a correct tracer's count is at most a·n + a²·n on average "
                                "(n paths, a the largest albedo); one that starts the roulette a bounce late casts n")
AIM = Tolerance(1e-5, "how far in front of a surface point a probe's ray starts, relative to the scene's size: close "
                      "enough that nothing lies between, far enough that the point is at t > 0 by many ulps")
