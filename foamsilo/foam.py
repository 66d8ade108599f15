"""OpenFOAM utilities called from Python, and small dictionary helpers.

Each utility has a snake_case wrapper that runs it in a case, keeps its log
as ``log.<utility>`` in the case, and raises :class:`~foamsilo.errors.FoamError`
(with the captured output) when it fails.
"""

from __future__ import annotations

import re
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from foamsilo.errors import FoamError
from foamsilo.toolchain import OpenFOAM

FOAM_BANNER = (
    "/*--------------------------------*- C++ -*----------------------------------*\\\n"
    "  written by foamsilo\n"
    "\\*---------------------------------------------------------------------------*/\n"
)


def foam_header(cls: str, obj: str, location: str | None = None) -> str:
    """Return an OpenFOAM ``FoamFile`` header."""
    loc = f'    location    "{location}";\n' if location else ""
    return (
        f"{FOAM_BANNER}FoamFile\n{{\n    version     2.0;\n    format      ascii;\n"
        f"    class       {cls};\n{loc}    object      {obj};\n}}\n\n"
    )


def run_utility(
    of: OpenFOAM,
    case: Path,
    utility: str,
    *args: str,
    log_name: str | None = None,
    timeout: float | None = None,
) -> str:
    """Run an OpenFOAM utility in ``case`` and return its output.

    Raises
    ------
    FoamError
        On a non-zero exit status or a ``FOAM FATAL`` message.
    """
    cmd = [utility, *args, "-case", str(case)]
    try:
        proc = subprocess.run(
            cmd, env=of.runtime_env(), capture_output=True, text=True, timeout=timeout
        )
    except FileNotFoundError:
        raise FoamError(" ".join(cmd), 127, f"{utility}: command not found", case) from None
    except subprocess.TimeoutExpired as exc:
        out = (exc.stdout or b"").decode() if isinstance(exc.stdout, bytes) else exc.stdout or ""
        raise FoamError(" ".join(cmd), 124, f"timed out after {timeout} s\n{out}", case) from None
    output = proc.stdout + proc.stderr
    (case / f"log.{log_name or utility}").write_text(output)
    if proc.returncode != 0 or "FOAM FATAL" in output:
        raise FoamError(" ".join(cmd), proc.returncode or 1, output, case)
    return output


def gmsh_to_foam(of: OpenFOAM, case: Path, msh: Path) -> None:
    """Convert a gmsh ``.msh`` (format 2.2) into ``constant/polyMesh``."""
    run_utility(of, case, "gmshToFoam", str(msh))


def set_alpha_field(of: OpenFOAM, case: Path) -> None:
    """Initialise the volume fraction from ``system/setAlphaFieldDict`` (cut cells)."""
    run_utility(of, case, "setAlphaField")


def set_patch_types(case: Path, types: dict[str, str]) -> None:
    """Set the ``type`` of named patches in ``constant/polyMesh/boundary``.

    gmshToFoam makes every patch a ``patch``; walls, empty and wedge patches
    need their own types for the boundary conditions to apply.
    """
    path = case / "constant" / "polyMesh" / "boundary"
    text = path.read_text()
    for name, typ in types.items():
        pattern = re.compile(r"(\n\s*" + re.escape(name) + r"\s*\{[^}]*?\btype\s+)\w+;")
        text, n = pattern.subn(r"\g<1>" + typ + ";", text, count=1)
        if n != 1:
            raise FoamError("set_patch_types", 1, f"patch {name!r} not found in {path}", case)
        # physicalType would otherwise keep saying 'patch'
        text = re.sub(
            r"(\n\s*" + re.escape(name) + r"\s*\{[^}]*?)\n\s*physicalType\s+\w+;",
            r"\1",
            text,
            count=1,
        )
    path.write_text(text)


def patch_names(case: Path) -> list[str]:
    """Names of the patches in ``constant/polyMesh/boundary``."""
    text = (case / "constant" / "polyMesh" / "boundary").read_text()
    return re.findall(r"\n\s*(\w+)\s*\n\s*\{", text)


@dataclass
class CheckMeshResult:
    """Verdict and figures of ``checkMesh``.

    Attributes
    ----------
    ok
        True when checkMesh printed ``Mesh OK.``.
    cells, faces, points
        Counts.
    cell_types
        Count per cell type (``hexahedra``, ``prisms``, ...).
    max_non_orthogonality
        Degrees.
    max_skewness, max_aspect_ratio
        As checkMesh reports them.
    failed_checks
        The lines of the checks that failed.
    """

    ok: bool
    cells: int
    faces: int
    points: int
    cell_types: dict[str, int] = field(default_factory=dict)
    max_non_orthogonality: float = 0.0
    max_skewness: float = 0.0
    max_aspect_ratio: float = 0.0
    failed_checks: list[str] = field(default_factory=list)

    def as_dict(self) -> dict[str, object]:
        """JSON-friendly form."""
        return dict(self.__dict__)


