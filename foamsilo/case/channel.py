"""Periodic channels with exact steady flows: the solver's verification cases.

Two geometries, each one line of cells, periodic along the flow:

* ``plane``: a layer of depth h on a plane inclined at theta (planar). Its
  steady uniform flow has exact solutions (:mod:`foamsilo.analytic.exact`):
  the mu(I) (Bagnold) profile and, where the viscosity cap holds
  throughout, the Newtonian film.
* ``pipe``: a vertical pipe of radius R full of grains (an axisymmetric
  wedge), driven by gravity along its axis; at the viscosity cap the flow is
  Hagen-Poiseuille's, which checks the hoop terms of the axisymmetric
  viscous stress. The pipe is closed: its pressure level is fixed at a
  reference cell (``reference_pressure``), high enough for the mu(I)
  viscosity to exceed the cap everywhere.

A channel case is an ordinary foamsilo case (written whole with its scene,
locked and run by the one pipeline). For the plane:

* gravity is tilted into the plane's frame, g = g (sin theta, -cos theta, 0);
* the slope's share of gravity, which ``p_rgh = p - rho g.(C - hRef)`` turns
  into a pressure growing along x, is carried by a jump of p_rgh across the
  periodic pair: rho g sin(theta) times the length, row by row (a uniform
  layer keeps its rows);
* the column is centred on x = 0, so g.C has no slope part at the cell
  centres, and ``p`` there is the physical pressure the rheology sees;
* the top is a slip lid at a fixed static pressure: the silo's
  total-pressure atmosphere would lower the pressure under the moving layer
  by 0.5 rho_air |U|^2 and with it the friction of the top rows.
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np

from foamsilo.case.create import Case, create_case
from foamsilo.case.templates import render_template, template_context
from foamsilo.errors import MeshError, SceneError
from foamsilo.foam import block_mesh, check_mesh, edit_dict, run_utility
from foamsilo.mesh import MeshResult
from foamsilo.scene import WEDGE_ANGLE_DEG, Scene
from foamsilo.toolchain import OpenFOAM

#: Metadata key of a channel case (what ``rebuild_mesh`` rebuilds it from)
CHANNEL_KEY = "channel"


@dataclass(frozen=True)
class Channel:
    """A layer on an inclined plane (``plane``) or a vertical pipe (``pipe``).

    Attributes
    ----------
    tan_theta
        Slope of the plane (a pipe is vertical: 0).
    depth
        Depth h of the layer, normal to the plane, or the pipe's radius R [m].
    cells
        Cells across the layer or the radius (of equal size).
    air_depth
        Depth of the air above the layer [m] (rounded to whole rows; a pipe
        is full of grains: 0).
    length
        Length of the periodic line along the flow [m] (one cell: the flow
        is uniform; it sets the Courant number along the flow).
    geometry
        ``plane`` or ``pipe``.
    reference_pressure
        Pressure at the reference cell of the closed pipe [Pa].
    """

    tan_theta: float
    depth: float
    cells: int
    air_depth: float
    length: float
    geometry: Literal["plane", "pipe"] = "plane"
    reference_pressure: float = 0.0

    def __post_init__(self) -> None:
        pipe = self.geometry == "pipe"
        checks = [
            ("geometry", self.geometry in ("plane", "pipe"), "plane, pipe"),
            ("tan_theta", self.tan_theta == 0 if pipe else self.tan_theta > 0,
             "0 (a vertical pipe)" if pipe else "> 0"),
            ("depth", self.depth > 0, "> 0"),
            ("cells", self.cells >= 2, ">= 2"),
            ("air_depth", self.air_depth == 0 if pipe else self.air_depth >= 0,
             "0 (a full pipe)" if pipe else ">= 0"),
            ("length", self.length > 0, "> 0"),
            ("reference_pressure", self.reference_pressure > 0 if pipe else True,
             "> 0 (a closed pipe)"),
        ]  # fmt: skip
        for name, ok, allowed in checks:
            if not ok:
                raise SceneError(
                    f"channel.{name}", f"got {getattr(self, name)!r}; allowed: {allowed}"
                )

    @property
    def theta(self) -> float:
        """Inclination [rad]."""
        return math.atan(self.tan_theta)

    @property
    def row_height(self) -> float:
        """Height of a row of cells [m]."""
        return self.depth / self.cells

    @property
    def rows(self) -> int:
        """Rows of cells, layer and air."""
        return self.cells + round(self.air_depth / self.row_height)

    @property
    def height(self) -> float:
        """Height of the column [m]: the layer's surface lies on a row boundary."""
        return self.rows * self.row_height

    def row_centres(self) -> np.ndarray:
        """Heights of the cell centres above the base [m]."""
        return (np.arange(self.rows) + 0.5) * self.row_height

    def as_dict(self) -> dict[str, Any]:
        """JSON-friendly form (kept in the case's metadata)."""
        return asdict(self)


