"""The validation and benchmark suite: ``foamsilo bench [--quick]``.

What a user reads before trusting foamsilo: how close the OpenFOAM path is
to theory and experiment, what that costs, and where it breaks. Every entry
runs real siloFoam cases (two at a time on two cores), and writes its table
and plots into ``docs/validation/`` (``suite.md``; ``suite-quick.md`` for
``--quick``), each row with the resolution, the wall and CPU time, and the
error. ``--quick`` runs reduced versions of the same entries in well under
15 minutes on two cores and checks that their figures stay within the
tolerances stated next to each check; the command fails when one does not.

Entries
-------
``work-precision``
    The planar silo of Zhou sec. III.B and the axisymmetric lab silo (Zhou
    Table I, L = 60 mm, D = 10 mm) at several resolutions: steady Q against
    the finest and against the analytic law, wall time, the resolution to
    pick for 5% and 2%.
``beverloo``
    Venier Test 1 (flat-bottomed D = 0.33 m silo, outlets 3 to 12 cm, their
    Table 1 material), axisymmetric: the fit W = C (d - f)^2.5 with C, f and
    R^2; and the planar silo against the orifice width, 2D Beverloo.
``extremes``
    Stiff and extreme scenes run to the end or stopped with a diagnosis:
    the viscosity cap from 1e2 to 1e5 (dimensionless), D/d near 5, a tall
    silo H/L = 20, each with its time-step history and Q.
"""

from __future__ import annotations

import json
import math
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from foamsilo.case import write_whole
from foamsilo.errors import FoamsiloError


@dataclass
class Check:
    """A figure of the suite and the range it must stay in."""

    entry: str
    name: str
    value: float | None
    low: float
    high: float
    why: str

    @property
    def passed(self) -> bool:
        """Whether the value is finite and inside [low, high]."""
        return (
            self.value is not None
            and math.isfinite(self.value)
            and (self.low <= self.value <= self.high)
        )


def _run(
    cases: list[tuple[str, str, list[str]]], work: Path, jobs: int, limit: float
) -> list[dict[str, Any]]:
    """Run (label, preset, sets) cases, ``jobs`` at a time; one outcome row each."""
    from foamsilo.validation import _run_outcome

    args = [
        (label, preset, sets, str(work / f"{i:02d}"), limit)
        for i, (label, preset, sets) in enumerate(cases)
    ]
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        return list(pool.map(_run_outcome, args))


# ----------------------------------------------------------- work precision
def _recommend(cells: list[int], err: list[float], level: float) -> int | None:
    """Coarsest resolution from which every finer one is within ``level`` of the finest."""
    for i, _ in enumerate(cells[:-1]):
        if all(e <= level for e in err[i:-1]):
            return cells[i]
    return None


def work_precision(quick: bool, work: Path, jobs: int, limit: float) -> dict[str, Any]:
    """Steady Q against resolution and wall time, planar and axisymmetric."""
    from foamsilo.compare import open_top_law
    from foamsilo.scene import load_preset

    plans = {
        "zhou-planar": (
            [16, 24, 32] if quick else [16, 24, 32, 48, 64, 96],
            ["run.end_time=0.5", "run.write_interval=0.25"]
            if quick
            else ["run.end_time=1.0", "run.write_interval=0.5"],
        ),
        # the wedge of the lab silo needs steps under ~1 ms up to 72 across
        # (the default cap 0.05 sqrt(L/g) = 3.9 ms diverges at 48 across once
        # the step passes ~1.2 ms: see the extremes entry) and 0.5 ms at 96
        "zhou-cyl-bottom": (
            [36, 48, 72] if quick else [36, 48, 72, 96],
            ["run.max_delta_t=0.001" if quick else "run.max_delta_t=0.0005"]
            + (
                ["run.end_time=0.3", "run.write_interval=0.15"]
                if quick
                else ["run.end_time=0.6", "run.write_interval=0.3"]
            ),
        ),
    }
    out: dict[str, Any] = {}
    for preset, (cells, sets) in plans.items():
        rows = _run(
            [(f"{n} across", preset, [f"mesh.cells_across={n}", *sets]) for n in cells],
            work / preset,
            jobs,
            limit,
        )
        law_name, q_law = open_top_law(load_preset(preset))
        q_fin = rows[-1].get("Q")
        for r, n in zip(rows, cells, strict=True):
            r["cells_across"] = n
            q = r.get("Q")
            r["err_vs_finest"] = abs(q / q_fin - 1) if q and q_fin else None
            r["err_vs_law"] = q / q_law - 1 if q else None
        errs = [r["err_vs_finest"] if r["err_vs_finest"] is not None else math.inf for r in rows]
        out[preset] = {
            "law": law_name,
            "Q_law": q_law,
            "rows": rows,
            "recommend_5pct": _recommend(cells, errs, 0.05),
            "recommend_2pct": _recommend(cells, errs, 0.02),
        }
    return out


