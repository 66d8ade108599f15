"""Error types of foamsilo.

Every error a user can cause or meet carries enough to act on: the scene
field and its allowed range, the OpenFOAM command with its captured output,
or the quantity, time and last good time directory of a diverged run.
"""

from __future__ import annotations

from pathlib import Path


class FoamsiloError(Exception):
    """Base class of all foamsilo errors."""


class InputError(FoamsiloError, ValueError):
    """Bad input from the user: a scene value, an option, a path (exit status 2)."""


class UsageError(InputError):
    """A command-line option or path cannot be used.

    Parameters
    ----------
    field
        The option (``"--output"``, ``"--np"``) or argument it concerns.
    message
        What is wrong and what is allowed.
    """

    def __init__(self, field: str, message: str) -> None:
        self.field = field
        super().__init__(f"{field}: {message}")


class CaseStateError(FoamsiloError):
    """A case is not in a state the command can act on; the message says which one moves it.

    Parameters
    ----------
    case_dir
        The case.
    state
        What was found (``"running"``, ``"interrupted"``, ...).
    message
        What was found and the command that moves the case on.
    """

    def __init__(self, case_dir: Path, state: str, message: str) -> None:
        self.case_dir = case_dir
        self.state = state
        super().__init__(message)


class SceneError(InputError):
    """A scene value is missing, unknown or out of its allowed range.

    Parameters
    ----------
    field
        Dotted name of the offending scene field (``"silo.orifice_width"``).
    message
        What is wrong and what is allowed.
    """

    def __init__(self, field: str, message: str) -> None:
        self.field = field
        super().__init__(f"{field}: {message}")


class ToolchainError(FoamsiloError):
    """A required tool (OpenFOAM, headers, wmake, MPI, gmsh) is missing.

    Parameters
    ----------
    component
        What is missing.
    fix
        The command that installs or builds it.
    """

    def __init__(self, component: str, message: str, fix: str) -> None:
        self.component = component
        self.fix = fix
        super().__init__(f"{component}: {message} (fix: {fix})")


class FoamError(FoamsiloError):
    """An OpenFOAM command failed.

    Parameters
    ----------
    command
        The command line that was run.
    returncode
        Its exit status.
    output
        Captured output (the tail of stdout and stderr).
    case_dir
        Case the command ran in.
    """

    def __init__(
        self, command: str, returncode: int, output: str, case_dir: Path | None = None
    ) -> None:
        self.command = command
        self.returncode = returncode
        self.output = output
        self.case_dir = case_dir
        tail = "\n".join(output.strip().splitlines()[-25:])
        where = f" in {case_dir}" if case_dir else ""
        super().__init__(f"'{command}' failed with status {returncode}{where}:\n{tail}")


class MeshError(FoamsiloError):
    """Meshing failed; ``geometry_file`` holds the geometry for inspection."""

    def __init__(self, message: str, geometry_file: Path | None = None) -> None:
        self.geometry_file = geometry_file
        hint = f" (geometry written to {geometry_file})" if geometry_file else ""
        super().__init__(message + hint)


class DivergenceError(FoamsiloError):
    """A run was stopped because it diverged; the case is kept.

    Parameters
    ----------
    quantity
        What diverged (``"Courant number"``, ``"p_rgh residual"``, ``"deltaT"``).
    time
        Simulated time at which it was detected [s].
    last_good_time
        Name of the last complete time directory, or None.
    case_dir
        The case, kept for inspection.
    delta_t
        The time step the run was taking when it diverged [s] (None: unknown).
    recoveries
        The recoveries tried before it was given up (see :mod:`foamsilo.pipeline`).
    """

    def __init__(
        self,
        quantity: str,
        time: float | None,
        detail: str,
        last_good_time: str | None,
        case_dir: Path,
        delta_t: float | None = None,
    ) -> None:
        self.quantity = quantity
        self.time = time
        self.detail = detail
        self.last_good_time = last_good_time
        self.case_dir = case_dir
        self.delta_t = delta_t
        self.recoveries: list[dict[str, object]] = []
        t = f"t = {time:.6g} s" if time is not None else "start-up"
        super().__init__(
            f"run diverged: {quantity} at {t} ({detail}); last good time directory: "
            f"{last_good_time or 'none'}; case kept in {case_dir}"
        )


class RunTimeLimitError(FoamsiloError):
    """A run was stopped at its wall-time limit; the case is kept.

    Parameters
    ----------
    limit
        The limit [s].
    time, end_time
        Simulated time reached and the end time aimed at [s].
    recoveries
        Recoveries of the run before it reached the limit.
    """

    def __init__(
        self,
        limit: float,
        time: float | None,
        end_time: float,
        case_dir: Path,
        recoveries: int = 0,
    ) -> None:
        self.limit = limit
        self.time = time
        self.end_time = end_time
        self.case_dir = case_dir
        self.recoveries = recoveries
        reached = f"{time:.6g}" if time is not None else "0"
        after = f" (after {recoveries} recoveries)" if recoveries else ""
        super().__init__(
            f"stopped at the wall-time limit of {limit:g} s{after}: reached t = {reached} s of "
            f"{end_time:g} s; case kept in {case_dir}"
        )


class RunInterruptedError(FoamsiloError):
    """A run was interrupted (Ctrl-C, SIGINT); the case is kept for ``--resume``.

    Parameters
    ----------
    time
        Simulated time reached [s], or None.
    last_good_time
        Latest complete time directory, or None.
    case_dir
        The case.
    """

    def __init__(self, time: float | None, last_good_time: str | None, case_dir: Path) -> None:
        self.time = time
        self.last_good_time = last_good_time
        self.case_dir = case_dir
        reached = f"{time:.6g}" if time is not None else "0"
        super().__init__(
            f"interrupted at t = {reached} s; latest complete time directory: "
            f"{last_good_time}; `foamsilo run {case_dir} --resume` goes on from there"
        )
