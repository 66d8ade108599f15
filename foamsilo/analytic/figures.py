"""Model lines of Zhou et al. 2019, Figs 2b, 2c, 7c and 9 (no data points).

The experimental points are not available; the curves are the paper's
equations with its Table I constants, phi_b = 0.6 and glass beads
(rho_p = 2500 kg/m^3) in air.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from foamsilo.analytic.zhou import (
    LPM,
    config,
    gas_assisted,
    q0_bottom,
    q0_lateral,
    q_impermeable,
)

PHI_B = 0.6
GRAIN_SIZES_UM = (124, 190, 375, 538, 762, 1129, 1347)  # sec. II.A


def _plt():  # noqa: ANN202 - matplotlib module
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _q_of_d(name: str, d: np.ndarray, q_air_lpm: float, **kw: Any) -> np.ndarray:
    return np.array(
        [gas_assisted(name, float(di), q_air_lpm * LPM, phi_b=PHI_B, **kw).Q for di in d]
    )


def fig2b(path: Path) -> Path:
    """Fig. 2b: Q against d, cylindrical silo, bottom orifice, L = 60 mm, D = 10 mm."""
    plt = _plt()
    c = config("cyl-bottom")
    d = np.geomspace(100e-6, 1500e-6, 120)
    fig, ax = plt.subplots(figsize=(6, 4.2), dpi=120)
    q0 = q0_bottom(0.010, d, PHI_B, 2500.0, c.C0 or 0, c.alpha_D, c.beta)
    ax.plot(d * 1e6, q0 * 1e3, "k-", lw=2, label="eq. 1, open top")
    for i, qa in enumerate((2, 5, 12, 20, 30)):
        ax.plot(d * 1e6, _q_of_d("cyl-bottom", d, qa, D=0.010) * 1e3, "--", color=f"C{i}",
                label=f"eq. 23, $Q_{{air}}$ = {qa} L/min")  # fmt: skip
    ax.set_xlabel(r"$d$ ($\mu$m)")
    ax.set_ylabel(r"$Q$ (g/s)")
    ax.set_yscale("log")
    ax.set_title("Zhou et al. Fig. 2b (model lines): cylindrical, bottom, D = 10 mm")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")
    return _save(fig, path)


def fig2c(path: Path) -> Path:
    """Fig. 2c: Q against Q_air for several d, with eq. 1 (d = 1129 um) and eq. 3."""
    plt = _plt()
    c = config("cyl-bottom")
    qa = np.linspace(0.0, 50.0, 101)
    fig, ax = plt.subplots(figsize=(6, 4.2), dpi=120)
    for i, dum in enumerate((190, 375, 538, 762, 1129)):
        q = [gas_assisted("cyl-bottom", dum * 1e-6, x * LPM, D=0.010, phi_b=PHI_B).Q for x in qa]
        ax.plot(qa, np.array(q) * 1e3, "--", color=f"C{i}", label=f"eq. 23, d = {dum} µm")
    q0 = float(q0_bottom(0.010, 1129e-6, PHI_B, 2500.0, c.C0 or 0, c.alpha_D, c.beta))
    ax.axhline(q0 * 1e3, color="k", lw=2, label="eq. 1, d = 1129 µm")
    ax.plot(qa, q_impermeable(qa * LPM, PHI_B) * 1e3, "k:", lw=1.5, label="eq. 3")
    ax.set_xlabel(r"$Q_{air}$ (L/min)")
    ax.set_ylabel(r"$Q$ (g/s)")
    ax.set_ylim(0, 150)
    ax.set_title("Zhou et al. Fig. 2c (model lines): cylindrical, bottom, D = 10 mm")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return _save(fig, path)


def fig7c(path: Path) -> Path:
    """Fig. 7c: Q against d, rectangular silo, bottom orifice D = 10 mm, W = 3.5 mm."""
    plt = _plt()
    c = config("rect-bottom")
    d = np.geomspace(100e-6, 1500e-6, 120)
    fig, ax = plt.subplots(figsize=(6, 4.2), dpi=120)
    q0 = q0_bottom(0.010, d, PHI_B, 2500.0, c.C0 or 0, c.alpha_D, c.beta, area=0.010 * 0.0035)
    ax.plot(d * 1e6, q0 * 1e3, "k-", lw=2, label="eq. 1, open top")
    for i, qa in enumerate((1, 2, 5, 10)):
        ax.plot(d * 1e6, _q_of_d("rect-bottom", d, qa) * 1e3, "--", color=f"C{i}",
                label=f"eq. 23, $Q_{{air}}$ = {qa} L/min")  # fmt: skip
    ax.set_xlabel(r"$d$ ($\mu$m)")
    ax.set_ylabel(r"$Q$ (g/s)")
    ax.set_yscale("log")
    ax.set_title("Zhou et al. Fig. 7c (model lines): rectangular, bottom")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")
    return _save(fig, path)


def fig9(path: Path) -> Path:
    """Fig. 9: Q against d for lateral orifices (a) cylindrical, (b) rectangular silo."""
    plt = _plt()
    d = np.geomspace(100e-6, 1500e-6, 120)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), dpi=120)
    panels = (
        ("cyl-lateral-rect", 0.020, 0.010, "(a) cylindrical, lateral, D = 20 mm, W = 10 mm"),
        ("rect-lateral", 0.010, 0.0035, "(b) rectangular, lateral, D = 10 mm, W = 3.5 mm"),
    )
    for ax, (name, D, W, title) in zip(axes, panels, strict=True):
        c = config(name)
        q0 = q0_lateral(D, W, d, PHI_B, 2500.0, c.C0l or 0, c.alpha_D, c.alpha_W, c.beta,
                        c.gamma2)  # fmt: skip
        ax.plot(d * 1e6, q0 * 1e3, "k-", lw=2, label="eq. 24, open top")
        for i, qa in enumerate((2, 5, 10, 20)):
            ax.plot(d * 1e6, _q_of_d(name, d, qa, D=D, W=W) * 1e3, "--", color=f"C{i}",
                    label=f"eq. 23 ($\\lambda g$), $Q_{{air}}$ = {qa} L/min")  # fmt: skip
        ax.set_xlabel(r"$d$ ($\mu$m)")
        ax.set_ylabel(r"$Q$ (g/s)")
        ax.set_yscale("log")
        ax.set_title(title, fontsize=9)
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3, which="both")
    fig.suptitle("Zhou et al. Fig. 9 (model lines): lateral orifices")
    return _save(fig, path)


def _save(fig: object, path: Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()  # type: ignore[attr-defined]
    fig.savefig(path)  # type: ignore[attr-defined]
    _plt().close(fig)
    return path


def all_figures(out_dir: Path) -> list[Path]:
    """Write the four figures into ``out_dir``."""
    out = Path(out_dir)
    return [
        fig2b(out / "zhou-fig2b-model.png"),
        fig2c(out / "zhou-fig2c-model.png"),
        fig7c(out / "zhou-fig7c-model.png"),
        fig9(out / "zhou-fig9-model.png"),
    ]