# ------------------------------------------------------------------ Beverloo
def beverloo_fit(d: np.ndarray, w: np.ndarray, exponent: float) -> dict[str, float]:
    """Fit W = C (d - f)^exponent: linear in d for W^(1/exponent); C, f and R^2."""
    y = np.asarray(w, float) ** (1.0 / exponent)
    slope, intercept = np.polyfit(d, y, 1)
    pred = slope * np.asarray(d) + intercept
    r2 = 1 - np.sum((y - pred) ** 2) / np.sum((y - y.mean()) ** 2)
    return {"C": float(slope**exponent), "f": float(-intercept / slope), "R2": float(r2)}


def beverloo(quick: bool, work: Path, jobs: int, limit: float) -> dict[str, Any]:
    """Venier Test 1 outlets (axisymmetric) and the planar silo against the orifice width."""
    outlets = [0.03, 0.06, 0.09, 0.12]
    if not quick:
        outlets = [0.03, 0.045, 0.059, 0.075, 0.09, 0.105, 0.12]  # Venier's seven
    venier_sets = [
        "run.max_delta_t=0.001",  # the 12 cm outlet diverges at 1 s with 2 ms (9 ms default)
        "mesh.cells_across=44" if quick else "mesh.cells_across=66",
        "run.end_time=1.0",  # 5.5 sqrt(L/g); the largest outlets diverge from ~1.1 s
        "run.write_interval=0.5",
    ]
    widths = [0.02, 0.025, 0.03] if quick else [0.015, 0.02, 0.025, 0.03, 0.035, 0.04]
    planar_sets = [
        "mesh.cells_across=24" if quick else "mesh.cells_across=48",
        "run.end_time=0.5",
        "run.write_interval=0.25",
    ]
    cases = [
        (f"outlet {o * 100:g} cm", "venier-test1", [*venier_sets, f"silo.orifice_width={o}"])
        for o in outlets
    ]
    cases += [
        (f"slot {w * 1000:g} mm", "zhou-planar", [*planar_sets, f"silo.orifice_width={w}"])
        for w in widths
    ]
    rows = _run(cases, work / "beverloo", jobs, limit)
    ven, pla = rows[: len(outlets)], rows[len(outlets) :]
    for r, o in zip(ven, outlets, strict=True):
        r["orifice_m"] = o
    for r, w in zip(pla, widths, strict=True):
        r["orifice_m"] = w
    out: dict[str, Any] = {"venier": {"rows": ven}, "planar": {"rows": pla}}
    ok_v = [r for r in ven if r.get("Q")]
    if len(ok_v) >= 3:
        out["venier"]["fit"] = beverloo_fit(
            np.array([r["orifice_m"] for r in ok_v]), np.array([r["Q"] for r in ok_v]), 2.5
        )
    ok_p = [r for r in pla if r.get("Q")]
    if len(ok_p) >= 3:
        out["planar"]["fit"] = beverloo_fit(
            np.array([r["orifice_m"] for r in ok_p]), np.array([r["Q"] for r in ok_p]), 1.5
        )
        out["planar"]["fit"]["C_dimensionless"] = out["planar"]["fit"]["C"] / (2500 * 9.81**0.5)
    return out


# ---------------------------------------------------------- gas-assisted lab
def _late_mean(case: Path, skip: float) -> tuple[float | None, float | None]:
    """Time-weighted mean and std of the orifice rate after ``skip`` seconds (discharge.csv)."""
    table = case / "discharge.csv"
    if not table.exists():
        return None, None
    data = np.loadtxt(table, delimiter=",", skiprows=1, ndmin=2)
    t, q = data[:, 0], data[:, 2]
    dt = np.diff(np.concatenate([[0.0], t]))
    keep = t > skip
    if keep.sum() < 20 or t[-1] < 2 * skip:
        return None, None
    w = dt[keep]
    mean = float(np.sum(q[keep] * w) / np.sum(w))
    return mean, float(np.sqrt(np.sum((q[keep] - mean) ** 2 * w) / np.sum(w)))


