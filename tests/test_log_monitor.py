"""The log monitor: step table and divergence detection on real-format lines."""

from __future__ import annotations

import csv
import math

import pytest

from foamsilo.run import LogMonitor

STEP = """Courant Number mean: {co_mean} max: {co}
Interface Courant Number mean: 0.01 max: {aco}
Granular Courant Number max: {gco}
deltaT = {dt}
Time = {t}

PIMPLE: iteration 1
smoothSolver:  Solving for alpha.granular, Initial residual = 1e-05, Final residual = 1e-12, No Iterations 1
DILUPBiCGStab:  Solving for Ux, Initial residual = {ru}, Final residual = 1e-09, No Iterations 3
DILUPBiCGStab:  Solving for Uy, Initial residual = 0.001, Final residual = 1e-09, No Iterations 3
GAMG:  Solving for p_rgh, Initial residual = {rp}, Final residual = 5e-08, No Iterations 9
time step continuity errors : sum local = 1e-09, global = 1e-10, cumulative = 1e-08
ExecutionTime = {ex} s  ClockTime = 1 s
"""


def feed_steps(mon, n, **kw):
    t = 0.0
    for i in range(n):
        dt = kw.get("dt", 1e-4)
        t += dt
        vals = dict(
            co_mean=0.1, co=0.4, aco=0.2, gco=0.3, dt=dt, t=t, ru=0.01, rp=0.1, ex=0.01 * (i + 1)
        )
        vals.update({k: v for k, v in kw.items() if k != "dt"})
        for line in STEP.format(**vals).splitlines():
            mon.feed(line)


def test_steps_are_tabulated(tmp_path):
    mon = LogMonitor(0.5, 0.5, 0.0)
    feed_steps(mon, 30)
    assert len(mon.steps) == 30
    s = mon.steps[-1]
    assert s.time == pytest.approx(30e-4) and s.delta_t == 1e-4
    assert s.courant == 0.4 and s.interface_courant == 0.2 and s.granular_courant == 0.3
    assert s.residuals == {"alpha.granular": 1e-05, "Ux": 0.01, "Uy": 0.001, "p_rgh": 0.1}
    assert s.iterations["p_rgh"] == 9
    assert s.continuity == 1e-9
    assert mon.divergence is None
    mon.write_table(tmp_path / "steps.csv")
    rows = (tmp_path / "steps.csv").read_text().splitlines()
    assert len(rows) == 31 and rows[0].startswith("time,delta_t,courant")


OUTER = "Outer iteration {k}: grains' velocity change rms {rms} m/s, largest {big} of the fastest grain's speed"


def test_each_outer_iteration_s_change_is_tabulated(tmp_path):
    # siloFoam's line, as it prints it, after each outer iteration's pressure solve
    mon = LogMonitor(0.5, 0.5, 0.0)
    feed_steps(mon, 2)
    for k, rms in enumerate([6.7e-05, 3.9e-05, 2.2e-05], start=1):
        mon.feed(OUTER.format(k=k, rms=rms, big=0.006))
    assert mon.steps[0].outer_changes == []
    assert mon.steps[-1].outer_changes == [6.7e-05, 3.9e-05, 2.2e-05]
    mon.write_table(tmp_path / "steps.csv")
    with open(tmp_path / "steps.csv") as f:
        rows = list(csv.DictReader(f))
    assert rows[0]["outer_iterations"] == "" and rows[0]["outer_change_last"] == ""
    assert rows[1]["outer_iterations"] == "3"
    assert float(rows[1]["outer_change_first"]) == 6.7e-05
    assert float(rows[1]["outer_change_last"]) == 2.2e-05


def test_nan_residual_is_divergence():
    mon = LogMonitor(0.5, 0.5)
    feed_steps(mon, 10)
    feed_steps(mon, 1, rp="nan")
    d = mon.divergence
    assert d is not None and d.quantity == "p_rgh residual"
    assert math.isclose(d.time, 1e-4)


def test_courant_far_above_the_limit_is_divergence():
    mon = LogMonitor(0.5, 0.5)
    feed_steps(mon, 5)
    feed_steps(mon, 1, co=12.0)  # 24 x the limit
    assert mon.divergence is not None and mon.divergence.quantity == "Courant number"
    assert "12" in mon.divergence.detail


def test_courant_above_limit_but_not_far_is_not_divergence():
    mon = LogMonitor(0.5, 0.5)
    feed_steps(mon, 5, co=2.0)
    assert mon.divergence is None


def test_collapsing_time_step_is_divergence():
    mon = LogMonitor(0.5, 0.5)
    feed_steps(mon, 30, dt=1e-4)
    feed_steps(mon, 1, dt=1e-9)
    assert mon.divergence is not None and mon.divergence.quantity == "deltaT"


