"""OpenFOAM dictionaries and fields, read and edited through PyFoam's parser.

Every dictionary foamsilo reads or changes after writing it (``controlDict``,
``polyMesh/boundary``, a field's ``internalField``) goes through
:class:`PyFoam.RunDictionary.ParsedParameterFile.ParsedParameterFile`; no
regular expression touches an OpenFOAM file. Fields are read in either
format OpenFOAM writes (``writeFormat ascii`` or ``binary``).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from foamsilo.errors import FoamsiloError

#: Components of each field class OpenFOAM writes
_COMPONENTS = {"scalar": 1, "vector": 3, "symmTensor": 6, "tensor": 9}


def _parse(path: Path, **kw: Any) -> Any:
    from PyFoam.RunDictionary.ParsedParameterFile import ParsedParameterFile

    path = Path(path)
    if not path.is_file():
        raise FoamsiloError(f"{path}: no such OpenFOAM file")
    try:
        return ParsedParameterFile(str(path), **kw)
    except Exception as exc:  # PyFoam raises its own parse errors, and IndexError on junk
        raise FoamsiloError(f"{path}: not a readable OpenFOAM dictionary ({exc})") from exc


def read_dict(path: Path) -> Any:
    """Parse a dictionary file; returns PyFoam's mapping-like object (``f["endTime"]``)."""
    return _parse(path)


def dict_value(path: Path, key: str, default: Any = None) -> Any:
    """One top-level entry of a dictionary (``default`` when it is absent)."""
    content = read_dict(path).content
    return content[key] if key in content else default


@contextmanager
def edit_dict(path: Path) -> Iterator[Any]:
    """Edit a dictionary in place: ``with edit_dict(p) as d: d["endTime"] = 1``.

    The file is rewritten whole (a temporary file, then a rename) when the
    block ends without an exception.
    """
    import os

    f = _parse(path)
    yield f.content
    tmp = Path(path).with_name(Path(path).name + ".tmp")
    tmp.write_text(str(f))
    os.replace(tmp, path)


def set_patch_types(case: Path, types: dict[str, str]) -> None:
    """Set the ``type`` of named patches in ``constant/polyMesh/boundary``.

    gmshToFoam makes every patch a ``patch``; walls, empty and wedge patches
    need their own types for the boundary conditions to apply. A
    ``physicalType`` entry, which would keep saying ``patch``, is removed.

    Raises
    ------
    FoamsiloError
        A named patch is not in the mesh (the message lists those that are).
    """
    import os

    from PyFoam.RunDictionary.ParsedParameterFile import ParsedBoundaryDict

    path = Path(case) / "constant" / "polyMesh" / "boundary"
    if not path.is_file():
        raise FoamsiloError(f"{path}: no such file (has the mesh been converted?)")
    # gmshToFoam writes the header as binary but the patch list in ASCII
    b = ParsedBoundaryDict(str(path), treatBinaryAsASCII=True)
    for name, typ in types.items():
        if name not in b.content:
            raise FoamsiloError(
                f"patch {name!r} not found in {path}; patches: {', '.join(b.content)}"
            )
        patch = b.content[name]
        patch["type"] = typ
        if "physicalType" in patch:
            del patch["physicalType"]
    b.header["format"] = "ascii"  # the file is text through and through
    tmp = path.with_name("boundary.tmp")
    tmp.write_text(str(b))
    os.replace(tmp, path)


def patch_types(case: Path) -> dict[str, str]:
    """Patch name -> type of ``constant/polyMesh/boundary``."""
    from PyFoam.RunDictionary.ParsedParameterFile import ParsedBoundaryDict

    path = Path(case) / "constant" / "polyMesh" / "boundary"
    if not path.is_file():
        raise FoamsiloError(f"{path}: no such file")
    b = ParsedBoundaryDict(str(path), treatBinaryAsASCII=True)
    return {name: str(p["type"]) for name, p in b.content.items()}


def _decode(field: Any, path: Path) -> np.ndarray:
    """Values of a parsed ``internalField`` (uniform, ASCII or binary list)."""
    from PyFoam.Basics.DataStructures import BinaryList, Vector

    val = field.val
    kind = str(field.name or "").removeprefix("List<").removesuffix(">")
    if field.uniform:
        if isinstance(val, Vector) or isinstance(val, (list, tuple)):
            return np.array([float(x) for x in val], dtype=float)
        return np.array([float(val)])
    if isinstance(val, BinaryList):
        ncomp = _COMPONENTS.get(kind)
        if ncomp is None:
            raise FoamsiloError(f"{path}: binary internalField of {field.name!r} not supported")
        raw = val.data.encode("latin-1")  # PyFoam keeps the bytes as a latin-1 string
        expected = val.length * ncomp * 8
        if len(raw) < expected:
            raise FoamsiloError(
                f"{path}: binary internalField holds {len(raw)} bytes, {val.length} "
                f"{kind} values need {expected} (a truncated file?)"
            )
        data = np.frombuffer(raw[:expected], dtype="<f8")
        return data.copy() if ncomp == 1 else data.reshape(val.length, ncomp).copy()
    rows = [
        [float(x) for x in v] if isinstance(v, (Vector, list, tuple)) else float(v) for v in val
    ]
    return np.array(rows, dtype=float)


def read_internal_field(path: Path) -> np.ndarray:
    """Cell values of an OpenFOAM field file, ASCII or binary, uniform or not.

    Returns
    -------
    numpy.ndarray
        Shape (n,) for scalars, (n, k) for k-component fields; a uniform
        field gives one value (one row).
    """
    path = Path(path)
    f = _parse(path, binaryMode=True)
    if "internalField" not in f.content:
        raise FoamsiloError(f"{path}: no internalField (not a field file?)")
    return _decode(f.content["internalField"], path)


def write_internal_field(path: Path, values: np.ndarray) -> None:
    """Replace the ``internalField`` of a field file with ``values`` (written ASCII).

    Raises
    ------
    FoamsiloError
        The file holds other binary lists (a solver-written binary field):
        write into the ASCII fields of ``0/`` instead.
    """
    import os

    from PyFoam.Basics.DataStructures import Field, UnparsedList

    path = Path(path)
    f = _parse(path)
    if str(f.header.get("format", "ascii")) != "ascii":
        raise FoamsiloError(f"{path}: a binary field file; only ASCII ones are edited")
    values = np.asarray(values, dtype=float)
    # round-trip precision: PyFoam's own number format keeps 6 digits
    if values.ndim == 1:
        kind, items = "scalar", [f"{v:.17g}" for v in values]
    elif values.shape[1] == 3:
        kind, items = "vector", [f"({x:.17g} {y:.17g} {z:.17g})" for x, y, z in values]
    else:
        raise FoamsiloError(f"{path}: only scalar and vector fields are written")
    data = UnparsedList(len(items), "\n" + "\n".join(items) + "\n")
    f.content["internalField"] = Field(data, name=f"List<{kind}>")
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(str(f))
    os.replace(tmp, path)