def gas_lab(quick: bool, work: Path, jobs: int, limit: float) -> dict[str, Any]:
    """Zhou's cylindrical lab silo with air injected at the top, against eq. 23.

    Table I cylinder (L = 60 mm, D = 10 mm), axisymmetric, for grain sizes
    and air flows of the experiments; Q_air = 0 is the closed top. Each grain
    size also runs with the open top, and the comparison is made on Q/Q0 (the
    rate over the open-top rate, Zhou's Fig. 7 axes): the continuum's own Q0
    is above eq. 1 (see work-precision), and the ratio isolates the gas.
    eq. 23 with the Table I constants (phi_o from eq. 2 with xi_phi = 0.83,
    Ergun permeabilities at phi_o, Forchheimer term on, A = 1).
    """
    from foamsilo.analytic.zhou import gas_assisted

    sizes = [538e-6] if quick else [190e-6, 538e-6, 1129e-6]
    flows = [12.0] if quick else [0.0, 4.0, 12.0, 25.0, 50.0]
    base = [
        "mesh.cells_across=48",
        "run.max_delta_t=0.001",
        "run.end_time=0.4" if quick else "run.end_time=0.6",
        "run.write_interval=0.2",
    ]
    cases, keys = [], []
    for d in sizes:
        size = f"material.grain_diameter={d}"
        cases.append((f"d = {d * 1e6:.0f} um, open top", "zhou-cyl-bottom", [*base, size]))
        keys.append((d, None))
        for q in flows:
            mode = (
                ['gas.mode="closed-top"']
                if q == 0
                else ['gas.mode="injection"', f"gas.q_air_lpm={q}"]
            )
            cases.append(
                (
                    f"d = {d * 1e6:.0f} um, Q_air = {q:g} L/min",
                    "zhou-cyl-bottom",
                    [*base, size, *mode],
                )
            )
            keys.append((d, q))
    rows = _run(cases, work / "gas-lab", jobs, limit)
    for r in rows:
        r["Q_mean"], r["Q_mean_std"] = _late_mean(Path(r["case_dir"]), skip=1.5 * 0.0782)
    q_open = {d: r.get("Q_mean") for r, (d, q) in zip(rows, keys, strict=True) if q is None}
    for r, (d, q) in zip(rows, keys, strict=True):
        r["grain_diameter"], r["q_air_lpm"] = d, q
        if q is None:
            continue
        theory = gas_assisted("cyl-bottom", d, q * 1e-3 / 60)
        r["eq23_ratio"] = theory.Q_reduced
        r["sim_ratio"] = r["Q_mean"] / q_open[d] if r.get("Q_mean") and q_open.get(d) else None
        r["rel_error"] = r["sim_ratio"] / theory.Q_reduced - 1 if r["sim_ratio"] else None
    return {"rows": rows}