def test_fatal_error_is_collected_not_mistaken_for_the_banner():
    mon = LogMonitor(0.5, 0.5)
    mon.feed("trapFpe: Floating point exception trapping enabled (FOAM_SIGFPE).")
    assert not mon.fatal
    feed_steps(mon, 2)
    mon.feed("--> FOAM FATAL ERROR: ")
    mon.feed("    Maximum number of iterations exceeded")
    assert mon.fatal[0].startswith("--> FOAM FATAL ERROR")
    assert len(mon.steps) == 2


def test_a_step_the_solver_takes_again_is_dropped_and_its_blow_up_not_counted():
    # siloFoam judges a step's volume fraction itself (createStepRetake.H):
    # the monitor must not stop a run on an alpha line the solver then
    # answers by taking the step again with half the step
    mon = LogMonitor(0.5, 0.5)
    feed_steps(mon, 3)
    ok = "Phase-1 volume fraction = 0.9259196003  Min(alpha.granular) = -2.168019742e-26  Max(alpha.granular) = 1.00000113"
    mon.feed(ok)
    assert mon.divergence is None and mon.alpha_max == 1.00000113
    mon.feed("Time = 0.004")
    mon.feed(
        "Phase-1 volume fraction = 0.9258084374  Min(alpha.granular) = -17.34392947  "
        "Max(alpha.granular) = 20.91493569"
    )
    assert mon.divergence is None
    n = len(mon.steps)
    mon.feed(
        "Step retaken (1 of 4): volume fraction alpha.granular between -17.34392947 and "
        "20.91493569 in outer iteration 2, in the step from t = 0.003 with deltaT = 0.001; "
        "taken again with deltaT = 0.0005"
    )
    assert len(mon.steps) == n - 1  # the failed attempt's row is dropped
    assert mon.retakes == [
        {
            "time": 0.003,
            "detail": "volume fraction alpha.granular between -17.34392947 and 20.91493569 "
            "in outer iteration 2",
            "delta_t": 0.001,
            "retake_delta_t": 0.0005,
        }
    ]
    mon.feed("Time = 0.0035")
    mon.feed(ok)
    assert mon.steps[-1].time == 0.0035 and mon.steps[-1].delta_t == 0.0005
    assert mon.alpha_max == 1.00000113 and mon.divergence is None


def test_a_step_that_diverges_after_its_retakes_is_a_divergence():
    mon = LogMonitor(0.5, 0.5)
    feed_steps(mon, 3)
    mon.feed("--> FOAM FATAL ERROR: ")
    mon.feed(
        "Step diverged: volume fraction alpha.granular between -3.1 and 4.2 in outer iteration "
        "3, in the step from t = 0.002 with deltaT = 6.25e-05, after 4 retakes"
    )
    d = mon.divergence
    assert d is not None and d.quantity == "volume fraction" and "-3.1" in d.detail
    assert d.time == mon.steps[-1].time
    # the solver's retake window ends at the start of the step it stopped in
    assert mon.diverged_step_start == 0.002
    mon2 = LogMonitor(0.5, 0.5)
    feed_steps(mon2, 3)
    mon2.feed("--> FOAM FATAL ERROR: ")
    mon2.feed(
        "Step diverged: Courant number 1e+30 (limit 0.5) at its end, in the step from t = 0.002"
    )
    assert mon2.divergence is not None and mon2.divergence.quantity == "Courant number"
    # in a parallel run every rank's error line starts with its number: the
    # same diagnosis, or the runner would not recover it
    mon3 = LogMonitor(0.5, 0.5)
    feed_steps(mon3, 3)
    mon3.feed("[1] --> FOAM FATAL ERROR: ")
    mon3.feed("[1] Step diverged: Courant number 92.9 (limit 0.5) at its end, in the step "
              "from t = 0.0158316702 with deltaT = 0.001314166531, after 0 retakes")  # fmt: skip
    assert mon3.divergence is not None and mon3.divergence.quantity == "Courant number"
    assert mon3.diverged_step_start == 0.0158316702


def test_a_floating_point_trap_is_a_divergence_the_runner_can_recover():
    mon = LogMonitor(0.5, 0.5)
    feed_steps(mon, 3)
    mon.feed("#0  Foam::error::printStack(Foam::Ostream&) at ??:?")
    mon.feed("#1  Foam::sigFpe::sigHandler(int) at ??:?")
    assert mon.divergence is not None and mon.divergence.quantity == "floating-point exception"
    assert mon.fatal  # the stack is kept for the report


def test_a_collapsed_step_is_a_divergence_and_the_run_s_largest_step_is_kept():
    # retakes in consecutive steps can drive the step far down; the recovery
    # caps at half the run's largest step, not at half the collapsed one
    mon = LogMonitor(0.5, 0.5)
    feed_steps(mon, 30, dt=1e-3)
    assert mon.divergence is None and mon.largest_step == 1e-3
    feed_steps(mon, 2, dt=5e-8)
    d = mon.divergence
    assert d is not None and d.quantity == "deltaT" and "collapsed" in d.detail
    assert mon.largest_step == 1e-3
