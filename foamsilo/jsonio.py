"""JSON at the edges: strict (no NaN), with the reason for every null it had to make.

JSON has no NaN or Infinity; Python's ``json`` writes them anyway, and
readers choke. :func:`dumps` writes numbers that are not finite as ``null``
and, when it had to, adds ``"null_reasons"``: the path of each such value
and why it is null.
"""

from __future__ import annotations

import dataclasses
import enum
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

#: Why a value became null
NOT_FINITE = "not a finite number (NaN or infinity)"


def jsonable(obj: Any, nulls: dict[str, str] | None = None, path: str = "") -> Any:
    """Plain JSON types for ``obj``; non-finite numbers become None, noted in ``nulls``."""
    if isinstance(obj, dict):
        return {
            str(k): jsonable(v, nulls, f"{path}.{k}" if path else str(k)) for k, v in obj.items()
        }
    if isinstance(obj, (list, tuple)):
        return [jsonable(v, nulls, f"{path}[{i}]") for i, v in enumerate(obj)]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist(), nulls, path)
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        x = float(obj)
        if not math.isfinite(x):
            if nulls is not None:
                nulls[path or "."] = NOT_FINITE
            return None
        return x
    if isinstance(obj, Path):
        return str(obj)
    if isinstance(obj, enum.Enum):
        return obj.value
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return jsonable(dataclasses.asdict(obj), nulls, path)
    if obj is None or isinstance(obj, str):
        return obj
    return str(obj)


def dumps(obj: Any, indent: int | None = 2) -> str:
    """Strict JSON text of ``obj`` (see the module docstring)."""
    nulls: dict[str, str] = {}
    clean = jsonable(obj, nulls)
    if nulls and isinstance(clean, dict):
        clean.setdefault("null_reasons", {}).update(nulls)
    return json.dumps(clean, indent=indent, allow_nan=False)
