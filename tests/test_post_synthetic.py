"""Steady-state detection and mass balance on exactly known series."""

from __future__ import annotations

import numpy as np
import pytest

from foamsilo.post import Discharge, find_steady, read_function_object
from foamsilo.scene import load_preset


def synthetic(
    q_plateau: float, t_end: float, tau: float, drift: float = 0.0, overshoot: float = 0.0
) -> Discharge:
    """Q(t) = Q0 (1 - exp(-t/tau)) (1 + drift t) (1 + overshoot e^(-t/0.08) sin(t/0.02)).

    The volume comes from exact integration of the same series.
    """
    scene = load_preset("zhou-planar")
    t = np.linspace(1e-4, t_end, 4000)
    dt = np.diff(np.concatenate([[0.0], t]))
    q = q_plateau * (1 - np.exp(-t / tau)) * (1 + drift * t)
    q *= 1 + overshoot * np.exp(-t / 0.08) * np.sin(t / 0.02)
    v0 = scene.silo.width * scene.silo.fill_height
    v = v0 - np.cumsum(q * dt)
    return scene, Discharge(t, dt, q, v, v0, 1.0, 1.0)


def test_plateau_found_and_both_estimates_agree():
    scene, d = synthetic(q_plateau=1e-3, t_end=1.0, tau=0.02)
    st = find_steady(d, scene)
    assert st.steady
    # the window opens once Q is inside the 2% band, so the tail of the
    # exponential (integral ~ tau * 2% / window) biases the mean by < 1e-3
    assert st.q == pytest.approx(1e-3, rel=1e-3)
    assert st.q_from_volume == pytest.approx(1e-3, rel=1e-3)
    assert 0.02 * np.log(50) - 0.01 <= st.t_start < 0.1
    assert st.q_std < 0.01 * 1e-3
    assert d.mass_balance_error < 1e-12


def test_grains_through_the_top_count_in_the_mass_balance():
    scene, d = synthetic(q_plateau=1e-3, t_end=1.0, tau=0.02)
    lost = np.where(d.time < 0.1, 1e-4, 0.0)  # grains splashed out at the top early on
    d.volume = d.volume - np.cumsum(lost * d.delta_t)
    assert d.mass_balance_error > 1e-4  # without the top flux the books do not close
    d.top_flux = lost
    assert d.mass_balance_error < 1e-12
    assert d.top_loss == pytest.approx(1e-4 * 0.1 / d.initial_volume, rel=1e-2)


def test_overshooting_start_up_is_left_out_of_the_window():
    # a damped oscillation (50% swing) crosses the plateau band early; the
    # window must open once the smoothed rate has stopped leaving the 5%
    # excursion band, not at its first crossing (which keeps the swing in the
    # window and calls the run unsteady)
    scene, d = synthetic(q_plateau=1e-3, t_end=1.0, tau=0.02, overshoot=0.5)
    st = find_steady(d, scene)
    assert st.steady, st.reason
    assert st.t_start > 0.15  # measured 0.181; the first crossing is at 0.05 s
    # what is left of the swing (< 5%, decaying) biases the mean by < 0.2%
    assert st.q == pytest.approx(1e-3, rel=2e-3)


def test_drifting_rate_is_not_steady():
    scene, d = synthetic(q_plateau=1e-3, t_end=1.0, tau=0.02, drift=0.2)
    st = find_steady(d, scene)
    assert not st.steady


def test_run_too_short_is_reported():
    scene, d = synthetic(q_plateau=1e-3, t_end=0.05, tau=0.02)
    st = find_steady(d, scene)
    assert not st.steady and "too short" in st.reason


def test_function_object_files_are_merged_over_restarts(tmp_path):
    root = tmp_path / "postProcessing" / "orificeFlow"
    (root / "0").mkdir(parents=True)
    (root / "0.2").mkdir()
    hdr = "# Time\tsum(alphaPhi0.granular)\tsum(phi)\n"
    (root / "0" / "surfaceFieldValue.dat").write_text(
        hdr + "".join(f"{t:.2f}\t{t}\t{t}\n" for t in (0.1, 0.2, 0.3, 0.4))
    )
    (root / "0.2" / "surfaceFieldValue.dat").write_text(
        hdr + "".join(f"{t:.2f}\t{10 * t}\t{t}\n" for t in (0.3, 0.4, 0.5))
    )
    s = read_function_object(tmp_path, "orificeFlow")
    cols, data = s.columns, s.data
    assert cols[0] == "Time"
    assert data[:, 0].tolist() == [0.1, 0.2, 0.3, 0.4, 0.5]
    assert data[2:, 1].tolist() == [3.0, 4.0, 5.0]  # the restart's rows win


