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
    # BEGIN SOLUTION S8: one branch per key; dataclasses.replace builds the new state (handout §S8)
    import dataclasses
    if key in ("q", "Q", "escape"):
        return dataclasses.replace(state, running=False)
    if key == "s":
        return dataclasses.replace(state, shading="phong" if state.shading == "gouraud" else "gouraud")
    if key == "+":
        return dataclasses.replace(state, slices=min(state.slices * 2, 256), stacks=min(state.stacks * 2, 256))
    if key == "-":
        return dataclasses.replace(state, slices=max(state.slices // 2, 4), stacks=max(state.stacks // 2, 4))
    return state
    # END SOLUTION