# ------------------------------------------------------------------ extremes
def extremes(quick: bool, work: Path, jobs: int, limit: float) -> dict[str, Any]:
    """Stiff and extreme scenes: run to the end or stop with a diagnosis."""
    base = ["mesh.cells_across=16", "run.end_time=0.5", "run.write_interval=0.25"]
    caps = [1e2, 1e3, 1e4, 1e5] if not quick else [1e2, 1e4]
    cases = [
        (
            f"eta_max = {c:g} rho sqrt(g L^3)",
            "zhou-planar",
            [*base, f"material.viscosity_cap_scaled={c}"],
        )
        for c in caps
    ]
    # D/d = 5: grains of D/5 (the continuum knows no grain size but through I);
    # a tall silo, H/L = 20, filled to 19.5 L; each also with eta_max = 1e4
    for label, sets in (
        ("D/d = 5", ["material.grain_diameter=0.005"]),
        ("tall silo H/L = 20", ["silo.height=2.0", "silo.fill_height=1.95"]),
    ):
        cases.append((label, "zhou-planar", [*base, *sets]))
        if not quick:
            cases.append(
                (
                    f"{label}, eta_max = 1e4",
                    "zhou-planar",
                    [*base, *sets, "material.viscosity_cap_scaled=1e4"],
                )
            )
    if not quick:
        lab_gas = [
            "mesh.cells_across=48",
            "run.max_delta_t=0.001",
            "run.end_time=0.3",
            "run.write_interval=0.15",
            'gas.mode="injection"',
            "gas.q_air_lpm=50",
            "material.grain_diameter=124e-6",
        ]
        # industrial scale, 3D (eccentric outlet), coarse; free discharge (no feeder)
        venier2 = ["mesh.cells_across=24", "run.end_time=5.0", "run.write_interval=2.5"]
        closed = [
            "mesh.cells_across=48",
            "run.max_delta_t=0.001",
            "run.end_time=0.6",
            "run.write_interval=0.3",
            'gas.mode="closed-top"',
        ]
        for label, preset, sets in (
            ("lab silo, d = 538 um, closed top (Q_air = 0)", "zhou-cyl-bottom", closed),
            ("lab silo, d = 124 um, Q_air = 50 L/min", "zhou-cyl-bottom", lab_gas),
            ("Venier Test 2, D = 4.2 m, eccentric outlet, 3D", "venier-test2", venier2),
        ):
            cases.append((label, preset, sets))
            cases.append(
                (f"{label}, eta_max = 1e4", preset, [*sets, "material.viscosity_cap_scaled=1e4"])
            )
    # where the axisymmetric lab silo breaks: 24 across (4 cells over the
    # orifice), and 48 across with the default step cap
    lab = ["run.end_time=0.1", "run.write_interval=0.1"]
    cases.append(("lab silo wedge, 24 across", "zhou-cyl-bottom", [*lab, "mesh.cells_across=24"]))
    if not quick:
        cases.append(
            (
                "lab silo wedge, 48 across, default step cap",
                "zhou-cyl-bottom",
                [*lab, "mesh.cells_across=48"],
            )
        )
    rows = _run(cases, work / "extremes", jobs, limit)
    # does the rate depend on the cap? each row against its default-cap twin
    q = {r["label"]: r.get("Q") for r in rows}
    for r in rows:
        label = r["label"]
        twin = (
            "eta_max = 100 rho sqrt(g L^3)"
            if label.startswith("eta_max")
            else label.replace(", eta_max = 1e4", "")
            if label.endswith("eta_max = 1e4")
            else None
        )
        ref = q.get(twin) if twin else None
        r["vs_default_cap"] = r["Q"] / ref - 1 if r.get("Q") and ref else None
    return {"rows": rows}


# --------------------------------------------------------------------- suite
ENTRIES = {
    "work-precision": work_precision,
    "beverloo": beverloo,
    "gas-lab": gas_lab,
    "extremes": extremes,
}