def test_a_row_cut_short_by_a_kill_is_dropped(tmp_path):
    root = tmp_path / "postProcessing" / "orificeFlow" / "0"
    root.mkdir(parents=True)
    hdr = "# Time\tsum(alphaPhi0.granular)\tsum(phi)\n"
    # kill -9 while OpenFOAM wrote the third row: "0.3 3.25e" with no newline
    (root / "surfaceFieldValue.dat").write_text(hdr + "0.1\t1.5\t1\n0.2\t2.5\t2\n0.3\t3.25e")
    s = read_function_object(tmp_path, "orificeFlow")
    assert s.data[:, 0].tolist() == [0.1, 0.2]
    assert s.data[:, 1].tolist() == [1.5, 2.5]
    assert "cut short" in s.notes[0]  # dropped, and said so


HDR = "# Time\tsum(alphaPhi0.granular)\tsum(phi)\n"


@pytest.mark.parametrize(
    ("body", "line", "words"),
    [
        # a garbage line in the middle of the table (not a cut last row)
        (b"0.1\t1.5\t1\nhello world\n0.3\t3.5\t3\n", 3, "not a row of numbers"),
        # binary bytes where a row should be
        (b"0.1\t1.5\t1\n\x00\x01\xff\xfe\n0.3\t3.5\t3\n", 3, "not text"),
        # the solver wrote NaN: the run diverged
        (b"0.1\t1.5\t1\n0.2\tnan\t2\n0.3\t3.5\t3\n", 3, "sum(alphaPhi0.granular) is nan"),
        # a row with a missing column (not at the end)
        (b"0.1\t1.5\t1\n0.2\t2.5\n0.3\t3.5\t3\n", 3, "2 values where the rows above have 3"),
    ],
)
def test_damaged_output_is_refused_naming_the_file_and_line(tmp_path, body, line, words):
    from foamsilo.post import DamagedOutputError

    root = tmp_path / "postProcessing" / "orificeFlow" / "0"
    root.mkdir(parents=True)
    f = root / "surfaceFieldValue.dat"
    f.write_bytes(HDR.encode() + body)
    with pytest.raises(DamagedOutputError) as err:
        read_function_object(tmp_path, "orificeFlow")
    assert f"{f}:{line}" in str(err.value)
    assert words in str(err.value)


def test_a_kill_between_the_two_outputs_keeps_the_mass_balance(tmp_path):
    """kill -9 after the flux row of t = 0.3 was written but before the volume's:
    the restart goes on from 0.3; the series are merged on their common times
    and the flux of the orphan step is carried into the next one."""
    from foamsilo.post import read_discharge

    scene = load_preset("zhou-planar")
    depth = scene.mesh_fraction
    pp = tmp_path / "postProcessing"
    t = [0.1, 0.2, 0.3, 0.4, 0.5]
    q = {0.1: 1.0, 0.2: 2.0, 0.3: 3.0, 0.4: 4.0, 0.5: 5.0}  # volume flux per step
    v, vol = {}, 100.0
    for ti in t:
        vol -= q[ti] * 0.1
        v[ti] = vol
    for name, rows_old, rows_new, value in (
        ("orificeFlow", [0.1, 0.2, 0.3], [0.4, 0.5], lambda x: f"{q[x]}\t0"),
        ("granularVolume", [0.1, 0.2], [0.4, 0.5], lambda x: f"{v[x]}"),
    ):
        for start, rows in (("0", rows_old), ("0.3", rows_new)):
            d = pp / name / start
            d.mkdir(parents=True)
            d.joinpath("f.dat").write_text(
                "# Time\tx\n" + "".join(f"{r}\t{value(r)}\n" for r in rows)
            )
    d = read_discharge(tmp_path, scene)
    assert d.time.tolist() == [0.1, 0.2, 0.4, 0.5]
    # the step ending at 0.4 carries the outflow of 0.2-0.4: (3 + 4) * 0.1 over 0.2 s
    assert d.volume_flux * depth == pytest.approx([1.0, 2.0, 3.5, 5.0])
    assert d.mass_balance_error < 1e-12


