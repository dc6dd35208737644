"""The reference's compiled inner loops (numba): hierarchy traversal, closest hit, shadow rays, and a
whole Whitted frame (closest hit, shading, shadow rays and the recursion for each camera ray).

Written per ray, in float64 (the hierarchy's boxes aside: tested in float32, widened by the test's error
bound), and run on chunks of rays in threads (``nogil``, see ``running.py``).
A clear numpy solution does not need this file: it is how the reference reaches Embree-like speeds
(see ``bench/whitted.py``). The frame kernel lives here with the traversal it inlines because numba's
cache checks only the file a kernel is defined in. Students' copies of it are empty.
"""