def checks(result: dict[str, Any]) -> list[Check]:
    """Return the suite's figures with their tolerances."""
    out: list[Check] = []
    wp = result.get("work-precision")
    if wp:
        planar = wp["zhou-planar"]["rows"]
        for r in planar:
            out.append(
                Check(
                    "work-precision",
                    f"planar {r['cells_across']} across: Q*",
                    r.get("Q_dimensionless"),
                    0.136,
                    0.184,
                    "Zhou Fig. 4a: 0.16; coarse grids within 15%",
                )
            )
        axi = wp["zhou-cyl-bottom"]["rows"]
        q = [r.get("Q") for r in axi]
        up = 1.0 if all(q) and all(b > a for a, b in zip(q[:-1], q[1:], strict=True)) else 0.0
        out.append(
            Check(
                "work-precision",
                "lab silo: Q rises with resolution",
                up,
                1.0,
                1.0,
                "measured: first order in the cell size, from below",
            )
        )
        at72 = next((r.get("Q") for r in axi if r["cells_across"] == 72), None)
        out.append(
            Check(
                "work-precision",
                "lab silo, 72 across, 0.3 s: Q [kg/s]",
                at72,
                0.0300 * 0.97,
                0.0300 * 1.03,
                "the demo's 0.0300 kg/s (README), within the 2% spread of Q",
            )
        )
    bev = result.get("beverloo")
    if bev:
        fit = bev["venier"].get("fit", {})
        out.append(
            Check(
                "beverloo",
                "Venier Test 1: R^2 of W = C (d - f)^2.5",
                fit.get("R2"),
                0.99,
                1.0,
                "Venier et al.: R^2 > 0.99",
            )
        )
        pfit = bev["planar"].get("fit", {})
        out.append(
            Check(
                "beverloo",
                "planar: C of Q = C rho sqrt(g) (D - f)^1.5",
                pfit.get("C_dimensionless"),
                1.28 * 0.8,
                1.28 * 1.2,
                "continuum C = 1.28 (Zhou: 0.16 at D = L/4), 20%",
            )
        )
    gl = result.get("gas-lab")
    if gl:
        for r in gl["rows"]:
            if r["q_air_lpm"] == 12.0 and r["grain_diameter"] == 538e-6:
                out.append(
                    Check(
                        "gas-lab",
                        "d = 538 um, 12 L/min: Q/Q0 over eq. 23's",
                        (r["sim_ratio"] / r["eq23_ratio"] if r.get("sim_ratio") else None),
                        0.8,
                        1.2,
                        "the rate fluctuates ~20%; its mean over ~7 correlation times: SE ~8%",
                    )
                )
    ext = result.get("extremes")
    if ext:
        for r in ext["rows"]:
            done = (
                1.0
                if r["outcome"] in ("steady", "not steady")
                or r["outcome"].startswith("stopped: diverged")
                else 0.0
            )
            out.append(
                Check(
                    "extremes",
                    f"{r['label']}: ran or stopped with a diagnosis",
                    done,
                    1.0,
                    1.0,
                    "no hang, no crash without a diagnosis",
                )
            )
    return out


def run_suite(
    quick: bool,
    out_dir: Path,
    work_dir: Path,
    only: list[str] | None = None,
    jobs: int = 2,
    limit: float = 900.0,
) -> dict[str, Any]:
    """Run the suite; write ``suite[-quick].json`` and ``.md`` with plots into ``out_dir``."""
    from foamsilo.bench import _git_commit, machine_info

    names = only or list(ENTRIES)
    bad = [n for n in names if n not in ENTRIES]
    if bad:
        raise FoamsiloError(f"unknown suite entry {bad[0]!r}; valid: " + ", ".join(ENTRIES))
    stem = "suite-quick" if quick else "suite"
    result: dict[str, Any] = {}
    previous = out_dir / f"{stem}.json"
    if only and previous.exists():
        # a partial rerun updates its entries in the existing report
        result = json.loads(previous.read_text())
        result.pop("checks", None)
    commits = result.get("commits") or {k: result.get("commit") for k in ENTRIES if k in result}
    timing = result.get("wall_s", {})
    result.update({"quick": quick, "machine": machine_info(), "jobs": jobs})
    for name in names:
        t0 = time.perf_counter()
        result[name] = ENTRIES[name](quick, Path(work_dir) / name, jobs, limit)
        timing[name] = time.perf_counter() - t0
        commits[name] = _git_commit()
    result["wall_s"] = timing
    result["commits"] = commits
    result["commit"] = ", ".join(sorted(set(commits.values()), key=str))
    result["checks"] = [{**asdict(c), "passed": c.passed} for c in checks(result)]
    out_dir.mkdir(parents=True, exist_ok=True)
    plot_work_precision(result, out_dir / f"{stem}-work-precision.png")
    plot_beverloo(result, out_dir / f"{stem}-beverloo.png")
    plot_time_steps(result, out_dir / f"{stem}-time-steps.png")
    write_whole(out_dir / f"{stem}.json", json.dumps(result, indent=1, default=str) + "\n")
    write_whole(out_dir / f"{stem}.md", suite_markdown(result, stem))
    return result


# ------------------------------------------------------------------- output
def plot_work_precision(result: dict[str, Any], path: Path) -> None:
    """Error against the finest resolution over wall time (work-precision)."""
    from foamsilo.plots import finish, labelled_loglog, subplots

    wp = result.get("work-precision")
    if not wp:
        return
    fig, ax = subplots(size=(6, 4.2))
    for preset, data in wp.items():
        rows = [r for r in data["rows"][:-1] if r.get("err_vs_finest")]
        labelled_loglog(ax, rows, "wall_s", "err_vs_finest", "cells_across", f"{preset} (N across)")
    for level in (5, 2):
        ax.axhline(level, color="0.6", ls=":", lw=1)
    ax.set_xlabel("wall time per case [s] (one core)")
    ax.set_ylabel("|Q - Q(finest)| / Q(finest) [%]")
    finish(fig, ax, path)