def test_a_restart_drops_the_abandoned_steps_after_its_start(tmp_path):
    """A run killed after t = 0.35 resumes from 0.3 with a longer first step (0.3-0.4).

    The abandoned run's step ending at 0.35 is not the restart's: kept (it
    precedes the restart's first row), it put the abandoned run's outflow
    over 0.3-0.35 beside the restart's volume, and the mass balance of a
    resumed run was off by 2.5e-6 (tests/test_running.py, seen once under
    load).
    """
    from foamsilo.post import read_discharge

    scene = load_preset("zhou-planar")
    pp = tmp_path / "postProcessing"
    old = {0.1: 1.0, 0.2: 1.0, 0.3: 1.0, 0.35: 7.0}  # the abandoned run's flux
    new = {0.4: 2.0, 0.5: 2.0}  # the restart's: 0.3-0.4, 0.4-0.5
    vol, v = 100.0, {}
    for t, dt, q in ((0.1, 0.1, 1.0), (0.2, 0.1, 1.0), (0.3, 0.1, 1.0), (0.4, 0.1, 2.0),
                     (0.5, 0.1, 2.0)):  # fmt: skip
        vol -= q * dt
        v[t] = vol
    v_old = {**{t: v[t] for t in (0.1, 0.2, 0.3)}, 0.35: v[0.3] - 7.0 * 0.05}
    for name, rows_old, rows_new in (
        ("orificeFlow", {t: f"{q}\t0" for t, q in old.items()},
         {t: f"{q}\t0" for t, q in new.items()}),
        ("granularVolume", {t: f"{x}" for t, x in v_old.items()},
         {t: f"{v[t]}" for t in new}),
    ):  # fmt: skip
        for start, rows in (("0", rows_old), ("0.3", rows_new)):
            d = pp / name / start
            d.mkdir(parents=True)
            d.joinpath("f.dat").write_text(
                "# Time\tx\n" + "".join(f"{t}\t{r}\n" for t, r in rows.items())
            )
    d = read_discharge(tmp_path, scene)
    assert d.time.tolist() == [0.1, 0.2, 0.3, 0.4, 0.5]
    assert d.volume_flux * scene.mesh_fraction == pytest.approx([1.0, 1.0, 1.0, 2.0, 2.0])
    assert d.mass_balance_error < 1e-12


def _noisy(sigma: float, corr_steps: int, n: int = 20000, seed: int = 1):
    """A plateau of 1 with AR(1) noise of standard deviation sigma, correlated over corr_steps."""
    rng = np.random.default_rng(seed)
    phi = np.exp(-1.0 / corr_steps)
    e = np.empty(n)
    e[0] = rng.normal()
    for k in range(1, n):
        e[k] = phi * e[k - 1] + np.sqrt(1 - phi**2) * rng.normal()
    t = np.arange(1, n + 1) * 1e-3
    return t, 1.0 + sigma * e, np.full(n, 1e-3), phi


@pytest.mark.parametrize("corr_steps", [1, 50])
def test_batch_means_give_the_error_of_a_correlated_mean(corr_steps):
    """The standard error of the mean of an AR(1) series is sigma sqrt((1 + phi)/((1 - phi) n)).

    One batch-means estimate (10 batches) scatters by ~1/sqrt(2 x 9) = 24%, so the
    estimator is judged over 20 realisations: their mean has a spread of ~5%, and the
    test allows 15% (the estimator's own small bias included: 10 batches of a
    correlated series underestimate by ~(correlation time / batch span)).
    """
    from foamsilo.post.steady import batch_means_error

    errs, exact = [], None
    for seed in range(20):
        t, q, dt, phi = _noisy(0.05, corr_steps, n=10000, seed=seed)
        exact = 0.05 * np.sqrt((1 + phi) / ((1 - phi) * len(t)))
        errs.append(batch_means_error(t, q, dt))
    assert np.mean(errs) == pytest.approx(exact, rel=0.15)
    # the naive error (independent samples) underestimates a correlated one
    if corr_steps > 1:
        assert np.mean(errs) > 3 * 0.05 / np.sqrt(len(t))


