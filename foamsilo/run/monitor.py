"""siloFoam's log, line by line: one row per time step, and the divergence verdict.

:class:`LogMonitor` keeps, for each time step, the time, the step, the
Courant numbers, the initial residuals and iteration counts, the continuity
error, each outer iteration's change of the grains' velocity (whether the
iterations converge) and the execution time, and decides whether the run
diverged:

* a NaN or Inf in a residual, a Courant number or the time step;
* a Courant number far above its limit (``COURANT_BLOWUP`` times);
* a time step collapsed by ``DT_COLLAPSE`` from the largest one so far;
* siloFoam's own verdict: a step whose outer iterations diverged (the volume
  fraction far outside [0, 1], a Courant number blown up at its end) is taken
  again by the solver with half the step (``Step retaken``, kept in
  :attr:`LogMonitor.retakes`, the failed attempt's row dropped), and once its
  retakes are spent it stops with a fatal error (``Step diverged``).

The regular expressions here read the solver's log, never a dictionary.
"""

from __future__ import annotations

import csv
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

from foamsilo.case.templates import RETAKE_COURANT_FACTOR

#: A Courant number this many times its limit at a step's start: the solver
#: retakes a step that ends so (the same factor), so this is a last resort
COURANT_BLOWUP = RETAKE_COURANT_FACTOR
DT_COLLAPSE = 1e-4
LOG_NAME = "log.siloFoam"
#: One row per time step of the run (written by :meth:`LogMonitor.write_table`)
STEP_TABLE = "steps.csv"

_FLOAT = r"([-+]?(?:\d+\.?\d*(?:[eE][-+]?\d+)?|nan|inf|-nan|-inf))"
_RE_TIME = re.compile(r"^Time = " + _FLOAT + r"\s*$")
_RE_DT = re.compile(r"^deltaT = " + _FLOAT)
_RE_CO = re.compile(r"^Courant Number mean: " + _FLOAT + r" max: " + _FLOAT)
_RE_ACO = re.compile(r"^Interface Courant Number mean: " + _FLOAT + r" max: " + _FLOAT)
_RE_GCO = re.compile(r"^Granular Courant Number max: " + _FLOAT)
_RE_RES = re.compile(
    r"^\w+:\s+Solving for (\S+), Initial residual = "
    + _FLOAT
    + r", Final residual = "
    + _FLOAT
    + r", No Iterations (\d+)"
)
_RE_CONT = re.compile(r"^time step continuity errors : sum local = " + _FLOAT)
_RE_EXEC = re.compile(r"^ExecutionTime = " + _FLOAT + r" s")
_RE_EMPTIED = re.compile(r"^The silo has emptied: .* at t = " + _FLOAT)
_RE_RETAKE = re.compile(
    r"^Step retaken \((\d+) of (\d+)\): (.*), in the step from t = "
    + _FLOAT
    + r" with deltaT = "
    + _FLOAT
    + r"; taken again with deltaT = "
    + _FLOAT
)
#: a step whose outer iterations grew, taken again with half the stress's
#: divergence share (``numerics.outer_growth_limit``)
_RE_SHARE_RETAKE = re.compile(
    r"^Step retaken with half the stress share: outer iterations growing by "
    + _FLOAT
    + r" \(limit "
    + _FLOAT
    + r"\), the last moving a grain by "
    + _FLOAT
    + r" of the fastest grain's speed \(limit "
    + _FLOAT
    + r"\), in the step from t = "
    + _FLOAT
    + r" with deltaT = "
    + _FLOAT
)
#: a step taken again with half the share that failed, taken as the whole
#: share first took it
_RE_SHARE_FALLBACK = re.compile(
    r"^Step retaken at the whole stress share: the step taken again with half of it "
    r"failed \((.*)\), in the step from t = " + _FLOAT + r" with deltaT = " + _FLOAT
)
#: a step that passed, taken again as a check (``run.retake_check_interval``)
_RE_RETAKE_CHECK = re.compile(
    r"^Step retaken for a check: in the step from t = " + _FLOAT + r" with deltaT = " + _FLOAT
)
#: one outer iteration's change of the grains' velocity (rms, m/s, and the
#: largest over the fastest grain's speed): whether the iterations converge
_RE_OUTER = re.compile(
    r"^Outer iteration (\d+): grains' velocity change rms "
    + _FLOAT
    + r" m/s, largest "
    + _FLOAT
    + r" of the fastest grain's speed"
)
_RE_STEP_DIVERGED = re.compile(r"^Step diverged: (volume fraction|Courant number) (.*)$")
#: the rank a parallel run's error lines start with (``[1] Step diverged: ...``)
_RE_RANK = re.compile(r"^\[\d+\]\s*")
_RE_STEP_FROM = re.compile(r"in the step from t = " + _FLOAT)
_RE_ALPHA = re.compile(
    r"^Phase-1 volume fraction = "
    + _FLOAT
    + r"\s+Min\([^)]*\) = "
    + _FLOAT
    + r"\s+Max\([^)]*\) = "
    + _FLOAT
)


