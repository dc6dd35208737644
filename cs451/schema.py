"""Declarative parsing of JSON into frozen dataclasses.

Each field is described once, in its dataclass, with ``field(doc=..., check=...)``.
The same descriptions feed validation errors and :func:`describe`, a field
reference of a record written from them. Unknown keys are errors, as in trimesh's schemas
(``additionalProperties: false``): a typo must never be silently ignored.
"""
from __future__ import annotations

import dataclasses
import difflib
import functools
import math
import typing
from typing import Any, Callable, Iterable, Literal, get_args, get_origin

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

def _bounds(**json: float) -> Callable[[Callable], Callable]:
    """Record a check's range as JSON Schema keywords, for :func:`json_schema` (editors then flag it too)."""
    def mark(check: Callable) -> Callable:
        check.json = json  # type: ignore[attr-defined]
        return check
    return mark


@_bounds(exclusiveMinimum=0)
def positive(x: Any) -> str | None:
    values = x if isinstance(x, tuple) else (x,)
    return None if all(v > 0 for v in values) else "must be > 0"


@_bounds(minimum=0)
def non_negative(x: Any) -> str | None:
    values = x if isinstance(x, tuple) else (x,)
    return None if all(v >= 0 for v in values) else "must be >= 0"


@_bounds(minimum=0, maximum=1)
def unit_interval(x: Any) -> str | None:
    values = x if isinstance(x, tuple) else (x,)
    return None if all(0 <= v <= 1 for v in values) else "must lie in [0, 1]"


#: the shortest vector a scene may give as a direction: a shorter one's length underflows when squared, so it
#: cannot be normalised (an `up` of [0, 1e-300, 0] would turn into NaN in the camera's frame)
MIN_LENGTH = 1e-30


def nonzero_vector(x: Any) -> str | None:
    if not any(v != 0 for v in x):
        return "must not be the zero vector"
    if max(abs(v) for v in x) < MIN_LENGTH:
        return f"is too short to give a direction (each component under {MIN_LENGTH:g}: it cannot be normalised)"
    return None


def at_least(n: float) -> Callable[[Any], str | None]:
    @_bounds(minimum=n)
    def check(x: Any) -> str | None:
        return None if x >= n else f"must be >= {n}"
    return check


def between(lo: float, hi: float, why: str = "") -> Callable[[Any], str | None]:
    """A count or size with a floor and a ceiling; ``why`` says what the ceiling protects."""
    @_bounds(minimum=lo, maximum=hi)
    def check(x: Any) -> str | None:
        if x < lo:
            return f"must be >= {lo}"
        return None if x <= hi else f"must be at most {hi:,}" + (f" ({why})" if why else "")
    return check


def max_items(n: int, why: str) -> Callable[[Any], str | None]:
    """A list of at most ``n`` items."""
    @_bounds(maxItems=n)
    def check(x: Any) -> str | None:
        return None if len(x) <= n else f"must hold at most {n:,} items ({why}), got {len(x):,}"
    return check


