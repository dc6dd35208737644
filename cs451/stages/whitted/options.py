"""Stage 2's options (``options.whitted`` in a scene), declared once: each field's help, default and check."""
from __future__ import annotations

import math
from dataclasses import dataclass

from ... import schema
from ...scene import LIGHT_SAMPLES_WHY, MAX_LIGHT_SAMPLES
from ...schema import Context, field


@dataclass(frozen=True)
class WhittedOptions:
    max_depth: int = field("Most bounces (reflections and refractions) after the camera ray.", 5, schema.at_least(0))
    min_weight: float = field("The cut-off: a ray whose weight β (max over RGB) falls below this is not cast.", 0.01,
                              schema.non_negative)
    spp: int = field("Samples per pixel on a regular grid (1, 4, 9, 16, …: a square).", 1, schema.positive)
    light_samples: int = field("Shadow rays per area light and shading point, overriding each light's `samples` (0: keep).",
                               0, schema.between(0, MAX_LIGHT_SAMPLES, LIGHT_SAMPLES_WHY))

    def validate(self, ctx: Context) -> None:
        """Refuse, naming the field, samples per pixel that are not a square (they lie on a k × k grid) and a
        depth past MAX_DEPTH."""
        if math.isqrt(self.spp) ** 2 != self.spp:
            raise ctx.child("spp").error(f"must be a square number (1, 4, 9, 16, …), got {self.spp}")
        if self.max_depth > MAX_DEPTH:
            raise ctx.child("max_depth").error(f"must be at most {MAX_DEPTH} (each bounce is a pass over every ray "
                                               f"still alive), got {self.max_depth}")


#: the deepest recursion a scene may ask for
MAX_DEPTH = 64
