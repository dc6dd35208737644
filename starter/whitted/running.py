"""Running the reference's compiled kernels: compiled once (numba's on-disk cache keeps them for later
runs, and the first compile says so), then over chunks of rays in threads. Students' copies are empty.
"""
