"""The decks' figures as a registry: each figure's draw function, what it shows, its sizes, and every source whose
change makes it again (:class:`Spec`). Figures are declared in the package of the stage they illustrate
(``cs451/stages/<stage>/figures.py``) with :func:`slide_figure`; :mod:`cs451.slides.figures` finds, caches and
draws them.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from .. import KIT_ROOT
from ..errors import KitError

#: Where the figures load the reference from (tests point it at an edited copy). The stages' own code loads
#: what it builds on from the kit's reference (:func:`cs451.impl.earlier_stage_impl`): see ``Spec.engine``.
REFERENCE = KIT_ROOT / "reference"
#: Bump to make every figure again (a change of this module alone already does: its source is hashed).

# --- the registry -------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Drawn:
    """A figure as drawn: the picture (uint8 RGB) and the numbers it shows, kept in the PNG beside it."""
    image: np.ndarray
    facts: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Spec:
    """One figure: what it shows, how it is drawn, at which sizes, and everything whose change makes it again."""
    name: str
    description: str
    draw: Callable[..., Drawn]       # draw(bar, **params) -> Drawn
    full: dict[str, Any]
    quick: dict[str, Any]
    stages: tuple[str, ...] = ()     # reference packages this module loads (from REFERENCE)
    engine: tuple[str, ...] = ()     # reference packages the stages' own code loads (the kit's reference)
    kit: tuple[str, ...] = ()        # kit modules that draw it (dotted names)
    bench: tuple[str, ...] = ()      # benchmark modules it measures with (bench/<name>.py)
    scenes: tuple[str, ...] = ()     # bundled scene files it reads (cs451/scenes/<file>)
    records: tuple[str, ...] = ()    # recorded measurements it draws (slides/records/<name>.json)
    steps: int = 1                   # progress steps, for the bar


SPECS: dict[str, Spec] = {}


def slide_figure(name: str, description: str, *, full: dict[str, Any] | None = None,
                 quick: dict[str, Any] | None = None,
                 **sources: Any) -> Callable[[Callable[..., Drawn]], Callable[..., Drawn]]:
    """Register a figure's draw function; ``quick`` overrides parameters of ``full`` for the tests' small version."""
    def register(draw: Callable[..., Drawn]) -> Callable[..., Drawn]:
        params = dict(full or {})
        SPECS[name] = Spec(name, description, draw, params, {**params, **(quick or {})}, **sources)
        return draw
    return register


def spec_of(name: str) -> Spec:
    if name not in SPECS:
        raise KitError(f"unknown figure {name!r} (the figures: {', '.join(SPECS)})")
    return SPECS[name]

