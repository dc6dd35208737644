"""Declarative parsing of JSON into frozen dataclasses.

Each field is described once, in its dataclass, with ``field(doc=..., check=...)``.
The same descriptions feed validation errors and :func:`describe`, a field
reference of a record written from them. Unknown keys are errors, as in trimesh's schemas
(``additionalProperties: false``): a typo must never be silently ignored.
"""
from __future__ import annotations

import dataclasses
import math
import typing
from typing import Any, Callable, Literal, get_args, get_origin

from .errors import InputError

Vec3 = tuple[float, float, float]

_MISSING = dataclasses.MISSING


def field(doc: str, default: Any = _MISSING, check: Callable[[Any], str | None] | None = None) -> Any:
    """A dataclass field with a description and an optional check returning an error or None."""
    meta = {"doc": doc, "check": check}
    if isinstance(default, (list, dict)):
        value = default
        return dataclasses.field(default_factory=lambda: type(value)(value), metadata=meta)
    return dataclasses.field(default=default, metadata=meta)


#: the largest number a scene may hold: a coordinate of 1e15 still squares to a finite 1e30
MAX_MAGNITUDE = 1e15
#: the largest integer (GL's and numpy's 32-bit counts)
MAX_INTEGER = 2**31 - 1


# --- checks -----------------------------------------------------------------

def positive(x: Any) -> str | None:
    values = x if isinstance(x, tuple) else (x,)
    return None if all(v > 0 for v in values) else "must be > 0"


def non_negative(x: Any) -> str | None:
    values = x if isinstance(x, tuple) else (x,)
    return None if all(v >= 0 for v in values) else "must be >= 0"


def unit_interval(x: Any) -> str | None:
    values = x if isinstance(x, tuple) else (x,)
    return None if all(0 <= v <= 1 for v in values) else "must lie in [0, 1]"


def nonzero_vector(x: Any) -> str | None:
    return None if any(v != 0 for v in x) else "must not be the zero vector"


def at_least(n: float) -> Callable[[Any], str | None]:
    def check(x: Any) -> str | None:
        return None if x >= n else f"must be >= {n}"
    return check


# --- parsing ----------------------------------------------------------------

class Context:
    """Where we are: the file and the JSON path, for error messages."""

    def __init__(self, file: str, path: str = ""):
        self.file, self.path = file, path

    def child(self, key: str | int) -> "Context":
        if isinstance(key, int):
            return Context(self.file, f"{self.path}[{key}]")
        return Context(self.file, f"{self.path}.{key}" if self.path else key)

    def error(self, message: str) -> InputError:
        return InputError(self.file, self.path, message)


def _type_name(tp: Any) -> str:
    if tp is float:
        return "a number"
    if tp is int:
        return "an integer"
    if tp is bool:
        return "true or false"
    if tp is str:
        return "a string"
    if tp == Vec3:
        return "a list of 3 numbers"
    return getattr(tp, "__name__", str(tp))


def parse_value(tp: Any, data: Any, ctx: Context) -> Any:
    """Convert JSON ``data`` to the annotated type ``tp`` or raise an InputError at ``ctx``."""
    if tp is Any:
        return data
    origin = get_origin(tp)
    if origin is typing.Union or (origin is not None and str(origin) == "<class 'types.UnionType'>"):
        args = [a for a in get_args(tp) if a is not type(None)]
        if data is None and len(args) < len(get_args(tp)):
            return None
        return parse_value(args[0], data, ctx)
    if origin is Literal:
        choices = get_args(tp)
        if data not in choices:
            raise ctx.error(f"must be one of {', '.join(repr(c) for c in choices)}, got {data!r}")
        return data
    if tp is bool:
        if not isinstance(data, bool):
            raise ctx.error(f"must be true or false, got {data!r}")
        return data
    if tp is float:
        if isinstance(data, bool) or not isinstance(data, (int, float)):
            raise ctx.error(f"must be a number, got {data!r}")
        if not math.isfinite(data):
            raise ctx.error(f"must be a finite number, got {data!r}")
        if abs(data) > MAX_MAGNITUDE:
            raise ctx.error(f"must lie within ±{MAX_MAGNITUDE:g} (squares of larger numbers overflow), got {data!r}")
        return float(data)
    if tp is int:
        if isinstance(data, bool) or not isinstance(data, (int, float)) or \
                (isinstance(data, float) and not data.is_integer()):
            raise ctx.error(f"must be an integer, got {data!r}")
        if abs(data) > MAX_INTEGER:
            raise ctx.error(f"must be an integer of at most {MAX_INTEGER:,}, got {data!r}")
        return int(data)
    if tp is str:
        if not isinstance(data, str):
            raise ctx.error(f"must be a string, got {data!r}")
        return data
    if origin is tuple:
        args = get_args(tp)
        if not isinstance(data, list) or len(data) != len(args):
            raise ctx.error(f"must be a list of {len(args)} numbers, got {data!r}")
        return tuple(parse_value(a, v, ctx.child(i)) for i, (a, v) in enumerate(zip(args, data)))
    if origin is list:
        (item,) = get_args(tp)
        if not isinstance(data, list):
            raise ctx.error(f"must be a list, got {type(data).__name__}")
        return [parse_value(item, v, ctx.child(i)) for i, v in enumerate(data)]
    if origin is dict:
        _, item = get_args(tp)
        if not isinstance(data, dict):
            raise ctx.error(f"must be an object, got {type(data).__name__}")
        return {k: parse_value(item, v, ctx.child(k)) for k, v in data.items()}
    if isinstance(tp, type) and issubclass(tp, Tagged):
        return tp.parse_tagged(data, ctx)
    if dataclasses.is_dataclass(tp):
        return parse_record(tp, data, ctx)
    raise TypeError(f"schema: unsupported type {tp!r}")  # a bug in the kit, not bad input