def plot_beverloo(result: dict[str, Any], path: Path) -> None:
    """Q against outlet size with the fitted Beverloo laws."""
    from foamsilo.plots import finish, subplots

    bev = result.get("beverloo")
    if not bev:
        return
    fig, axes = subplots(2, (11, 4.2))
    for ax, key, exp, unit in (
        (axes[0], "venier", 2.5, "kg/s"),
        (axes[1], "planar", 1.5, "kg/(m s)"),
    ):
        rows = [r for r in bev[key]["rows"] if r.get("Q")]
        d = np.array([r["orifice_m"] for r in rows])
        ax.plot(d * 100, [r["Q"] for r in rows], "ko", label="siloFoam, steady Q")
        fit = bev[key].get("fit")
        if fit:
            dd = np.linspace(max(fit["f"], 0.0) + 1e-4, d.max() * 1.1, 100)
            ax.plot(
                dd * 100,
                fit["C"] * (dd - fit["f"]) ** exp,
                "C3-",
                label=f"W = C (d - f)^{exp}: C = {fit['C']:.4g}, f = {fit['f'] * 100:.2f} cm, "
                f"R^2 = {fit['R2']:.4f}",
            )
        ax.set_xlabel("outlet size [cm]")
        ax.set_ylabel(f"Q [{unit}]")
        ax.set_title(
            "Venier Test 1 (axisymmetric)" if key == "venier" else "Zhou planar silo", fontsize=9
        )
    finish(fig, axes, path, legend_size=7)


def plot_time_steps(result: dict[str, Any], path: Path) -> None:
    """Time-step histories of the stiff and extreme cases."""
    from foamsilo.plots import finish, subplots

    ext = result.get("extremes")
    if not ext:
        return
    fig, ax = subplots(size=(7, 4.5))
    for r in ext["rows"]:
        h = np.array(r.get("dt_history") or [])
        if h.size:
            ax.semilogy(h[:, 0], h[:, 1], lw=1, label=f"{r['label']}: {r['outcome']}")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("time step [s]")
    finish(fig, ax, path, legend_size=6)


def _fmt(v: Any, spec: str) -> str:
    return "-" if v is None or (isinstance(v, float) and not math.isfinite(v)) else format(v, spec)


