"""The registry of stages, found by name (as pbrt-v4 creates shapes by name in one factory).

Every package here (``stages/<name>/``) is a stage and defines ``STAGE`` in its ``__init__``; the registry finds
a new stage by its package alone. The rest a stage needs (reference, specs, handout) is listed in
docs/adding-a-stage.md. Stages are imported lazily because each pulls in its own GL or numba machinery.
"""
from __future__ import annotations

import importlib
import pkgutil

from ..errors import KitError
from .base import Stage

_NOT_STAGES = {"base"}


def _module_names() -> list[str]:
    return [m.name for m in pkgutil.iter_modules(__path__) if m.name not in _NOT_STAGES and not m.name.startswith("_")]


def _registry() -> dict[str, Stage]:
    stages = [importlib.import_module(f"{__name__}.{name}").STAGE for name in _module_names()]
    return {s.name: s for s in sorted(stages, key=lambda s: s.number)}


def stage_names() -> list[str]:
    """Every stage's name, in stage order (the CLI's choices, and the stages the canary looks for copies of)."""
    return list(_registry())


def get_stage(name: str) -> Stage:
    """The stage called ``name``, importing its package alone (a grading worker asks for one stage: importing every
    stage's GL and numba machinery cost it a fifth of its time); a KitError listing the stages there are where none
    is. A stage's name is its package's."""
    if name in _module_names():
        stage = importlib.import_module(f"{__name__}.{name}").STAGE
        if stage.name == name:
            return stage
    stages = _registry()
    if name not in stages:
        raise KitError(f"unknown stage {name!r} (stages: {', '.join(stages)})")
    return stages[name]


def check_options(scene: object) -> None:
    """Refuse a scene whose ``options`` name a stage that does not exist, or hold a bad option of any stage,
    not only of the one about to run: a typo in ``options.radiosity`` must not wait for the day someone
    renders the scene with stage 4."""
    from ..schema import suggestion
    stages = _registry()
    for name in getattr(scene, "options", {}):
        if name not in stages:
            raise KitError(f"{scene.label}: options.{name}: no stage is called {name!r}"  # type: ignore[attr-defined]
                           f"{suggestion(name, stages)} (stages: {', '.join(stages)})")
        stages[name].options(scene)