def parse_record(cls: type, data: Any, ctx: Context) -> Any:
    """Parse a JSON object into dataclass ``cls``: required fields, defaults, checks, no unknown keys."""
    if not isinstance(data, dict):
        raise ctx.error(f"must be an object, got {type(data).__name__}")
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    for key in data:
        if key not in fields:
            known = ", ".join(sorted(fields))
            raise ctx.child(key).error(f"unknown field (known fields: {known})")
    values = {}
    for name, f in fields.items():
        sub = ctx.child(name)
        if name not in data:
            if f.default is _MISSING and f.default_factory is _MISSING:  # type: ignore[misc]
                raise sub.error("missing required field")
            continue
        value = parse_value(hints[name], data[name], sub)
        check = f.metadata.get("check")
        if check is not None and value is not None:
            problem = check(value)
            if problem:
                raise sub.error(f"{problem}, got {data[name]!r}")
        values[name] = value
    obj = cls(**values)
    validate = getattr(obj, "validate", None)
    if validate is not None:
        validate(ctx)
    return obj


class Tagged:
    """Base of a family of records chosen by their ``"type"`` key (a factory, as pbrt-v4 creates shapes).

    Subclasses register with ``@SomeFamily.register("name")``.
    """

    _registry: dict[str, type]

    def __init_subclass__(cls, family: bool = False, **kw: Any):
        super().__init_subclass__(**kw)
        if family:
            cls._registry = {}

    @classmethod
    def register(cls, name: str) -> Callable[[type], type]:
        def deco(sub: type) -> type:
            cls._registry[name] = sub
            sub.type_name = name  # type: ignore[attr-defined]
            return sub
        return deco

    @classmethod
    def parse_tagged(cls, data: Any, ctx: Context) -> Any:
        if not isinstance(data, dict):
            raise ctx.error(f"must be an object, got {type(data).__name__}")
        kind = data.get("type")
        if not isinstance(kind, str) or kind not in cls._registry:
            known = ", ".join(sorted(cls._registry))
            raise ctx.child("type").error(f"unknown {cls.__name__.lower()} type {kind!r} (known types: {known})")
        body = {k: v for k, v in data.items() if k != "type"}
        return parse_record(cls._registry[kind], body, ctx)


def describe(cls: type, indent: str = "") -> str:
    """A Markdown list of a record's fields, with types, defaults and descriptions (for handouts)."""
    hints = typing.get_type_hints(cls)
    lines = []
    for f in dataclasses.fields(cls):
        if not f.init:
            continue
        if f.default is not _MISSING:
            default = f"default `{f.default!r}`"
        elif f.default_factory is not _MISSING:  # type: ignore[misc]
            default = f"default `{f.default_factory()!r}`"  # type: ignore[misc]
        else:
            default = "required"
        lines.append(f"{indent}- `{f.name}` ({_type_name(hints[f.name])}, {default}): {f.metadata.get('doc', '')}")
    return "\n".join(lines)