def suite_markdown(result: dict[str, Any], stem: str) -> str:
    """Return the suite's report (Markdown)."""
    m = result["machine"]
    cmd = "foamsilo bench --quick" if result["quick"] else "foamsilo bench"
    lines = [
        f"# Validation suite{' (quick)' if result['quick'] else ''}",
        "",
        f"`{cmd}` on {m['cpu']}, {m['cores']} cores, {result['jobs']} cases at a time; "
        f"commit {result['commit']}. Wall time per entry: "
        + ", ".join(f"{k} {v / 60:.1f} min" for k, v in result["wall_s"].items())
        + ".",
        "",
    ]
    wp = result.get("work-precision")
    if wp:
        lines += [
            "## Error against run time",
            "",
            f"![work precision]({stem}-work-precision.png)",
            "",
        ]
        for preset, data in wp.items():
            lines += [
                f"**{preset}** (law: {data['law']}, Q = {data['Q_law']:.5g}); resolution "
                f"for 5%: {data['recommend_5pct']} across, for 2%: "
                f"{data['recommend_2pct']} across (against the finest).",
                "",
                "| cells across | cells | Q | Q* | vs finest | vs law | wall [s] | CPU [s] | "
                "steps |",
                "| --- | --- | --- | --- | --- | --- | --- | --- | --- |",
            ]
            for r in data["rows"]:
                lines.append(
                    f"| {r['cells_across']} | {_fmt(r.get('cells'), 'd')} "
                    f"| {_fmt(r.get('Q'), '.5g')} | {_fmt(r.get('Q_dimensionless'), '.4f')} "
                    f"| {_fmt(r.get('err_vs_finest'), '.1%')} "
                    f"| {_fmt(r.get('err_vs_law'), '+.1%')} | {_fmt(r.get('wall_s'), '.0f')} "
                    f"| {_fmt(r.get('cpu_s'), '.0f')} | {_fmt(r.get('steps'), 'd')} |"
                )
            lines.append("")
    bev = result.get("beverloo")
    if bev:
        lines += ["## Beverloo scaling", "", f"![Beverloo]({stem}-beverloo.png)", ""]
        for key, title in (
            ("venier", "Venier Test 1, W = C (d - f)^2.5"),
            ("planar", "planar silo, Q = C rho sqrt(g) (D - f)^1.5"),
        ):
            fit = bev[key].get("fit") or {}
            lines += [
                f"**{title}**: C = {_fmt(fit.get('C'), '.4g')}, f = "
                f"{_fmt(fit.get('f'), '.4f')} m, R² = {_fmt(fit.get('R2'), '.4f')}"
                + (f", C/(ρ√g) = {fit['C_dimensionless']:.3f}" if "C_dimensionless" in fit else "")
                + ".",
                "",
                "| outlet [m] | Q | Q std | outcome | wall [s] |",
                "| --- | --- | --- | --- | --- |",
            ]
            for r in bev[key]["rows"]:
                lines.append(
                    f"| {r['orifice_m']:g} | {_fmt(r.get('Q'), '.5g')} "
                    f"| {_fmt(r.get('Q_std'), '.2g')} | {r['outcome']} "
                    f"| {_fmt(r.get('wall_s'), '.0f')} |"
                )
            lines.append("")
    ext = result.get("extremes")
    if ext:
        lines += [
            "## Stiff and extreme cases",
            "",
            f"![time steps]({stem}-time-steps.png)",
            "",
            "| case | outcome | Q | vs default cap | steps | Δt min – max [s] | wall [s] |",
            "| --- | --- | --- | --- | --- | --- | --- |",
        ]
        for r in ext["rows"]:
            lines.append(
                f"| {r['label']} | {r['outcome']} | {_fmt(r.get('Q'), '.5g')} "
                f"| {_fmt(r.get('vs_default_cap'), '+.1%')} | {_fmt(r.get('steps'), 'd')} "
                f"| {_fmt(r.get('dt_min'), '.2g')} – {_fmt(r.get('dt_max'), '.2g')} "
                f"| {_fmt(r.get('wall_s'), '.0f')} |"
            )
        lines += [""] + [
            f"* **{r['label']}**: {r['detail']}" for r in ext["rows"] if r.get("detail")
        ]
        lines.append("")
    gl = result.get("gas-lab")
    if gl:
        lines += [
            "## Gas-assisted lab silo against eq. 23",
            "",
            "Zhou Table I cylinder, axisymmetric, 48 across. Q: the time mean of the "
            "orifice rate after 1.5 sqrt(L/g) (the gas-driven rate fluctuates by 10-20%, "
            "more than the 5% of the steady criterion), with its standard deviation; Q/Q0 "
            "against the same grains with the open top, compared with eq. 23 (Table I "
            "constants, A = 1).",
            "",
            "| case | Q [kg/s] | Q/Q0 simulated | Q/Q0 eq. 23 | difference | wall [s] |",
            "| --- | --- | --- | --- | --- | --- |",
        ]
        for r in gl["rows"]:
            q = f"{_fmt(r.get('Q_mean'), '.4g')} ± {_fmt(r.get('Q_mean_std'), '.2g')}"
            lines.append(
                f"| {r['label']} | {q} | {_fmt(r.get('sim_ratio'), '.3f')} "
                f"| {_fmt(r.get('eq23_ratio'), '.3f')} | {_fmt(r.get('rel_error'), '+.1%')} "
                f"| {_fmt(r.get('wall_s'), '.0f')} |"
            )
        notes = [
            f"* **{r['label']}**: {r['outcome']}: {r['detail']}"
            for r in gl["rows"]
            if r.get("detail") and r.get("Q_mean") is None
        ]
        lines += ["", *notes, ""]
    lines += [
        "## Checks",
        "",
        "| entry | figure | value | allowed | why | |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for c in result["checks"]:
        lines.append(
            f"| {c['entry']} | {c['name']} | {_fmt(c['value'], '.4g')} "
            f"| [{c['low']:g}, {c['high']:g}] | {c['why']} "
            f"| {'pass' if c['passed'] else '**FAIL**'} |"
        )
    return "\n".join(lines) + "\n"
