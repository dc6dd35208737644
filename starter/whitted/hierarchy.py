"""The reference's hierarchy, built once per geometry: a binned-SAH build and the eight-wide layout the
compiled kernels traverse, both in numba, each kept in a small cache keyed by a digest of the arrays it
was made from (so renders and demo frames of the same geometry build nothing), with counts of what was
built and what was reused. Students' copies of this file are empty.
"""
