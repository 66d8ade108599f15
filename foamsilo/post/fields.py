"""Field output of a case, read with pyvista's OpenFOAM reader.

:class:`CaseFields` opens a case (serial, or decomposed when only the
processor directories hold results) and reduces its written time directories
to what users look at besides Q(t): where the free surface is, the velocity
across the silo at a given height (Venier et al. Fig. 3: y = 0.15 H), which
part of the grains is stagnant (viscosity at the cap), and mid-plane pictures
of granular pressure, volume fraction, speed and log10 viscosity (Venier
Fig. 6), rendered off-screen.

Geometry conventions: y is up, the silo floor is y = 0. Planar silos span
0 <= x <= L (mid-depth z = depth/2); cylinders and hoppers have their axis on
x = z = 0 (the wedge lies around the z = 0 plane); rectangular 3D boxes span
0 <= x <= L.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from foamsilo.case import SCENE_FILE
from foamsilo.errors import FoamsiloError
from foamsilo.scene import Scene, load_scene_file

#: Cells whose granular viscosity is within this fraction of the cap are stagnant
CAP_FRACTION = 0.99
#: Grains slower than this fraction of the fastest are drawn as the stagnant zone
STAGNANT_SPEED = 0.02
#: Volume fraction that marks the free surface
SURFACE_ALPHA = 0.5
ALPHA = "alpha.granular"
#: How a case's fields are read: decomposed when only processor*/ hold results
CASE_TYPES = ("auto", "reconstructed", "decomposed")


def _integrate(y: np.ndarray, x: np.ndarray) -> float:
    """Trapezoidal rule (numpy's is named differently across 1.x and 2.x)."""
    return float(np.sum((y[1:] + y[:-1]) * np.diff(x)) / 2) if len(x) > 1 else math.nan


class CaseFields:
    """Written fields of a foamsilo case.

    Parameters
    ----------
    case
        A case directory written by ``foamsilo new`` / ``foamsilo run``.
    case_type
        ``auto`` (the processor directories when only they hold results),
        ``reconstructed`` or ``decomposed``.

    Raises
    ------
    FoamsiloError
        The directory is not a case, or holds no written time.
    """

    def __init__(self, case: Path, case_type: str = "auto") -> None:
        import pyvista as pv

        self.case = Path(case).resolve()
        foam = self.case / "case.foam"
        if not foam.exists() or not (self.case / SCENE_FILE).exists():
            raise FoamsiloError(f"{self.case} is not a foamsilo case (no case.foam/scene.toml)")
        if case_type not in CASE_TYPES:
            raise FoamsiloError(
                f"case_type {case_type!r}: allowed: " + ", ".join(map(repr, CASE_TYPES))
            )
        self.scene: Scene = load_scene_file(self.case / SCENE_FILE)
        self._reader = pv.POpenFOAMReader(str(foam))
        if case_type == "auto":
            serial = [t for t in self._reader.time_values if t > 0]
            if not serial and (self.case / "processor0").is_dir():
                case_type = "decomposed"
            else:
                case_type = "reconstructed"
        if case_type == "decomposed" and not (self.case / "processor0").is_dir():
            raise FoamsiloError(f"{self.case}: case_type 'decomposed' but no processor0/")
        self._reader.case_type = case_type
        self._reader.cell_to_point_creation = False
        self._reader.disable_all_patch_arrays()
        self._reader.enable_patch_array("internalMesh")
        self._cache: dict[tuple[float, tuple[str, ...] | None], Any] = {}
        self._geometry: tuple[int, np.ndarray, np.ndarray] | None = None
        self._plane: tuple[float, Any, list[np.ndarray]] | None = None

    # --------------------------------------------------------------- properties
    @property
    def case_type(self) -> str:
        """``reconstructed`` or ``decomposed``: where the fields are read from."""
        return str(self._reader.case_type)

    @property
    def decomposed(self) -> bool:
        """Whether the fields are read from the processor directories."""
        return self._reader.case_type == "decomposed"

    @property
    def times(self) -> list[float]:
        """Written times [s], 0 included."""
        return [float(t) for t in self._reader.time_values]

    @property
    def field_names(self) -> list[str]:
        """Cell fields the case writes."""
        return sorted(self._reader.cell_array_names)

    @cached_property
    def nu_cap(self) -> float:
        """Kinematic viscosity at the cap, eta_max / rho [m^2/s]."""
        return self.scene.eta_max / self.scene.material.density

    # ------------------------------------------------------------------ reading
    def _check_time(self, time: float) -> float:
        for t in self.times:
            if math.isclose(t, time, rel_tol=1e-9, abs_tol=1e-12):
                return t
        valid = ", ".join(f"{t:g}" for t in self.times)
        raise FoamsiloError(f"time {time:g} s is not written in {self.case}; valid: {valid}")

    def mesh(self, time: float, fields: tuple[str, ...] | None = None) -> Any:
        """Return the internal mesh at ``time`` with its cell fields (a pyvista grid).

        ``fields`` limits what is read (all by default): reading one field of
        a 3D case is several times faster than reading all of them.
        """
        t = self._check_time(time)
        key = (t, fields)
        if key not in self._cache:
            self._reader.set_active_time_value(t)
            if fields is None:
                self._reader.enable_all_cell_arrays()
            else:
                self._reader.disable_all_cell_arrays()
                for name in fields:
                    self._reader.enable_cell_array(name)
            grid: Any = self._reader.read()["internalMesh"]
            # the mesh does not move: cell volumes and centres are computed once
            if self._geometry is None or self._geometry[0] != grid.n_cells:
                sized = grid.compute_cell_sizes(length=False, area=False, volume=True)
                centres = np.asarray(grid.cell_centers().points)
                self._geometry = (grid.n_cells, np.asarray(sized.cell_data["Volume"]), centres)
            self._cache = {key: grid}  # one time at a time: 3D meshes are large
        return self._cache[key]

    def _geom(self) -> tuple[int, np.ndarray, np.ndarray]:
        """Cell count, volumes and centres (read with the first time if needed)."""
        if self._geometry is None:
            self.mesh(self.times[0], (ALPHA,))
        assert self._geometry is not None
        return self._geometry

    @property
    def _volumes(self) -> np.ndarray:
        return self._geom()[1]

    @property
    def _centres(self) -> np.ndarray:
        return self._geom()[2]

    def _field(self, grid: Any, name: str) -> np.ndarray:
        if name not in grid.cell_data:
            valid = ", ".join(sorted(grid.cell_data.keys()))
            raise FoamsiloError(f"field {name!r} not written in {self.case}; valid: {valid}")
        return np.asarray(grid.cell_data[name])

    # ---------------------------------------------------------------- reductions
    def granular_volume(self, time: float) -> float:
        """Volume of grains in the silo [m^3] (per unit depth in a planar scene: [m^2])."""
        g = self.mesh(time, (ALPHA,))
        v = float(np.sum(self._field(g, ALPHA) * self._volumes))
        return v / self.scene.mesh_fraction

    def _horizontal(self) -> np.ndarray:
        """Horizontal coordinate of cell centres: x (planar, box) or radius."""
        c = self._centres
        if self.scene.representation == "planar" or self.scene.silo.shape == "rectangular":
            return c[:, 0]
        return np.hypot(c[:, 0], c[:, 2])

    def free_surface(self, time: float, bins: int = 8) -> dict[str, float]:
        """Heights of the free surface [m]: on the axis, at the wall, and the mean.

        The cross-section is cut into ``bins`` bands of x (planar, boxes) or r;
        a band spans the domain's height H, so its grains stand
        ``H sum(alpha V) / sum(V)`` high: the VOF column height, which places
        the surface within a cell. The first band holds the axis (the crater
        above the orifice), the last the wall. (In a hopper the bands are not
        prisms and the heights are approximate; the mean is exact.)
        """
        g = self.mesh(time, (ALPHA,))
        alpha = self._field(g, ALPHA)
        vol = self._volumes
        h = self._horizontal()
        height = self.scene.silo.height
        lo, hi = float(h.min()), float(h.max())
        if self.scene.representation == "planar" or self.scene.silo.shape == "rectangular":
            # the orifice is in the middle: fold x onto the distance from it
            axis = self.scene.silo.width / 2
            h = np.abs(h - axis)
            lo, hi = 0.0, float(h.max())
        edges = np.linspace(lo, hi, bins + 1)
        band_of = np.clip(np.searchsorted(edges, h, side="right") - 1, 0, bins - 1)
        num = np.bincount(band_of, weights=alpha * vol, minlength=bins)
        den = np.bincount(band_of, weights=vol, minlength=bins)
        heights = np.where(den > 0, height * num / np.where(den > 0, den, 1), np.nan)
        return {
            "axis_m": float(heights[0]),
            "wall_m": float(heights[-1]),
            "mean_m": self.granular_volume(time) / self.scene.cross_section_area,
        }

    def velocity_profile(self, time: float, height: float, n: int = 200) -> dict[str, Any]:
        """Velocity across the silo on a horizontal line at ``height`` [m].

        Returns the positions (x, or r from the axis), the horizontal and
        vertical velocity [m/s] and the volume fraction along the line, and
        ``mass_flow``: the grains' mass flow down through the line,
        rho int(-alpha v) dx per unit depth (planar) or rho int(-alpha v) 2 pi r dr
        (axisymmetric flow: wedges and centred 3D cylinders), NaN otherwise.
        In a steady discharge it equals the orifice rate Q.
        """
        s = self.scene
        if not 0.0 < height < s.silo.height:
            raise FoamsiloError(
                f"height {height:g} m: must be inside the silo (0, {s.silo.height:g}) m"
            )
        g = self.mesh(time, (ALPHA, "U"))
        rep = s.representation
        eps = 1e-6 * s.silo.width
        if rep == "planar":
            z = float(g.bounds[4] + g.bounds[5]) / 2
            a, b = (eps, height, z), (s.silo.width - eps, height, z)
        elif s.silo.shape == "rectangular":
            z = float(g.bounds[4] + g.bounds[5]) / 2
            a, b = (eps, height, z), (s.silo.width - eps, height, z)
        else:
            r = s.silo.wall_radius(height)
            a, b = (eps, height, 0.0), (r - eps, height, 0.0)
        line = g.sample_over_line(a, b, resolution=n - 1)
        # points outside every cell (a wedge's planar outer face lies inside r = R)
        inside = np.asarray(line.point_data["vtkValidPointMask"]).astype(bool)
        pts = np.asarray(line.points)[inside]
        pos = pts[:, 0] if rep != "axisymmetric" else np.hypot(pts[:, 0], pts[:, 2])
        u = np.asarray(line.point_data["U"])[inside]
        alpha = np.asarray(line.point_data[ALPHA])[inside]
        down = -alpha * u[:, 1] * s.material.density
        if rep == "planar":
            mass_flow = _integrate(down, pos)
        elif s.silo.shape != "rectangular" and s.silo.eccentricity == 0.0:
            mass_flow = _integrate(down * 2 * np.pi * pos, pos)
        else:
            mass_flow = math.nan
        return {
            "position_m": pos,
            "u_horizontal": u[:, 0],
            "u_vertical": u[:, 1],
            "alpha": alpha,
            "mass_flow": mass_flow,
        }

    def stagnant_fraction(self, time: float) -> float:
        """Fraction of the granular volume whose viscosity sits at the cap."""
        g = self.mesh(time, (ALPHA, "nu1"))
        alpha = self._field(g, ALPHA)
        nu = self._field(g, "nu1")
        w = alpha * self._volumes
        total = float(np.sum(w))
        if total <= 0:
            return math.nan
        return float(np.sum(w[nu >= CAP_FRACTION * self.nu_cap]) / total)

    # ----------------------------------------------------------------- pictures
    def _mid_plane(self, time: float) -> tuple[Any, list[np.ndarray]]:
        """Return the mid-plane at ``time`` (all fields) and its cells' outlines in (x, y).

        Cut once per time for both pictures (the outlines are a Python loop
        over the cells, the slow part on a 3D mesh).
        """
        if self._plane is None or self._plane[0] != time:
            g = self.mesh(time)
            planar = self.scene.representation == "planar"
            z0 = float(g.bounds[4] + g.bounds[5]) / 2 if planar else 0.0
            plane = g.slice(normal="z", origin=(0.0, 0.0, z0))
            if plane.n_cells == 0:
                raise FoamsiloError(f"{self.case}: the mid-plane z = {z0:g} m cuts no cell")
            polys = [np.asarray(plane.get_cell(i).points)[:, :2] for i in range(plane.n_cells)]
            self._plane = (time, plane, polys)
        return self._plane[1], self._plane[2]

    def picture(self, time: float, path: Path) -> Path:
        """Mid-plane images of p, alpha, |U| and log10 eta side by side (PNG).

        The plane is cut with pyvista (the mesh itself for a planar scene, the
        z = 0 section through the axis otherwise) and drawn cell by cell with
        matplotlib's Agg backend: off-screen, no display or GL needed.
        """
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from matplotlib.collections import PolyCollection

        s = self.scene
        plane, polys = self._mid_plane(time)
        rho = s.material.density
        panels = [
            ("granular pressure p [Pa]", np.asarray(plane.cell_data["p"]), "viridis"),
            ("volume fraction alpha", np.asarray(plane.cell_data[ALPHA]), "cividis"),
            ("grain speed |U| [m/s]", np.linalg.norm(plane.cell_data["U"], axis=1), "magma"),
            (
                "log10 grain viscosity [Pa s]",
                np.log10(np.maximum(np.asarray(plane.cell_data["nu1"]) * rho, 1e-12)),
                "plasma",
            ),
        ]
        x0, x1, y0, y1 = plane.bounds[0], plane.bounds[1], plane.bounds[2], plane.bounds[3]
        aspect = (y1 - y0) / max(x1 - x0, 1e-12)
        fig_h = 6.0
        panel_w = max(fig_h / aspect, 1.2) + 0.9
        fig, axes = plt.subplots(1, 4, figsize=(4 * panel_w, fig_h + 0.6), constrained_layout=True)
        # speed and viscosity of the grains only: the air above them carries
        # spurious fast velocities that would set the colour scale
        air = np.asarray(plane.cell_data[ALPHA]) < SURFACE_ALPHA
        for k in (2, 3):
            panels[k] = (panels[k][0], np.where(air, np.nan, panels[k][1]), panels[k][2])
        for ax, (title, values, cmap_name) in zip(axes, panels, strict=True):
            cmap = matplotlib.colormaps[cmap_name].with_extremes(bad="0.85")
            coll = PolyCollection(
                polys, array=np.ma.masked_invalid(values), cmap=cmap, edgecolors="none"
            )
            ax.add_collection(coll)
            ax.set_xlim(x0, x1)
            ax.set_ylim(y0, y1)
            ax.set_aspect("equal")
            ax.set_title(title, fontsize=9)
            ax.set_xlabel("r [m]" if s.representation != "planar" else "x [m]", fontsize=8)
            ax.tick_params(labelsize=7)
            fig.colorbar(coll, ax=ax, shrink=0.8)
        axes[0].set_ylabel("y [m]", fontsize=8)
        fig.suptitle(f"{s.name}, t = {time:g} s ({s.representation})", fontsize=10)
        path = Path(path)
        fig.savefig(path, dpi=110)
        plt.close(fig)
        return path

    def orifice_centre(self, bounds: tuple[float, ...]) -> tuple[float, float]:
        """Return the orifice's centre in the mid-plane (x or r, y) [m], given its bounds."""
        s = self.scene.silo
        if s.orifice_position == "lateral":
            assert s.orifice_height is not None
            return float(bounds[1]), s.orifice_height + s.orifice_width / 2
        if self.scene.representation == "axisymmetric":
            return 0.0, 0.0
        if self.scene.representation == "planar" or s.shape == "rectangular":
            return float(bounds[0] + bounds[1]) / 2, 0.0
        return s.eccentricity, 0.0

    def orifice_picture(self, time: float, path: Path) -> Path:
        """Where the flow is: the whole silo and the orifice region, grain speed (PNG).

        Left, the mid-plane of the whole silo; beside it the region within
        three orifice widths of the orifice, with velocity arrows; on both the
        stagnant zone outlined (white: grains slower than ``STAGNANT_SPEED`` of
        the fastest) and the free surface (alpha = 1/2, cyan). A 3D case adds the horizontal
        section half an orifice width above the orifice's lower edge. Equal
        aspect ratio throughout; off-screen (matplotlib's Agg).
        """
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from matplotlib.collections import PolyCollection
        from matplotlib.tri import Triangulation
        from scipy.interpolate import griddata

        sc = self.scene
        plane, polys = self._mid_plane(time)
        centres = np.asarray(plane.cell_centers().points)[:, :2]
        alpha = np.asarray(plane.cell_data[ALPHA])
        u = np.asarray(plane.cell_data["U"])
        grains = alpha >= SURFACE_ALPHA
        speed = np.where(grains, np.linalg.norm(u, axis=1), np.nan)
        # stagnant: grains slower than a small fraction of the fastest (a plug
        # moving as a rigid block sits at the viscosity cap too, but moves)
        fastest = float(np.nanmax(speed)) if np.isfinite(speed).any() else 0.0
        stagnant = grains & (np.nan_to_num(speed) <= STAGNANT_SPEED * fastest)
        bounds = tuple(float(b) for b in plane.bounds)
        xc, yc = self.orifice_centre(bounds)
        D = sc.silo.orifice_width
        if sc.silo.orifice_position == "lateral":
            win = (max(bounds[0], xc - 5 * D), xc, max(bounds[2], yc - 3 * D),
                   min(bounds[3], yc + 3 * D))  # fmt: skip
        else:
            win = (max(bounds[0], xc - 3 * D), min(bounds[1], xc + 3 * D), bounds[2],
                   min(bounds[3], bounds[2] + 4 * D))  # fmt: skip
        tri = Triangulation(centres[:, 0], centres[:, 1])
        vmax = fastest if fastest > 0 else 1.0
        cmap = matplotlib.colormaps["magma"].with_extremes(bad="0.85")

        def speed_panel(ax: Any, box: tuple[float, ...], title: str) -> Any:
            coll = PolyCollection(polys, array=np.ma.masked_invalid(speed), cmap=cmap,
                                  edgecolors="none", clim=(0.0, vmax))  # fmt: skip
            ax.add_collection(coll)
            if stagnant.any() and not stagnant.all():
                ax.tricontour(tri, stagnant.astype(float), levels=[0.5], colors="white",
                              linewidths=1.0)  # fmt: skip
            ax.tricontour(tri, alpha, levels=[SURFACE_ALPHA], colors="cyan", linewidths=1.0)
            ax.set_xlim(box[0], box[1])
            ax.set_ylim(box[2], box[3])
            ax.set_aspect("equal")
            ax.set_title(title, fontsize=9)
            ax.set_xlabel("r [m]" if sc.representation == "axisymmetric" else "x [m]", fontsize=8)
            ax.tick_params(labelsize=7)
            return coll

        section = None
        if sc.representation == "3d":
            ys = (sc.silo.orifice_height or 0.0) + D / 2 if sc.silo.orifice_position == "lateral" \
                else 0.5 * D  # fmt: skip
            cut = self.mesh(time).slice(normal="y", origin=(0.0, ys, 0.0))
            if cut.n_cells:
                section = (cut, ys)
        # widths in proportion to what each panel shows, at one height
        whole_w = (bounds[1] - bounds[0]) / max(bounds[3] - bounds[2], 1e-12)
        zoom_w = (win[1] - win[0]) / max(win[3] - win[2], 1e-12)
        ratios = [max(whole_w, 0.25), max(zoom_w, 0.25)] + ([1.0] if section else [])
        fig_h = 5.5
        size = (fig_h * sum(ratios) + 2.5, fig_h + 0.7)
        fig, axes = plt.subplots(1, len(ratios), figsize=size, constrained_layout=True,
                                 gridspec_kw={"width_ratios": ratios})  # fmt: skip
        speed_panel(axes[0], bounds, "whole silo (mid-plane)")
        coll = speed_panel(axes[1], win, f"orifice region (D = {D * 1e3:g} mm)")
        axes[1].add_patch(matplotlib.patches.Rectangle((win[0], win[2]), win[1] - win[0],
                          win[3] - win[2], fill=False, ec="0.4", lw=0.6))  # fmt: skip
        axes[0].add_patch(matplotlib.patches.Rectangle((win[0], win[2]), win[1] - win[0],
                          win[3] - win[2], fill=False, ec="tab:blue", lw=1.0))  # fmt: skip
        gx, gy = np.meshgrid(np.linspace(win[0], win[1], 18), np.linspace(win[2], win[3], 18))
        inside = (centres[:, 0] >= win[0] - D) & (centres[:, 0] <= win[1] + D) & \
                 (centres[:, 1] <= win[3] + D)  # fmt: skip
        if inside.sum() >= 4:
            pts = centres[inside]
            gu = griddata(pts, np.where(grains, u[:, 0], np.nan)[inside], (gx, gy))
            gv = griddata(pts, np.where(grains, u[:, 1], np.nan)[inside], (gx, gy))
            axes[1].quiver(gx, gy, gu, gv, color="tab:green", angles="xy", width=0.004)
        axes[0].set_ylabel("y [m]", fontsize=8)
        if section is not None:
            cut, ys = section
            cpolys = [np.asarray(cut.get_cell(i).points)[:, [0, 2]] for i in range(cut.n_cells)]
            ca = np.asarray(cut.cell_data[ALPHA])
            cs = np.where(ca >= SURFACE_ALPHA, np.linalg.norm(cut.cell_data["U"], axis=1), np.nan)
            ax = axes[2]
            ax.add_collection(PolyCollection(cpolys, array=np.ma.masked_invalid(cs), cmap=cmap,
                                             edgecolors="none", clim=(0.0, vmax)))  # fmt: skip
            b = cut.bounds
            ax.set_xlim(b[0], b[1])
            ax.set_ylim(b[4], b[5])
            ax.set_aspect("equal")
            ax.set_title(f"section y = {ys * 1e3:.3g} mm", fontsize=9)
            ax.set_xlabel("x [m]", fontsize=8)
            ax.set_ylabel("z [m]", fontsize=8)
            ax.tick_params(labelsize=7)
        fig.colorbar(coll, ax=axes, shrink=0.8, label="grain speed |U| [m/s]")
        fig.suptitle(f"{sc.name}, t = {time:g} s: grain speed; white: stagnant zone (slower "
                     f"than {STAGNANT_SPEED:.0%} of the fastest), cyan: free surface",
                     fontsize=10)  # fmt: skip
        path = Path(path)
        fig.savefig(path, dpi=110)
        plt.close(fig)
        return path


#: Height of the velocity profile, as a fraction of the silo height (Venier Fig. 3)
PROFILE_HEIGHT = 0.15
PROFILE_CSV = "profile_U.csv"
PROFILE_PNG = "profile_U.png"
SURFACE_CSV = "free_surface.csv"
SURFACE_PNG = "free_surface.png"
FIELDS_PNG = "fields.png"
ORIFICE_PNG = "orifice.png"


def _write_csv(path: Path, header: list[str], rows: list[list[float]]) -> None:
    import csv
    import os

    tmp = path.with_name(path.name + ".tmp")
    with open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        for r in rows:
            w.writerow([f"{x:.9g}" for x in r])
    os.replace(tmp, path)


def plot_profile(prof: dict[str, Any], scene: Scene, time: float, path: Path) -> None:
    """Vertical and horizontal grain velocity across the silo at one height (PNG)."""
    from foamsilo.plots import finish, subplots

    fig, ax = subplots(size=(6, 4))
    x = prof["position_m"]
    ax.plot(x, prof["u_vertical"], "C0-", label="vertical $u_y$")
    ax.plot(x, prof["u_horizontal"], "C1--", label="horizontal $u_x$")
    ax.axhline(0, color="0.6", lw=0.8)
    ax.set_xlabel("r [m]" if scene.representation == "axisymmetric" else "x [m]")
    ax.set_ylabel("grain velocity [m/s]")
    ax.set_title(
        f"{scene.name}: y = {prof['height_m']:.4g} m ({PROFILE_HEIGHT:g} H), t = {time:g} s",
        fontsize=9,
    )
    finish(fig, ax, path)


def plot_free_surface(series: np.ndarray, scene: Scene, path: Path) -> None:
    """Free-surface heights (axis, wall, mean) against time (PNG)."""
    from foamsilo.plots import finish, subplots

    fig, ax = subplots(size=(6, 4))
    for k, (label, style) in enumerate(
        (("on the axis (crater)", "C3o-"), ("at the wall", "C2s-"), ("mean (volume / area)", "k-"))
    ):
        ax.plot(series[:, 0], series[:, k + 1], style, ms=3, label=label)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("free-surface height [m]")
    ax.set_title(f"{scene.name}: free surface", fontsize=9)
    finish(fig, ax, path)


@dataclass
class FieldSummary:
    """What the written fields say at the latest written time.

    Attributes
    ----------
    time_s
        The time they were read at [s].
    case_type
        ``reconstructed`` or ``decomposed``: where they were read from.
    free_surface_m
        Free-surface heights on the axis, at the wall and the mean [m].
    stagnant_fraction
        Share of the granular volume at the viscosity cap.
    profile_height_m
        Height of the velocity profile [m] (0.15 H).
    profile_mass_flow
        Mass flow of grains down through the profile's line (None where the
        geometry has no exact line integral: eccentric or 3D boxes).
    profile_max_downward_m_s
        Largest downward grain speed on the line (None: no grains there).
    files
        The tables and pictures written.
    """

    time_s: float
    case_type: str
    free_surface_m: dict[str, float]
    stagnant_fraction: float | None
    profile_height_m: float
    profile_mass_flow: float | None
    profile_max_downward_m_s: float | None
    files: list[str]

    def as_dict(self) -> dict[str, Any]:
        """JSON-friendly form (the ``fields`` section of the summary)."""
        d = asdict(self)
        if self.profile_mass_flow is None:
            d["profile_mass_flow_reason"] = (
                "the line integral is exact only for planar and axisymmetric flow"
            )
        return d


def _finite(x: float) -> float | None:
    return x if math.isfinite(x) else None


def field_summary(case: Path, case_type: str = "auto") -> FieldSummary:
    """Reduce the written fields of a case; write the profile, surface and picture files.

    At the latest written time: the free surface (axis, wall, mean), the
    stagnant fraction, the velocity profile at 0.15 H (``profile_U.csv``,
    ``profile_U.png``) with the mass flow through it, the mid-plane
    picture (``fields.png``) and the orifice region's (``orifice.png``);
    over every written time, the free surface (``free_surface.csv``,
    ``free_surface.png``).
    """
    f = CaseFields(case, case_type)
    later = [t for t in f.times if t > 0]
    if not later:
        raise FoamsiloError(f"{f.case}: no time written after 0")
    t = later[-1]
    height = PROFILE_HEIGHT * f.scene.silo.height
    prof = f.velocity_profile(t, height)
    prof["height_m"] = height
    _write_csv(
        f.case / PROFILE_CSV,
        ["position_m", "u_horizontal_m_s", "u_vertical_m_s", "alpha"],
        np.column_stack(
            [prof["position_m"], prof["u_horizontal"], prof["u_vertical"], prof["alpha"]]
        ).tolist(),
    )
    plot_profile(prof, f.scene, t, f.case / PROFILE_PNG)
    series = []
    for tt in [x for x in f.times if x >= 0]:
        s = f.free_surface(tt)
        series.append([tt, s["axis_m"], s["wall_m"], s["mean_m"]])
    _write_csv(f.case / SURFACE_CSV, ["t_s", "axis_m", "wall_m", "mean_m"], series)
    plot_free_surface(np.array(series), f.scene, f.case / SURFACE_PNG)
    f.picture(t, f.case / FIELDS_PNG)
    f.orifice_picture(t, f.case / ORIFICE_PNG)
    grains = prof["alpha"] >= SURFACE_ALPHA
    return FieldSummary(
        time_s=t,
        case_type=f.case_type,
        free_surface_m=f.free_surface(t),
        stagnant_fraction=_finite(f.stagnant_fraction(t)),
        profile_height_m=height,
        profile_mass_flow=_finite(prof["mass_flow"]),
        profile_max_downward_m_s=float(-np.min(prof["u_vertical"][grains]))
        if grains.any()
        else None,
        files=[PROFILE_CSV, PROFILE_PNG, SURFACE_CSV, SURFACE_PNG, FIELDS_PNG, ORIFICE_PNG],
    )
