"""Every demo's keys, written once: the window titles, `cs451 demo --help` and docs/lecturers.md's table name them from here.

Plain data, cheap to import (the CLI builds its help from it without loading a demo).
Stage 1's keys are the student's S8 table (the handout's), the others the demos' own.
"""
from __future__ import annotations

#: stage -> (key, what it does), in the order the title and the help list them
CONTROLS: dict[str, tuple[tuple[str, str], ...]] = {
    "sphere": (("s", "Gouraud / Phong"), ("+ -", "tessellation"), ("q", "quits (through S8)")),
    "whitted": (("s", "shadows"), ("r", "reflection"), ("t", "refraction"), ("c", "the β cut-off"),
                ("+ -", "depth"), ("click", "a pixel's ray tree"), ("x", "clears it"), ("q", "quits")),
    "hemicube": (("← →", "patch"), ("click", "picks a patch (scene or item buffer)"), ("space", "sweep"),
                 ("p", "proximity fix (H6)"), ("r", "rotation"), ("+ -", "resolution"), ("q", "quits")),
    "radiosity": (("q", "quits"),),
}

#: Keys that end every demo the kit's loop runs (stage 1 leaves quitting to the student's S8).
QUIT_KEYS = ("q", "escape")


def key_line(stage: str) -> str:
    """``s shadows · r reflection · …``: one line for a window title or a caption."""
    return " · ".join(f"{key} {what}" for key, what in CONTROLS.get(stage, ()))


def help_text(stages: list[str] | None = None) -> str:
    """The keys of every demo (or of ``stages``' only: a student's copy has one), for ``cs451 demo --help``."""
    lines = ["keys in the window:"]
    for stage, controls in CONTROLS.items():
        if stages is not None and stage not in stages:
            continue
        lines.append(f"  {stage:<10} " + ", ".join(f"{key}: {what}" for key, what in controls))
    return "\n".join(lines)
