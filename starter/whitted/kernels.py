"""The reference's compiled inner loops (numba): hierarchy traversal, closest hit and shadow rays.

Written per ray, in float64, and run on chunks of rays in threads (``nogil``).
A clear numpy solution does not need this file: it is how the reference reaches
Embree-like speeds (see ``bench/whitted.py``). Students' copies of it are empty.
"""