def log_time(case: Path) -> float | None:
    """Return the latest simulated time in a case's solver log (None: no step logged yet).

    Reads the log's tail only: what a progress display asks of a running case.
    """
    try:
        with open(Path(case) / LOG_NAME, "rb") as fh:
            fh.seek(0, 2)
            fh.seek(max(0, fh.tell() - 16384))
            tail = fh.read().decode("utf-8", "replace")
    except OSError:
        return None
    for line in reversed(tail.splitlines()):
        m = _RE_TIME.match(line.strip())
        if m:
            t = float(m.group(1))
            return t if math.isfinite(t) else None
    return None


def _isbad(x: float) -> bool:
    return not math.isfinite(x)


@dataclass
class Step:
    """What the log says about one time step."""

    time: float
    delta_t: float = math.nan
    courant: float = math.nan
    interface_courant: float = math.nan
    granular_courant: float = math.nan
    residuals: dict[str, float] = field(default_factory=dict)
    iterations: dict[str, int] = field(default_factory=dict)
    continuity: float = math.nan
    execution_time: float = math.nan
    #: each outer iteration's rms change of the grains' velocity [m/s]
    outer_changes: list[float] = field(default_factory=list)


@dataclass
class Divergence:
    """Why and when a run diverged."""

    quantity: str
    time: float | None
    detail: str