def _num(pattern: str, text: str, default: float = 0.0) -> float:
    m = re.search(pattern, text, re.M)
    return float(m.group(1)) if m else default


def parse_check_mesh(output: str) -> CheckMeshResult:
    """Parse the output of ``checkMesh``."""
    types = {
        k: int(v)
        for k, v in re.findall(
            r"^\s+(hexahedra|prisms|wedges|pyramids|tet wedges|tetrahedra|polyhedra):\s+(\d+)",
            output,
            re.M,
        )
        if int(v) > 0
    }
    failed = [ln.strip() for ln in output.splitlines() if ln.strip().startswith("***")]
    return CheckMeshResult(
        ok=bool(re.search(r"^Mesh OK\.", output, re.M)),
        cells=int(_num(r"^\s+cells:\s+(\d+)", output)),
        faces=int(_num(r"^\s+faces:\s+(\d+)", output)),
        points=int(_num(r"^\s+points:\s+(\d+)", output)),
        cell_types=types,
        max_non_orthogonality=_num(r"non-orthogonality Max:\s+([-\d.eE+]+)", output),
        max_skewness=_num(r"Max skewness = ([-\d.eE+]+)", output),
        max_aspect_ratio=_num(r"Max aspect ratio = ([-\d.eE+]+)", output),
        failed_checks=failed,
    )


def check_mesh(of: OpenFOAM, case: Path) -> CheckMeshResult:
    """Run ``checkMesh`` and return its verdict and figures.

    A mesh that fails its checks is returned (``ok`` False), not raised:
    the caller decides.
    """
    return parse_check_mesh(run_utility(of, case, "checkMesh"))


def read_internal_field(path: Path) -> np.ndarray:
    """Cell values of an ASCII OpenFOAM field file (uniform or nonuniform).

    Returns
    -------
    numpy.ndarray
        Shape (n,) for scalars, (n, 3) for vectors; a uniform field gives
        one row.
    """
    text = Path(path).read_text()
    m = re.search(r"internalField\s+nonuniform\s+List<(\w+)>\s*(\d+)\s*\(", text)
    if not m:
        u = re.search(r"internalField\s+uniform\s+([^;]+);", text)
        if not u:
            raise ValueError(f"{path}: no ASCII internalField (binary file?)")
        return np.array(u.group(1).strip("() ").split(), dtype=float)
    n = int(m.group(2))
    body = text[m.end() :]
    if m.group(1) == "vector":
        vals = re.findall(r"\(([^()]*)\)", body[: body.index("\n)")])[:n]
        return np.array([v.split() for v in vals], dtype=float)
    return np.array(body[: body.index(")")].split()[:n], dtype=float)


def write_internal_field(path: Path, values: np.ndarray) -> None:
    """Replace the ``internalField`` of an ASCII field file with ``values``."""
    values = np.asarray(values, dtype=float)
    if values.ndim == 1:
        items = "\n".join(f"{v:.17g}" for v in values)
        kind = "scalar"
    else:
        items = "\n".join(f"({v[0]:.17g} {v[1]:.17g} {v[2]:.17g})" for v in values)
        kind = "vector"
    text = Path(path).read_text()
    new = f"internalField   nonuniform List<{kind}>\n{len(values)}\n(\n{items}\n)\n;"
    text, n = re.subn(
        r"internalField\s+(uniform\s+[^;]+|nonuniform\s+List<\w+>\s*\d+\s*\((?:[^;])*?\)\s*);",
        lambda _m: new,
        text,
        count=1,
        flags=re.S,
    )
    if n != 1:
        raise ValueError(f"{path}: internalField not found")
    Path(path).write_text(text)


_VOLUME_DICT = """FoamFile { version 2.0; format ascii; class dictionary; object foamsiloVolume; }
functions
{
    foamsiloVolume
    {
        type            volFieldValue;
        libs            ("libfieldFunctionObjects.so");
        log             true;
        writeFields     false;
        writeToFile     false;
        regionType      all;
        operation       volIntegrate;
        fields          (alpha.granular);
    }
}
"""


def granular_volume(of: OpenFOAM, case: Path, time: str = "0") -> float:
    """Volume of grains in the mesh, the integral of alpha.granular [m^3].

    Runs ``postProcess`` with a volIntegrate function object at ``time``.
    """
    d = case / "system" / "foamsiloVolumeDict"
    d.write_text(_VOLUME_DICT)
    try:
        out = run_utility(
            of, case, "postProcess", "-dict", str(d), "-time", time,
            "-fields", "(alpha.granular)", log_name="granularVolume",
        )  # fmt: skip
    finally:
        d.unlink(missing_ok=True)
    m = re.search(r"volIntegrate\(\S*\) of alpha\.granular = (\S+)", out)
    if not m:
        raise FoamError("postProcess volIntegrate", 0, out, case)
    return float(m.group(1))
