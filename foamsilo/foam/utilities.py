"""OpenFOAM utilities called from Python, one snake_case function each.

Each runs its utility in a case through :func:`foamsilo.process.run_command`,
keeps its log as ``log.<utility>`` in the case, and raises
:class:`~foamsilo.errors.FoamError` (with the captured output) when it fails.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from foamsilo.errors import FoamError
from foamsilo.process import run_command
from foamsilo.toolchain import OpenFOAM


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
    KeyboardInterrupt
        Ctrl-C reached the utility.
    """
    argv = [utility, *args, "-case", str(case)]
    try:
        res = run_command(argv, env=of.runtime_env(), timeout=timeout)
    except FileNotFoundError:
        raise FoamError(" ".join(argv), 127, f"{utility}: command not found", case) from None
    (Path(case) / f"log.{log_name or utility}").write_text(res.output)
    if res.returncode != 0 or "FOAM FATAL" in res.output:
        raise FoamError(" ".join(argv), res.returncode or 1, res.output, case)
    return res.output


def gmsh_to_foam(of: OpenFOAM, case: Path, msh: Path) -> None:
    """Convert a gmsh ``.msh`` (format 2.2) into ``constant/polyMesh``."""
    run_utility(of, case, "gmshToFoam", str(msh))


def block_mesh(of: OpenFOAM, case: Path) -> None:
    """Make ``constant/polyMesh`` from ``system/blockMeshDict``."""
    run_utility(of, case, "blockMesh")


def set_alpha_field(of: OpenFOAM, case: Path) -> None:
    """Initialise the volume fraction from ``system/setAlphaFieldDict`` (cut cells)."""
    run_utility(of, case, "setAlphaField")


def topo_set(of: OpenFOAM, case: Path) -> None:
    """Make the sets and zones of ``system/topoSetDict``."""
    run_utility(of, case, "topoSet")


def decompose_par(of: OpenFOAM, case: Path) -> None:
    """Split the latest time over the ranks of ``system/decomposeParDict``."""
    run_utility(of, case, "decomposePar", "-force", "-latestTime", log_name="decomposePar")


def reconstruct_par(of: OpenFOAM, case: Path, *, latest_only: bool = False) -> None:
    """Merge the processor directories back into time directories."""
    args = ["-latestTime"] if latest_only else ["-newTimes"]
    run_utility(of, case, "reconstructPar", *args, log_name="reconstructPar")


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
    """Parse the log (not a dictionary) ``checkMesh`` prints."""
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
    d = Path(case) / "system" / "foamsiloVolumeDict"
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
