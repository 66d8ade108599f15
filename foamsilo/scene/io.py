"""Reading and writing scenes: TOML files, bundled presets, ``--set`` overrides.

Every way a scene comes in (a file, a preset name, overrides on either)
ends in :func:`scene_from_dict`, which builds the typed :class:`Scene` and
applies the cross-field rules; a file that cannot be read as UTF-8 TOML is
refused with a :class:`~foamsilo.errors.SceneError` naming the file and, for
a syntax error, the line.
"""

from __future__ import annotations

import copy
import hashlib
import json
import sys
from importlib import resources
from pathlib import Path
from typing import Any

import tomli_w

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from foamsilo.errors import SceneError
from foamsilo.scene.model import Scene
from foamsilo.scene.rules import validate
from foamsilo.scene.schema import build


def scene_from_dict(data: dict[str, Any]) -> Scene:
    """Build and validate a :class:`Scene` from a nested dict.

    Raises
    ------
    SceneError
        Naming the offending field and its allowed values.
    """
    scene = build(Scene, data, "")
    validate(scene)
    return scene


def parse_override(item: str) -> tuple[list[str], Any]:
    """Parse ``"section.key=value"`` with the value read as a TOML literal."""
    if "=" not in item:
        raise SceneError(item, "override must be of the form section.key=value")
    key, raw = item.split("=", 1)
    key = key.strip()
    if not key or any(not part for part in key.split(".")):
        raise SceneError(item, "override must be of the form section.key=value")
    try:
        value = tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()  # a bare word, e.g. representation=planar
    return key.split("."), value


def format_override(key: str, value: Any) -> str:
    """``section.key=value`` for a value (a TOML literal): the inverse of :func:`parse_override`."""
    if isinstance(value, bool):
        literal = "true" if value else "false"
    elif isinstance(value, str):
        literal = "'" + value + "'"
    else:
        literal = repr(value)
    return f"{key}={literal}"


#: Keys that say the same thing two ways: setting one removes the other
ALTERNATIVES = {
    ("mesh", "cells_across"): "cells_across_orifice",
    ("mesh", "cells_across_orifice"): "cells_across",
    ("material", "viscosity_cap"): "viscosity_cap_scaled",
    ("material", "viscosity_cap_scaled"): "viscosity_cap",
}


def apply_overrides(data: dict[str, Any], overrides: list[str] | None) -> dict[str, Any]:
    """Return a copy of ``data`` with ``--set`` style overrides applied.

    ``section.key=value`` sets a value (a TOML literal); ``section.key=`` with
    nothing after the ``=`` removes the key, so that its default applies.
    Setting one of two keys that say the same thing two ways
    (:data:`ALTERNATIVES`: ``mesh.cells_across`` and
    ``mesh.cells_across_orifice``; ``material.viscosity_cap`` and
    ``material.viscosity_cap_scaled``) removes the other.
    """
    out = copy.deepcopy(data)
    for item in overrides or []:
        path, value = parse_override(item)
        node = out
        for part in path[:-1]:
            node = node.setdefault(part, {})
            if not isinstance(node, dict):
                raise SceneError(".".join(path), "is not a table")
        if value == "":  # "key=" unsets the key (its default applies)
            node.pop(path[-1], None)
        else:
            node[path[-1]] = value
            other = ALTERNATIVES.get((path[0], path[-1])) if len(path) == 2 else None
            if other is not None:
                node.pop(other, None)
    return out


def read_toml(path: Path, what: str = "scene") -> dict[str, Any]:
    """Read a UTF-8 TOML file; errors name the file (and the line of a syntax error).

    Raises
    ------
    SceneError
        With field ``what``: the file is missing, a directory, unreadable,
        not UTF-8 text, or not valid TOML.
    """
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise SceneError(what, f"file not found: {path}") from None
    except IsADirectoryError:
        raise SceneError(what, f"{path} is a directory, not a TOML file") from None
    except OSError as exc:
        raise SceneError(what, f"cannot read {path}: {exc.strerror}") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        raise SceneError(
            what, f"{path} is not UTF-8 text (byte {exc.start}, line {line}): TOML files are UTF-8"
        ) from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(what, f"{path} is not valid TOML: {exc}") from None


def load_scene_file(path: str | Path, overrides: list[str] | None = None) -> Scene:
    """Read a scene from a TOML file.

    Parameters
    ----------
    path
        The scene file.
    overrides
        ``section.key=value`` strings applied on top of the file.
    """
    return scene_from_dict(apply_overrides(read_toml(Path(path)), overrides))


def preset_names() -> list[str]:
    """Names of the bundled presets."""
    files = resources.files("foamsilo") / "presets"
    return sorted(p.name[:-5] for p in files.iterdir() if p.name.endswith(".toml"))


def preset_data(name: str) -> dict[str, Any]:
    """Return the raw TOML table of a preset."""
    names = preset_names()
    if name not in names:
        raise SceneError("preset", f"unknown preset {name!r}; allowed: {', '.join(names)}")
    text = (resources.files("foamsilo") / "presets" / f"{name}.toml").read_text("utf-8")
    return tomllib.loads(text)


def load_preset(name: str, overrides: list[str] | None = None) -> Scene:
    """Load a bundled preset, with optional overrides."""
    return scene_from_dict(apply_overrides(preset_data(name), overrides))


def is_scene_file(spec: str | Path) -> bool:
    """Whether ``spec`` names a file (not a preset): a ``.toml`` suffix or an existing path."""
    p = Path(spec)
    return p.suffix == ".toml" or p.exists()


def load_scene(spec: str | Path, overrides: list[str] | None = None) -> Scene:
    """Load a scene from a preset name or a TOML file path."""
    if is_scene_file(spec):
        return load_scene_file(Path(spec), overrides)
    return load_preset(str(spec), overrides)


def to_toml(data: dict[str, Any]) -> str:
    """Serialise a scene dict to TOML (None values dropped: TOML has no null)."""

    def clean(d: Any) -> Any:
        if isinstance(d, dict):
            return {k: clean(v) for k, v in d.items() if v is not None}
        if isinstance(d, tuple):
            return list(d)
        return d

    return tomli_w.dumps(clean(data))


def scene_digest(scene: Scene) -> str:
    """Stable hash of a scene's values (to tell whether a case matches it)."""
    return hashlib.sha256(json.dumps(scene.to_dict(), sort_keys=True).encode()).hexdigest()[:16]
