"""The reference's plain numpy paths: what a clear vectorised student solution looks like.

The reference uses these for small batches (the autograder's images, the unit tests), where
compiling the numba kernels of ``kernels.py`` would cost more than it saves, and the kernels
for large renders. Both give the same hits (``tests/test_whitted_robust.py`` checks).
"""
