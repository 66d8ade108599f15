"""Scene fields: how a field declares its unit and range, and how raw values are checked.

A field is declared with :func:`field_spec` (description, unit, bounds,
default); :func:`build` turns a raw TOML table into the dataclass, checking
every value's type and range and naming the dotted field on error.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import field
from typing import Any, Literal, get_args, get_origin, get_type_hints

from foamsilo.errors import SceneError


def field_spec(
    description: str,
    unit: str = "",
    *,
    gt: float | None = None,
    ge: float | None = None,
    lt: float | None = None,
    le: float | None = None,
    default: Any = dataclasses.MISSING,
) -> Any:
    """Declare a scene field with its documentation and allowed range."""
    meta = {"description": description, "unit": unit, "gt": gt, "ge": ge, "lt": lt, "le": le}
    if default is dataclasses.MISSING:
        return field(metadata=meta)
    return field(default=default, metadata=meta)


def describe_range(meta: Mapping[str, Any]) -> str:
    """Return a field's allowed range in words (``> 0 and <= 2``), empty when unbounded."""
    parts = []
    if meta.get("gt") is not None:
        parts.append(f"> {meta['gt']:g}")
    if meta.get("ge") is not None:
        parts.append(f">= {meta['ge']:g}")
    if meta.get("lt") is not None:
        parts.append(f"< {meta['lt']:g}")
    if meta.get("le") is not None:
        parts.append(f"<= {meta['le']:g}")
    return " and ".join(parts)


def _check_number(name: str, value: Any, typ: type, meta: Mapping[str, Any]) -> float | int:
    unit = f" {meta['unit']}" if meta.get("unit") else ""
    rng = describe_range(meta)
    allowed = f"a{'n integer' if typ is int else ' number'}{' ' + rng if rng else ''}{unit}"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SceneError(name, f"got {value!r}; allowed: {allowed}")
    if typ is int and not float(value).is_integer():
        raise SceneError(name, f"got {value!r}; allowed: {allowed}")
    v = int(value) if typ is int else float(value)
    if not math.isfinite(v):
        raise SceneError(name, f"got {value!r}; allowed: {allowed}")
    bad = (
        (meta.get("gt") is not None and not v > meta["gt"])
        or (meta.get("ge") is not None and not v >= meta["ge"])
        or (meta.get("lt") is not None and not v < meta["lt"])
        or (meta.get("le") is not None and not v <= meta["le"])
    )
    if bad:
        raise SceneError(name, f"got {v:g}; allowed: {allowed}")
    return v


def build(cls: Any, data: Any, prefix: str) -> Any:
    """Build dataclass ``cls`` from a raw table, checking every value; errors name the field."""
    if not isinstance(data, dict):
        raise SceneError(prefix or "scene", f"expected a table, got {data!r}")
    hints = get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    unknown = sorted(set(data) - set(fields))
    if unknown:
        where = prefix + "." if prefix else ""
        raise SceneError(
            where + unknown[0],
            f"unknown key; allowed keys{' in ' + prefix if prefix else ''}: "
            + ", ".join(sorted(fields)),
        )
    kwargs: dict[str, Any] = {}
    for name, f in fields.items():
        dotted = f"{prefix}.{name}" if prefix else name
        if name not in data:
            if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
                raise SceneError(dotted, f"missing; {f.metadata.get('description', '')}")
            continue
        kwargs[name] = _convert(dotted, data[name], hints[name], f.metadata)
    return cls(**kwargs)


def _convert(name: str, value: Any, typ: Any, meta: Mapping[str, Any]) -> Any:
    origin = get_origin(typ)
    args = get_args(typ)
    if dataclasses.is_dataclass(typ):
        return build(typ, value, name)
    if origin is Literal:
        if value not in args:
            raise SceneError(name, f"got {value!r}; allowed: {', '.join(map(repr, args))}")
        return value
    if origin is tuple:  # tuple[float, ...]: a TOML array of numbers
        if not isinstance(value, (list, tuple)):
            raise SceneError(name, f"got {value!r}; allowed: a list of numbers")
        return tuple(_check_number(f"{name}[{i}]", v, args[0], meta) for i, v in enumerate(value))
    if args and type(None) in args:  # Optional[X]
        inner = [a for a in args if a is not type(None)][0]
        return _convert(name, value, inner, meta)
    if typ is bool:
        if not isinstance(value, bool):
            raise SceneError(name, f"got {value!r}; allowed: true, false")
        return value
    if typ in (int, float):
        return _check_number(name, value, typ, meta)
    if typ is str:
        if not isinstance(value, str):
            raise SceneError(name, f"got {value!r}; allowed: a string")
        return value
    raise SceneError(name, f"unsupported type {typ}")  # pragma: no cover