class LogMonitor:
    """Parse siloFoam's log line by line; detect divergence.

    Parameters
    ----------
    max_courant, max_interface_courant, max_granular_courant
        The limits the run uses (from controlDict); 0 disables a check.
    """

    def __init__(
        self,
        max_courant: float,
        max_interface_courant: float,
        max_granular_courant: float = 0.0,
    ) -> None:
        self.limits = {
            "Courant number": max_courant,
            "interface Courant number": max_interface_courant,
            "granular Courant number": max_granular_courant,
        }
        self.steps: list[Step] = []
        self.divergence: Divergence | None = None
        self.fatal: list[str] = []
        self._in_fatal = False
        self._pending: dict[str, float] = {}
        self._max_dt = 0.0
        self.end_seen = False
        #: time at which the solver ended the run because the silo had emptied
        self.emptied_at: float | None = None
        #: the steps the solver took again, each with why (``detail``), its
        #: start ``time``, the step that failed and the one it was taken with
        self.retakes: list[dict[str, float | str]] = []
        #: steps taken again with half the stress's divergence share, their
        #: outer iterations growing or the last moving a grain too far
        #: (``numerics.outer_growth_limit``, ``numerics.outer_change_limit``):
        #: start ``time``, ``growth`` and ``change``, and ``failed`` (why) where the step at half
        #: the share failed and was taken as the whole share first took it
        self.share_retakes: list[dict[str, float | str]] = []
        #: start of the step that ended the solver's retakes (``Step diverged``):
        #: its retake window ends there
        self.diverged_step_start: float | None = None
        self._alpha_max = -math.inf
        self._attempt_alpha_max = -math.inf

    @property
    def largest_step(self) -> float:
        """The largest time step of the run after its first five steps [s] (0: none yet)."""
        return self._max_dt

    @property
    def alpha_max(self) -> float:
        """The largest volume fraction the solver reported in the steps it kept.

        MULES keeps it within ~1e-6 of 1 where the fluxes are divergence-free;
        a step the solver took again does not count.
        """
        return max(self._alpha_max, self._attempt_alpha_max)

    @property
    def current_time(self) -> float | None:
        """Latest simulated time reached."""
        return self.steps[-1].time if self.steps else None

    def _diverge(self, quantity: str, detail: str) -> None:
        if self.divergence is None:
            self.divergence = Divergence(quantity, self.current_time, detail)

    def _check_courant(self, name: str, value: float) -> None:
        limit = self.limits[name]
        if _isbad(value):
            self._diverge(name, f"{name} is {value}")
        elif limit > 0 and value > COURANT_BLOWUP * limit:
            self._diverge(name, f"{name} {value:.3g} > {COURANT_BLOWUP:g} x limit {limit:g}")

    def feed(self, line: str) -> None:
        """Consume one log line."""
        line = line.rstrip()
        if "FOAM FATAL" in line or "sigFpe::sigHandler" in line or "error::printStack" in line:
            self._in_fatal = True
        if self._in_fatal:
            self.fatal.append(line)
            m = _RE_STEP_DIVERGED.match(_RE_RANK.sub("", line.strip()))
            if m:
                self._diverge(m.group(1), m.group(2))
                start = _RE_STEP_FROM.search(m.group(2))
                self.diverged_step_start = float(start.group(1)) if start else None
            if "sigFpe::sigHandler" in line:
                # a floating-point trap is a blow-up the log had no line for
                self._diverge("floating-point exception", "the solver stopped on SIGFPE")
            return
        if line == "End":
            self.end_seen = True
            return
        m = _RE_EMPTIED.match(line)
        if m:
            self.emptied_at = float(m.group(1))
            return
        m = _RE_CO.match(line)
        if m:
            self._pending["courant"] = float(m.group(2))
            self._check_courant("Courant number", float(m.group(2)))
            return
        m = _RE_ACO.match(line)
        if m:
            self._pending["interface_courant"] = float(m.group(2))
            self._check_courant("interface Courant number", float(m.group(2)))
            return
        m = _RE_GCO.match(line)
        if m:
            self._pending["granular_courant"] = float(m.group(1))
            self._check_courant("granular Courant number", float(m.group(1)))
            return
        m = _RE_DT.match(line)
        if m:
            dt = float(m.group(1))
            self._pending["delta_t"] = dt
            if _isbad(dt) or dt <= 0:
                self._diverge("deltaT", f"time step is {dt}")
            elif len(self.steps) > 20 and dt < DT_COLLAPSE * self._max_dt:
                self._diverge("deltaT", f"time step {dt:.3g} s collapsed from {self._max_dt:.3g} s")
            if len(self.steps) > 5:
                self._max_dt = max(self._max_dt, dt)
            return
        m = _RE_TIME.match(line)
        if m:
            # the attempt before was kept: no retake line came in between
            self._alpha_max = max(self._alpha_max, self._attempt_alpha_max)
            self._attempt_alpha_max = -math.inf
            step = Step(time=float(m.group(1)))
            for k, v in self._pending.items():
                setattr(step, k, v)
            self._pending = {}
            self.steps.append(step)
            return
        if not self.steps:
            return
        step = self.steps[-1]
        m = _RE_RES.match(line)
        if m:
            name, r0 = m.group(1), float(m.group(2))
            step.residuals.setdefault(name, r0)  # first solve of the step
            step.iterations[name] = step.iterations.get(name, 0) + int(m.group(4))
            if _isbad(r0) or _isbad(float(m.group(3))):
                self._diverge(f"{name} residual", f"{name} residual is {r0}")
            return
        m = _RE_OUTER.match(line)
        if m:
            step.outer_changes.append(float(m.group(2)))
            return
        m = _RE_ALPHA.match(line)
        if m:
            # no verdict here: the solver judges the step and takes it again
            self._attempt_alpha_max = max(self._attempt_alpha_max, float(m.group(3)))
            return
        m = _RE_RETAKE.match(line)
        if m:
            self.retakes.append(
                {
                    "time": float(m.group(4)),
                    "detail": m.group(3),
                    "delta_t": float(m.group(5)),
                    "retake_delta_t": float(m.group(6)),
                }
            )
            self._attempt_alpha_max = -math.inf
            self._drop_attempt(float(m.group(6)))
            return
        m = _RE_SHARE_RETAKE.match(line)
        if m:
            self.share_retakes.append(
                {
                    "time": float(m.group(5)),
                    "growth": float(m.group(1)),
                    "change": float(m.group(3)),
                }
            )
            self._attempt_alpha_max = -math.inf
            self._drop_attempt(float(m.group(6)))
            return
        m = _RE_SHARE_FALLBACK.match(line)
        if m:
            if self.share_retakes:
                self.share_retakes[-1]["failed"] = m.group(1)
            self._attempt_alpha_max = -math.inf
            self._drop_attempt(float(m.group(3)))
            return
        m = _RE_RETAKE_CHECK.match(line)
        if m:
            # the check's pass prints the step again: one row per step
            self._drop_attempt(float(m.group(2)))
            return
        m = _RE_CONT.match(line)
        if m:
            step.continuity = float(m.group(1))
            if _isbad(step.continuity):
                self._diverge("continuity error", f"continuity error is {step.continuity}")
            return
        m = _RE_EXEC.match(line)
        if m:
            step.execution_time = float(m.group(1))

    def _drop_attempt(self, delta_t: float) -> None:
        """Drop the last step's row: the solver takes that step again at ``delta_t``.

        The step taken again prints no Courant or step lines of its own: the
        dropped attempt's carry over.
        """
        if self.steps:
            dropped = self.steps.pop()
            self._pending = {
                "courant": dropped.courant,
                "interface_courant": dropped.interface_courant,
                "granular_courant": dropped.granular_courant,
                "delta_t": delta_t,
            }

    def write_table(self, path: Path) -> None:
        """Write one row per time step (CSV), replaced whole."""
        names = sorted({k for s in self.steps for k in s.residuals})
        tmp = path.with_suffix(path.suffix + ".tmp")
        with open(tmp, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(
                [
                    "time",
                    "delta_t",
                    "courant",
                    "interface_courant",
                    "granular_courant",
                    "continuity",
                    "execution_time",
                    "outer_iterations",
                    "outer_change_first",
                    "outer_change_last",
                ]
                + [f"res_{n}" for n in names]
                + [f"iter_{n}" for n in names]
            )
            for s in self.steps:
                w.writerow(
                    [
                        s.time,
                        s.delta_t,
                        s.courant,
                        s.interface_courant,
                        s.granular_courant,
                        s.continuity,
                        s.execution_time,
                        len(s.outer_changes) or "",
                        s.outer_changes[0] if s.outer_changes else "",
                        s.outer_changes[-1] if s.outer_changes else "",
                    ]
                    + [s.residuals.get(n, "") for n in names]
                    + [s.iterations.get(n, "") for n in names]
                )
        os.replace(tmp, path)
