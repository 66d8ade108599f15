"""Files foamsilo ships with: the case templates, the solver sources, the presets.

``templates/`` and ``solver_src/`` sit at the top of the repository (where a
reader of the project looks for them) and are installed inside the package
as ``foamsilo.templates`` and ``foamsilo.solver_src`` (``pyproject.toml``
maps them), so an editable checkout and a plain ``pip install .`` find them
the same way: through the import system, never through the repository root.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

from foamsilo.errors import ToolchainError


def data_dir(name: str) -> Path:
    """Directory of the shipped data package ``foamsilo.<name>``.

    Raises
    ------
    ToolchainError
        The installation lacks it (a broken install).
    """
    spec = importlib.util.find_spec(f"foamsilo.{name}")
    locations = list(spec.submodule_search_locations or []) if spec else []
    for loc in locations:
        if Path(loc).is_dir():
            return Path(loc)
    raise ToolchainError(
        f"foamsilo.{name}",
        "not found in the installed package",
        "pip install --force-reinstall foamsilo (or pip install -e . in a checkout)",
    )


def templates_dir() -> Path:
    """Return the jinja2 templates of the case dictionaries (``templates/``)."""
    return data_dir("templates")


def solver_source_dir() -> Path:
    """Return the solver sources (``solver_src/``: siloFoam and the mu(I) library)."""
    src = data_dir("solver_src")
    if not (src / "Allwmake").is_file():
        raise ToolchainError(
            "solver sources", f"{src} holds no Allwmake", "pip install --force-reinstall foamsilo"
        )
    return src
