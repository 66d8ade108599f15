"""The package's shape: each stage imports only the ones below it; no regex on OpenFOAM files.

The layers follow the data flow (docs/architecture.md): a module may import
modules of its own layer or of a lower one, never of a higher one, at the
top of the file or inside a function.
"""

from __future__ import annotations

import ast
import re
import sys
from pathlib import Path

import pytest

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "foamsilo"

#: The stages, lowest first (a module's layer is that of its top-level name)
LAYERS: list[set[str]] = [
    {"errors", "process", "resources", "jsonio", "plots"},
    {"toolchain", "scene", "analytic", "hopper"},
    {"foam", "solver"},
    {"mesh"},
    {"case"},
    {"run"},
    {"post"},
    {"compare"},
    {"summary"},
    {"report"},
    {"pipeline"},
    {"slurm"},
    {"sweep", "studies"},
    {"cli", "__main__"},
]
LAYER = {name: k for k, names in enumerate(LAYERS) for name in names}

#: The only modules that use regular expressions, and on what (none on a dictionary)
REGEX_USERS = {
    "run/monitor.py": "the solver's log lines",
    "foam/utilities.py": "the logs of checkMesh and postProcess",
    "toolchain.py": "Debian's etc/bashrc (a shell script)",
    "scene/rules.py": "the characters of a scene name",
    "case/create.py": "the characters of a case path",
}


def _stage(module: str) -> str | None:
    parts = module.split(".")
    if parts[0] != "foamsilo" or len(parts) < 2:
        return None
    return parts[1]


def _imports(path: Path) -> list[str]:
    tree = ast.parse(path.read_text())
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            out.append(node.module)
            out += [
                f"{node.module}.{a.name}"
                for a in node.names
                if node.module == "foamsilo" and a.name != "__version__"
            ]
    return out


def modules() -> list[Path]:
    return sorted(p for p in PACKAGE.rglob("*.py") if "__pycache__" not in p.parts)


@pytest.mark.parametrize("path", modules(), ids=lambda p: str(p.relative_to(PACKAGE)))
def test_a_stage_imports_only_the_stages_below_it(path):
    rel = path.relative_to(PACKAGE)
    own = rel.parts[0].removesuffix(".py")
    if own == "__init__":
        return
    assert own in LAYER, f"{rel}: add its stage to LAYERS (and to docs/architecture.md)"
    for module in _imports(path):
        stage = _stage(module)
        if stage is None or stage == own:
            continue
        assert stage in LAYER, f"{rel} imports foamsilo.{stage}, which has no layer"
        assert LAYER[stage] <= LAYER[own], (
            f"{rel} (stage {own!r}) imports {module}, a stage above it ({stage!r})"
        )


def test_no_regular_expression_touches_an_openfoam_dictionary():
    pattern = re.compile(r"\bre\.(sub|subn|search|match|fullmatch|findall|finditer|compile)\(")
    users = {str(p.relative_to(PACKAGE)) for p in modules() if pattern.search(p.read_text())}
    unexpected = users - set(REGEX_USERS)
    assert not unexpected, (
        f"{sorted(unexpected)} use regular expressions: OpenFOAM files go through "
        "foamsilo.foam.dictionary (PyFoam's parser)"
    )


def test_every_subpackage_is_shipped():
    listed = set(
        tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"]
    )
    found = {
        ".".join(p.parent.relative_to(ROOT).parts)
        for p in PACKAGE.rglob("__init__.py")
        if "__pycache__" not in p.parts
    }
    assert found <= listed, f"not in pyproject.toml's packages: {sorted(found - listed)}"
    assert {"foamsilo.templates", "foamsilo.solver_src"} <= listed


def test_no_machine_name_or_measured_finding_in_report_code():
    """Reports are written from data: no machine name, no 'Findings' section in code."""
    for path in modules():
        text = path.read_text()
        for words in ("EPYC", "## Findings", "2-core AMD"):
            assert words not in text, f"{path.relative_to(PACKAGE)} writes {words!r} itself"
