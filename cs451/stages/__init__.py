"""The registry of stages, found by name (as pbrt-v4 creates shapes by name in one factory)."""
from __future__ import annotations

from ..errors import KitError
from .base import Stage


def _registry() -> dict[str, Stage]:
    from . import sphere  # imported lazily: each stage pulls in its own GL or numba machinery
    return {sphere.STAGE.name: sphere.STAGE}


def stage_names() -> list[str]:
    return list(_registry())


def get_stage(name: str) -> Stage:
    stages = _registry()
    if name not in stages:
        raise KitError(f"unknown stage {name!r} (stages: {', '.join(stages)})")
    return stages[name]
