"""The one way foamsilo starts a program: explicit environment, dies with its parent.

Every OpenFOAM utility, the solver, mpirun and wmake are started through
:func:`run_command` (or, for PyFoam's runner, the shell line of
:func:`shell_line`): the environment is passed as ``env=``, never by editing
``os.environ``, and the child is started under ``setpriv --pdeathsig`` so a
foamsilo process killed with ``kill -9`` takes the programs it started with
it instead of leaving them running on a case.
"""

from __future__ import annotations

import os
import shlex
import shutil
import signal
import subprocess
from dataclasses import dataclass
from pathlib import Path

#: Signal a child gets when the foamsilo process that started it dies
PARENT_DEATH_SIGNAL = "TERM"


def cpu_model() -> str:
    """Return the processor's model name (``/proc/cpuinfo``; else the platform's; ``""``).

    A cost in CPU-s is a figure of the machine it was measured on: the runner
    records it with each run, the studies with each row and report.
    """
    import platform

    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or ""


def _setpriv() -> str | None:
    return shutil.which("setpriv")


def tied_to_parent(argv: list[str]) -> list[str]:
    """``argv`` prefixed so that the program gets SIGTERM when its parent dies.

    Uses util-linux's ``setpriv --pdeathsig`` (Linux); elsewhere ``argv`` is
    returned unchanged.
    """
    tool = _setpriv()
    if tool is None:
        return list(argv)
    return [tool, "--pdeathsig", PARENT_DEATH_SIGNAL, "--", *argv]


@dataclass(frozen=True)
class CommandResult:
    """What a finished program left: its status and its output (stdout then stderr)."""

    argv: list[str]
    returncode: int
    output: str


def run_command(
    argv: list[str],
    *,
    env: dict[str, str],
    cwd: Path | None = None,
    timeout: float | None = None,
) -> CommandResult:
    """Run a program to completion and capture its output.

    Parameters
    ----------
    argv
        The program and its arguments.
    env
        Its whole environment.
    cwd
        Working directory.
    timeout
        Kill it after this many seconds (``returncode`` 124).

    Raises
    ------
    KeyboardInterrupt
        The program died of SIGINT: Ctrl-C reached its process group, and
        the caller must stop as for a Ctrl-C of its own.
    FileNotFoundError
        The program does not exist.
    """
    try:
        proc = subprocess.run(
            tied_to_parent(argv),
            env=env,
            cwd=cwd,
            capture_output=True,
            timeout=timeout,
        )
    except subprocess.TimeoutExpired as exc:
        out = (exc.stdout or b"") + (exc.stderr or b"")
        text = out.decode("utf-8", "replace") if isinstance(out, bytes) else str(out)
        return CommandResult(list(argv), 124, f"timed out after {timeout} s\n{text}")
    if proc.returncode == -signal.SIGINT:
        raise KeyboardInterrupt
    output = proc.stdout.decode("utf-8", "replace") + proc.stderr.decode("utf-8", "replace")
    return CommandResult(list(argv), proc.returncode, output)


def shell_line(argv: list[str], env: dict[str, str]) -> str:
    """Return a shell command line that runs ``argv`` with environment ``env``, tied to its parent.

    For runners that take a command line rather than an environment (PyFoam's
    ``BasicRunner`` starts ``/bin/sh -c LINE`` with the caller's environment):
    the line sets the variables that differ from ``os.environ`` with
    ``env -u NAME NAME=VALUE``, and ``exec`` makes the program the process
    the runner signals.
    """
    unset = [k for k in os.environ if k not in env]
    changed = {k: v for k, v in env.items() if os.environ.get(k) != v}
    prefix = ["env"] + [a for k in sorted(unset) for a in ("-u", k)]
    prefix += [f"{k}={v}" for k, v in sorted(changed.items())]
    return "exec " + " ".join(shlex.quote(a) for a in [*prefix, *tied_to_parent(argv)])