def _check_scene(scene: Scene, channel: Channel) -> None:
    want = "planar" if channel.geometry == "plane" else "axisymmetric"
    if scene.representation != want:
        raise SceneError(
            "mesh.representation",
            f"got {scene.representation!r}; allowed: {want} (a {channel.geometry} channel)",
        )
    if scene.gas_coupled:
        raise SceneError("gas.mode", f"got {scene.gas.mode!r}; allowed: open-top (a dry layer)")
    if (
        channel.geometry == "plane"
        and abs(scene.silo.fill_height - channel.depth) > 1e-12 * channel.depth
    ):
        raise SceneError(
            "silo.fill_height",
            f"got {scene.silo.fill_height!r} m; must equal the layer depth {channel.depth!r} m",
        )
    if channel.geometry == "pipe" and scene.silo.fill_height < channel.length / 2:
        raise SceneError(
            "silo.fill_height",
            f"got {scene.silo.fill_height!r} m; allowed: >= {channel.length / 2!r} m (a full pipe)",
        )


def mesh_channel(channel: Channel, scene: Scene, case: Path, of: OpenFOAM) -> MeshResult:
    """Mesh the column and set its periodic fields, tilted gravity and lid.

    Raises
    ------
    MeshError
        checkMesh fails the column.
    """
    t0 = time.perf_counter()
    depth = template_context(scene)["mid_depth"] * 2  # the planar mesh's thickness
    wedge_tan = math.tan(math.radians(WEDGE_ANGLE_DEG) / 2)
    render_template("system/blockMeshDict", scene, case, channel=channel, depth=depth,
                    wedge_tan=wedge_tan)  # fmt: skip
    block_mesh(of, case)
    t1 = time.perf_counter()
    check = check_mesh(of, case)
    if not check.ok:
        raise MeshError("checkMesh failed: " + "; ".join(check.failed_checks))
    # cell centres and volumes, for the reduction (0/C, 0/V; the solver reads neither)
    for fo in ("writeCellCentres", "writeCellVolumes"):
        run_utility(of, case, "postProcess", "-func", fo, "-time", "0", log_name=fo)
    g, rho_g = scene.gravity, scene.material.density
    if channel.geometry == "plane":
        rho = np.where(channel.row_centres() < channel.depth, rho_g, scene.void_density)
        # p_rgh = p - rho g_x x falls by rho g sin(theta) L over one period
        jumps = -rho * g * math.sin(channel.theta) * channel.length
        jump = f"nonuniform List<scalar> {len(jumps)}({' '.join(f'{j:.12g}' for j in jumps)})"
    else:
        # p_rgh = p + rho g y rises by rho g L over one period (gravity along -y)
        jump = f"uniform {rho_g * g * channel.length:.12g}"
    cyclic = {"type": "cyclic"}
    gone = ["orifice"] if channel.geometry == "plane" else ["orifice", "atmosphere"]
    for name in ("U", "alpha.granular"):
        with edit_dict(case / "0" / name) as f:
            bf = f["boundaryField"]
            bf["upstream"], bf["downstream"] = cyclic, cyclic
            if channel.geometry == "plane" and name == "U":
                bf["atmosphere"] = {"type": "slip"}
            for patch in gone:
                del bf[patch]
    with edit_dict(case / "0" / "p_rgh") as f:
        bf = f["boundaryField"]
        bf["upstream"] = {"type": "fixedJump", "patchType": "cyclic", "jump": jump,
                          "value": "uniform 0"}  # fmt: skip
        bf["downstream"] = {"type": "fixedJump", "patchType": "cyclic", "value": "uniform 0"}
        if channel.geometry == "plane":
            bf["atmosphere"] = {"type": "prghPressure", "p": "uniform 0", "value": "uniform 0"}
        for patch in gone:
            del bf[patch]
    if channel.geometry == "plane":
        with edit_dict(case / "constant" / "g") as f:
            f["value"] = (
                f"({g * math.sin(channel.theta):.12g} {-g * math.cos(channel.theta):.12g} 0)"
            )
    else:
        with edit_dict(case / "system" / "fvSolution") as f:
            f["PIMPLE"]["pRefCell"] = 0
            f["PIMPLE"]["pRefValue"] = channel.reference_pressure
    with edit_dict(case / "system" / "controlDict") as f:
        f["functions"] = {}  # the silo's orifice flux and probes have no place here
    t2 = time.perf_counter()
    return MeshResult(
        scene.representation, check.cells, check, case / "system" / "blockMeshDict", t2 - t0,
        timings={"blockMesh": t1 - t0, "fields": t2 - t1},
    )  # fmt: skip


def create_channel_case(
    scene: Scene, channel: Channel, case_dir: Path, of: OpenFOAM, *, overwrite: bool = False
) -> Case:
    """Write a channel case: the scene's material, air and run, the channel's mesh.

    The scene must be dry, planar for a plane (its fill height the layer's
    depth: grains below y = h, at rest) and axisymmetric for a pipe (filled
    above the pipe's top).

    Raises
    ------
    SceneError
        The scene does not fit the channel.
    """
    _check_scene(scene, channel)
    return create_case(
        scene,
        case_dir,
        of,
        overwrite=overwrite,
        mesher=lambda sc, case, of_: mesh_channel(channel, sc, case, of_),
        metadata={CHANNEL_KEY: channel.as_dict()},
    )
