"""The demos' keys as a window title and ``cs451 demo --help`` show them. Each stage declares its own
(``Stage.demo_keys``, in its package); docs/lecturers.md's table lists the same.
"""
from __future__ import annotations

from ..errors import KitError
from ..stages import get_stage, stage_names

#: Keys that end every demo the kit's loop runs (stage 1 leaves quitting to the student's S8).
QUIT_KEYS = ("q", "escape")
#: Keys the window itself answers in every demo (before the demo, or the student's S8, sees any key).
WINDOW_KEYS = (("f", "full screen on / off"), ("h ?", "this help"))


def key_line(stage: str) -> str:
    """``s shadows · r reflection · …``: one line for a window title or a caption (empty for no stage)."""
    try:
        keys = get_stage(stage).demo_keys
    except KitError:
        return ""
    return " · ".join(f"{key} {what}" for key, what in keys)


def help_keys(stage: str) -> list[tuple[str, str]]:
    """What the help overlay lists: the stage's own keys, then the window's (full screen, help), and q if not there."""
    try:
        keys = list(get_stage(stage).demo_keys)
    except KitError:
        keys = []
    quits = [k for k in keys if k[0].split()[0] == "q"]
    rest = [k for k in keys if k not in quits]
    return rest + list(WINDOW_KEYS) + (quits or [("q Esc", "quits")])


def help_text(stages: list[str] | None = None) -> str:
    """The keys of every demo (or of ``stages``' only: a student's copy has one), for ``cs451 demo --help``."""
    lines = ["keys in the window:"]
    for stage in stage_names():
        if stages is not None and stage not in stages:
            continue
        lines.append(f"  {stage:<10} " + ", ".join(f"{key}: {what}" for key, what in get_stage(stage).demo_keys))
    lines.append(f"  {'every demo':<10} " + ", ".join(f"{key}: {what}" for key, what in WINDOW_KEYS))
    return "\n".join(lines)
