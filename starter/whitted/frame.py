"""The reference's compiled W11: a whole frame's recursion in one kernel (``kernels.frame``), so that no
per-bounce bookkeeping runs in numpy. ``tracer.trace`` hands large batches here; both give the same
colours to rounding and the same counters (``tests/test_whitted_frame.py``). Students' copies are empty.
"""
