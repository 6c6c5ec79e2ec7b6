"""A small TOML writer for scene edits given as dicts (World.apply, World(toml=...)).

Writes what docs/scene-format.md uses: tables, strings, booleans, integers, floats and
arrays of those; a list of dicts is an array of inline tables (a scene list such as
[[swe.sources]]: {"swe": {"sources": [{"start": [10, 0, 5], "discharge": 2.0}]}}). Reading uses the standard library's tomllib.
"""
from __future__ import annotations

import math
from typing import Any, Mapping


def _value(key: str, v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            raise ValueError(f"scene key {key}: {v} is not a finite number")
        return repr(v)
    if isinstance(v, str):
        escaped = v.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")
        return f'"{escaped}"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(key, x) for x in v) + "]"
    if isinstance(v, Mapping):  # an inline table: an entry of a scene list
        for k in v:
            if not isinstance(k, str):
                raise ValueError(f"scene key {key}: keys must be strings, got {k!r}")
        return "{" + ", ".join(f"{_key(k)} = {_value(f'{key}.{k}', x)}" for k, x in v.items()) + "}"
    if hasattr(v, "tolist"):  # numpy scalars and arrays
        return _value(key, v.tolist())
    raise ValueError(f"scene key {key}: a {type(v).__name__} is not a TOML value "
                     "(allowed: bool, int, float, str, lists of them, tables)")


def _key(k: str) -> str:
    return k if k.replace("_", "").replace("-", "").isalnum() else _value(k, k)


def dumps(scene: Mapping[str, Any], _prefix: str = "") -> str:
    """TOML text for a nested dict ({"pbf": {"viscosity": 0.02}} -> "[pbf]\\nviscosity = 0.02")."""
    lines: list[str] = []
    tables: list[tuple[str, Mapping[str, Any]]] = []
    for k, v in scene.items():
        if not isinstance(k, str):
            raise ValueError(f"scene key {k!r}: keys must be strings")
        if isinstance(v, Mapping):
            tables.append((k, v))
        else:
            lines.append(f"{_key(k)} = {_value(_prefix + k, v)}")
    out = "\n".join(lines) + ("\n" if lines else "")
    for k, v in tables:
        name = _prefix + _key(k)
        out += f"\n[{name}]\n" + dumps(v, name + ".")
    return out
