"""The 1988 paper's order of shooting, for the benchmark beside the notes' sweeps (the student's R3).

Cohen, Chen, Wallace and Greenberg pick the shooter again before every shot: always the patch
with the most unshot energy now. The reference holds it as the optional extension R7
(``shoot_largest_first``, one numpy ``argmax`` over the keys per shot: O(n), a few microseconds for
thousands of patches); the bench runs it in R3's place.
"""
from __future__ import annotations

from types import SimpleNamespace
from typing import Any


def with_maximum_order(impl: Any) -> Any:
    """The implementation ``impl`` with its R3 replaced by its R7, the paper's order (its other tasks kept)."""
    names = ("subdivide", "shoot", "ambient_term", "vertex_colors")
    return SimpleNamespace(**{n: getattr(impl, n) for n in names}, progressive_refinement=impl.shoot_largest_first,
                           __name__=getattr(impl, "__name__", "maximum-order"))
