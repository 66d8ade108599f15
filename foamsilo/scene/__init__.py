"""The scene: a validated description of a silo discharge, in SI units.

A scene is read from a TOML file (or a named preset) and turned into a
:class:`Scene`.  Every field carries its unit, its allowed range and a
one-line description; loading rejects unknown keys, missing keys and
out-of-range values with a :class:`~foamsilo.errors.SceneError` that names
the field and what is allowed.

Modules: :mod:`~foamsilo.scene.model` (the dataclasses and derived values),
:mod:`~foamsilo.scene.schema` (field declaration, type and range checks),
:mod:`~foamsilo.scene.rules` (cross-field rules), :mod:`~foamsilo.scene.io`
(TOML files, presets, overrides), :mod:`~foamsilo.scene.reference` (the
Markdown reference).

Example
-------
>>> from foamsilo.scene import load_preset
>>> scene = load_preset("zhou-planar", overrides=["mesh.cells_across=16"])
>>> scene.cells_across
16
"""

from foamsilo.scene.io import (
    apply_overrides,
    format_override,
    is_scene_file,
    load_preset,
    load_scene,
    load_scene_file,
    parse_override,
    preset_data,
    preset_names,
    read_toml,
    scene_digest,
    scene_from_dict,
    to_toml,
)
from foamsilo.scene.model import (
    CELLS_ACROSS_MAX,
    GRAVITY,
    WEDGE_ANGLE_DEG,
    Air,
    Gas,
    Material,
    Mesh,
    Numerics,
    Representation,
    Run,
    Scene,
    Silo,
)
from foamsilo.scene.reference import reference_markdown

__all__ = [
    "CELLS_ACROSS_MAX",
    "GRAVITY",
    "WEDGE_ANGLE_DEG",
    "Air",
    "Gas",
    "Material",
    "Mesh",
    "Numerics",
    "Representation",
    "Run",
    "Scene",
    "Silo",
    "apply_overrides",
    "format_override",
    "is_scene_file",
    "load_preset",
    "load_scene",
    "load_scene_file",
    "parse_override",
    "preset_data",
    "preset_names",
    "read_toml",
    "reference_markdown",
    "scene_digest",
    "scene_from_dict",
    "to_toml",
]
