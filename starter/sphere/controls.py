"""S8: the GLUT keyboard callback, as a pure function of the key and the viewer's state."""
from __future__ import annotations

from cs451.stages.sphere import ViewState


def handle_key(key: str, state: ViewState) -> ViewState:
    """Return the state after ``key`` is pressed (the state is immutable: build a new one).

    Keys: ``q``, ``Q`` or ``escape`` quit (``running`` becomes False);
    ``s`` switches between Gouraud and Phong shading;
    ``+`` doubles ``slices`` and ``stacks`` (at most 256), ``-`` halves them (at least 4);
    any other key changes nothing.
    """
    # TODO S8: one branch per key; dataclasses.replace builds the new state (handout §S8)
    raise NotImplementedError("S8: one branch per key; dataclasses.replace builds the new state (handout §S8)")
