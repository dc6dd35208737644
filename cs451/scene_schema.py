"""The scene format as a JSON Schema (``docs/scene.schema.json``), for editors.

Written from the same declarations the loader parses with (:mod:`cs451.schema`), each stage's options
included, so an editor that is told of it (VS Code: ``"$schema": "…/scene.schema.json"`` at the top of a scene,
or ``json.schemas`` in its settings) completes field names, shows each field's description and marks a typo
or a value out of range as it is typed. The loader stays the judge: the checks that are code (a camera's up
against its view, a polygon's convexity) are its alone.
"""
from __future__ import annotations

import json
from pathlib import Path

from . import KIT_ROOT
from .schema import json_schema

#: where the kit keeps the exported schema (``cs451 scenes --schema`` prints the same)
SCHEMA_FILE = KIT_ROOT / "docs" / "scene.schema.json"


def scene_json_schema() -> dict:
    """The schema of a scene file, ``options`` spelt out per stage."""
    from .scene import Scene
    from .stages import get_stage, stage_names
    out = json_schema(Scene, "cs451-kit scene file")
    out["properties"]["$schema"] = {"type": "string", "description": "Where an editor finds this schema."}
    del out["properties"]["source"]       # set by the loader, refused in a file
    options = {}
    for name in stage_names():
        stage = get_stage(name)
        sub = json_schema(stage.options_type)
        out["$defs"].update(sub.pop("$defs"))
        sub.pop("$schema")
        sub.pop("title")
        sub["description"] = f"Stage {stage.number}'s options."
        options[name] = sub
    out["properties"]["options"] = {"type": "object", "description": out["properties"]["options"]["description"],
                                    "properties": options, "additionalProperties": False}
    return out


def schema_text() -> str:
    return json.dumps(scene_json_schema(), indent=1, ensure_ascii=False) + "\n"


def write_schema(path: Path = SCHEMA_FILE) -> Path:
    path.write_text(schema_text())
    return path