def suggestion(word: Any, choices: Iterable[str]) -> str:
    """`` (did you mean 'tolerance'?)`` for a misspelt key or name, or nothing when no choice is close."""
    close = difflib.get_close_matches(str(word), list(choices), n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


class JSONObject(dict):
    """A JSON object as :func:`json_object` reads it: a dict that remembers the keys that appeared twice."""
    duplicates: tuple[str, ...] = ()


def json_object(pairs: list[tuple[str, Any]]) -> dict:
    """``object_pairs_hook`` for :func:`json.loads`: JSON lets a key repeat and keeps the last silently; the
    schema refuses it, at the object's path (:func:`check_duplicates`)."""
    out = JSONObject(pairs)
    if len(out) < len(pairs):
        seen: set[str] = set()
        out.duplicates = tuple(k for k, _ in pairs if k in seen or seen.add(k))  # type: ignore[func-returns-value]
    return out


def check_duplicates(data: dict, ctx: "Context") -> None:
    for key in getattr(data, "duplicates", ()):
        raise ctx.child(key).error("appears twice in this object (JSON would silently keep the last one)")


# --- parsing ----------------------------------------------------------------

class Context:
    """Where we are: the file and the JSON path, for error messages (the path is spelt out only for an error:
    a scene of 200,000 spheres would otherwise build a million strings it never shows)."""

    def __init__(self, file: str, path: str = "", parent: "Context | None" = None, key: str | int | None = None):
        self.file, self._path, self._parent, self._key = file, path, parent, key

    @property
    def path(self) -> str:
        if self._parent is None:
            return self._path
        base, key = self._parent.path, self._key
        if isinstance(key, int):
            return f"{base}[{key}]"
        return f"{base}.{key}" if base else str(key)

    def child(self, key: str | int) -> "Context":
        return Context(self.file, parent=self, key=key)

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
        check_duplicates(data, ctx)
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
    hints, fields = _declared(cls)
    check_duplicates(data, ctx)
    for key in data:
        if key not in fields:
            known = ", ".join(sorted(fields))
            raise ctx.child(key).error(f"unknown field{suggestion(key, fields)} (known fields: {known})")
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


@functools.cache
def _declared(cls: type) -> tuple[dict[str, Any], dict[str, dataclasses.Field]]:
    """A record's type hints and init fields, worked out once per class (``get_type_hints`` compiles its
    annotations each call: 20 of the 29 s a scene of 200,000 spheres took to load)."""
    return typing.get_type_hints(cls), {f.name: f for f in dataclasses.fields(cls) if f.init}


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
        check_duplicates(data, ctx)
        kind = data.get("type")
        if not isinstance(kind, str) or kind not in cls._registry:
            known = ", ".join(sorted(cls._registry))
            raise ctx.child("type").error(f"unknown {cls.__name__.lower()} type {kind!r}"
                                          f"{suggestion(kind, cls._registry)} (known types: {known})")
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


# --- JSON Schema, for editors -------------------------------------------------

def json_schema(cls: type, title: str = "") -> dict:
    """The JSON Schema (draft 2020-12) of a record, from the same declarations the parser reads: an editor
    that knows it completes field names, shows each field's description and flags typos and ranges as one
    types. Checks that are code (a camera's up against its view) stay the parser's alone."""
    defs: dict[str, dict] = {}
    root = _record_schema(cls, defs)
    return {"$schema": "https://json-schema.org/draft/2020-12/schema", "title": title or cls.__name__,
            **root, "$defs": dict(sorted(defs.items()))}


def _schema_of(tp: Any, defs: dict[str, dict]) -> dict:
    origin = get_origin(tp)
    if tp is Any:
        return {}
    if origin is typing.Union or (origin is not None and str(origin) == "<class 'types.UnionType'>"):
        return {"anyOf": [_schema_of(a, defs) if a is not type(None) else {"type": "null"} for a in get_args(tp)]}
    if origin is Literal:
        return {"enum": list(get_args(tp))}
    simple = {bool: {"type": "boolean"}, str: {"type": "string"},
              float: {"type": "number", "minimum": -MAX_MAGNITUDE, "maximum": MAX_MAGNITUDE},
              int: {"type": "integer", "minimum": -MAX_INTEGER, "maximum": MAX_INTEGER}}
    if tp in simple:
        return dict(simple[tp])
    if origin is tuple:
        items = [_schema_of(a, defs) for a in get_args(tp)]
        return {"type": "array", "prefixItems": items, "minItems": len(items), "maxItems": len(items)}
    if origin is list:
        return {"type": "array", "items": _schema_of(get_args(tp)[0], defs)}
    if origin is dict:
        return {"type": "object", "additionalProperties": _schema_of(get_args(tp)[1], defs)}
    if isinstance(tp, type) and issubclass(tp, Tagged):
        name = tp.__name__
        if name not in defs:
            defs[name] = {}   # a placeholder first: a group holds objects
            kinds = [_record_schema(sub, defs, tag=kind) for kind, sub in sorted(tp._registry.items())]
            defs[name] = {"description": (tp.__doc__ or "").strip(), "oneOf": kinds}
        return {"$ref": f"#/$defs/{name}"}
    if dataclasses.is_dataclass(tp):
        name = tp.__name__
        if name not in defs:
            defs[name] = {}
            defs[name] = _record_schema(tp, defs)
        return {"$ref": f"#/$defs/{name}"}
    raise TypeError(f"schema: unsupported type {tp!r}")  # a bug in the kit, not bad input


def _record_schema(cls: type, defs: dict[str, dict], tag: str | None = None) -> dict:
    hints, fields = _declared(cls)
    props: dict[str, dict] = {"type": {"const": tag}} if tag else {}
    required = ["type"] if tag else []
    for name, f in fields.items():
        prop = _schema_of(hints[name], defs)
        bounds = getattr(f.metadata.get("check"), "json", None)
        if bounds:
            target = prop.get("prefixItems") or [prop]
            for item in target:
                item.update(bounds)
        prop["description"] = f.metadata.get("doc", "")
        if f.default is not _MISSING:
            prop["default"] = list(f.default) if isinstance(f.default, tuple) else \
                (f.default if not dataclasses.is_dataclass(f.default) else dataclasses.asdict(f.default))
        elif f.default_factory is _MISSING:  # type: ignore[misc]
            required.append(name)
        props[name] = prop
    out = {"type": "object", "properties": props, "additionalProperties": False}
    if required:
        out["required"] = required
    if cls.__doc__ and not cls.__doc__.startswith(cls.__name__ + "("):
        out["description"] = cls.__doc__.strip()
    return out