def test_the_window_is_judged_on_the_orifice_time_scale():
    """A plateau of 2.5 sqrt(D/g) is a steady window; it is shorter than sqrt(L/g)."""
    scene = load_preset(
        "zhou-planar", ["silo.width=0.4", "silo.height=0.8", "silo.fill_height=0.7"]
    )
    T_d, T_L = scene.discharge_time_scale, scene.time_scale
    assert T_d < 0.5 * T_L
    t = np.linspace(1e-4, 3.6 * T_d, 4000)
    dt = np.diff(np.concatenate([[0.0], t]))
    q = 1e-3 * (1 - np.exp(-t / (0.05 * T_d)))
    v0 = scene.silo.width * scene.silo.fill_height
    d = Discharge(t, dt, q, v0 - np.cumsum(q * dt), v0, 1.0, 1.0)
    st = find_steady(d, scene)
    assert st.steady, st.reason
    assert st.t_end - st.t_start < T_L  # a plateau the silo width's scale would refuse
    assert st.q == pytest.approx(1e-3, rel=1e-3)


def test_a_rate_swinging_from_step_to_step_is_told_from_a_slow_wander():
    from foamsilo.post.steady import STEP_SWING_WARNING, step_swing

    # the lab silo's second branch at small steps: +-3% with a period of 4 steps
    scene, d = synthetic(q_plateau=1e-3, t_end=1.0, tau=0.02)
    k = np.arange(d.time.size)
    d.volume_flux = d.volume_flux * (1 + 0.03 * np.sin(np.pi * k / 2 + 0.3))
    st = find_steady(d, scene)
    assert st.steady  # the mean is flat: the steady test alone cannot see it
    # a sine of amplitude a has std a/sqrt(2); its step-to-step swing is the
    # same at a period of 4 steps (quarter-period differences are a sqrt(2))
    assert st.step_swing == pytest.approx(0.03 / np.sqrt(2), rel=0.02)
    assert st.step_swing > STEP_SWING_WARNING
    # the same 3% as a slow wander (a period of 0.25 s, 1000 steps): no swing
    slow = 1e-3 * (1 + 0.03 * np.sin(2 * np.pi * d.time / 0.25))
    assert step_swing(slow) < 0.02 * STEP_SWING_WARNING
    assert np.std(slow) / np.mean(slow) > 0.02  # though its std is as large


def _emptying(collapse_at: float) -> tuple:
    """A steady rate that halves once the silo holds ``collapse_at`` of its fill.

    The series ends 0.1 s (2 sqrt(D/g)) after the fall, so that the fall is
    the run's last word and not a second plateau.
    """
    scene = load_preset("zhou-planar")
    v0 = scene.silo.width * scene.silo.fill_height
    t = np.linspace(1e-4, 1.0, 4000)
    dt = np.diff(np.concatenate([[0.0], t]))
    q = 1.2 * v0 * (1 - np.exp(-t / 0.02))  # empties the silo in ~0.8 s
    k = int(np.argmax(v0 - np.cumsum(q * dt) < collapse_at * v0))
    q[k:] *= 0.5
    n = int(np.searchsorted(t, t[k] + 0.1))
    v = v0 - np.cumsum(q * dt)
    return scene, Discharge(t[:n], dt[:n], q[:n], v[:n], v0, 1.0, 1.0), t[k]


def test_the_end_of_an_emptying_discharge_is_cut_from_the_window():
    """Air ejecting a column: a steady rate until the bed is thin, then a fall."""
    scene, d, t_fall = _emptying(0.15)
    st = find_steady(d, scene)
    assert st.steady, st.reason
    assert st.t_end < t_fall  # the window ends before the fall...
    assert st.t_end > t_fall - 2 * scene.discharge_time_scale  # ...not long before
    assert st.q == pytest.approx(1.2 * d.initial_volume, rel=1e-3)


def test_a_fall_while_the_silo_is_still_full_is_no_end_of_discharge():
    scene, d, _ = _emptying(0.4)
    st = find_steady(d, scene)
    assert not st.steady
