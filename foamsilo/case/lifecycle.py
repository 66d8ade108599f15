"""The lifecycle of a case directory, and the lock that makes a running case exclusive.

A case is, in this order of precedence:

``running``
    A foamsilo process holds its lock (``.foamsilo.lock``: an exclusive
    ``flock`` held for the run, with the PID, host and command written in
    it). A lock whose holder is gone is stale and ignored.
``finished``
    Its latest complete time directory is at the end time.
``failed``
    The last run stopped on an error (``run.json``: diverged, solver error,
    wall-time limit); the case is kept as it was.
``interrupted``
    A run started (a complete time after 0, or ``run.json`` says so) and
    was stopped (Ctrl-C, kill -9) before the end.
``prepared``
    Written and meshed, never run.
``new``
    No case yet (no directory, or an empty one). A directory that holds
    files but no ``foamsilo.json`` is not a case: no command deletes it.

:func:`inspect` reads the state; :meth:`CaseStatus.advice` says what was
found and which command moves the case on.
"""

from __future__ import annotations

import contextlib
import enum
import errno
import fcntl
import json
import os
import shutil
import socket
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from foamsilo.case.times import latest_processor_time, time_directories
from foamsilo.errors import CaseStateError
from foamsilo.foam import dict_value

METADATA_FILE = "foamsilo.json"
SCENE_FILE = "scene.toml"
RUN_RECORD = "run.json"
LOCK_FILE = ".foamsilo.lock"


class CaseState(enum.Enum):
    """Where a case directory stands."""

    NEW = "new"
    PREPARED = "prepared"
    RUNNING = "running"
    INTERRUPTED = "interrupted"
    FINISHED = "finished"
    FAILED = "failed"


@dataclass(frozen=True)
class LockInfo:
    """Who holds (or held) a case's lock."""

    pid: int
    host: str
    started: str
    command: str

    def describe(self) -> str:
        """One line for messages."""
        return f"PID {self.pid} on {self.host} since {self.started} ({self.command})"


def _read_lock_info(fh: Any) -> LockInfo | None:
    fh.seek(0)
    try:
        data = json.loads(fh.read() or "null")
        return LockInfo(
            int(data["pid"]), str(data["host"]), str(data["started"]), str(data.get("command", ""))
        )
    except (ValueError, KeyError, TypeError):
        return None


class CaseLock:
    """The exclusive lock of a case directory, held while a command changes it.

    Use as a context manager; entering raises :class:`CaseStateError` when
    another live process holds it.

    Parameters
    ----------
    case_dir
        The case.
    """

    def __init__(self, case_dir: Path) -> None:
        self.case_dir = Path(case_dir)
        self.path = self.case_dir / LOCK_FILE
        self._fh: Any = None
        #: a previous holder that was gone (reported once, then overwritten)
        self.stale: LockInfo | None = None

    def acquire(self) -> None:
        """Take the lock, or raise :class:`CaseStateError` naming its holder."""
        fh = open(self.path, "a+")  # noqa: SIM115 -- held until release()
        for _ in range(20):  # a probe holds the lock for microseconds: retry briefly
            try:
                fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:
                time.sleep(0.05)
            except OSError as exc:  # no locking on this filesystem: trust the PID
                if exc.errno not in (errno.ENOLCK, errno.EOPNOTSUPP):
                    raise
                info = _read_lock_info(fh)
                if info and info.host == socket.gethostname() and _pid_alive(info.pid):
                    fh.close()
                    raise _running_error(self.case_dir, info) from None
                break
        else:
            info = _read_lock_info(fh)
            fh.close()
            raise _running_error(self.case_dir, info)
        self.stale = _read_lock_info(fh)
        fh.seek(0)
        fh.truncate()
        info = LockInfo(
            os.getpid(),
            socket.gethostname(),
            time.strftime("%Y-%m-%dT%H:%M:%S"),
            " ".join(Path(sys.argv[0]).name.split() + sys.argv[1:])[:300],
        )
        fh.write(json.dumps(info.__dict__) + "\n")
        fh.flush()
        os.fsync(fh.fileno())
        self._fh = fh

    def release(self) -> None:
        """Give the lock up (the file stays, empty)."""
        if self._fh is None:
            return
        with contextlib.suppress(OSError):
            self._fh.seek(0)
            self._fh.truncate()
            self._fh.flush()
        fcntl.flock(self._fh, fcntl.LOCK_UN)
        self._fh.close()
        self._fh = None

    def __enter__(self) -> CaseLock:
        self.acquire()
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _running_error(case_dir: Path, info: LockInfo | None) -> CaseStateError:
    who = info.describe() if info else "another process"
    stop = f"; to stop it: kill {info.pid}" if info else ""
    return CaseStateError(
        case_dir,
        CaseState.RUNNING.value,
        f"{case_dir} is being run by {who}: wait for it to finish{stop}",
    )


def lock_holder(case_dir: Path) -> LockInfo | None:
    """Who holds the case's lock now (None: nobody alive does)."""
    path = Path(case_dir) / LOCK_FILE
    if not path.is_file():
        return None
    with open(path) as fh:
        try:
            fcntl.flock(fh, fcntl.LOCK_SH | fcntl.LOCK_NB)
        except BlockingIOError:
            return _read_lock_info(fh) or LockInfo(0, "?", "?", "?")
        except OSError:
            info = _read_lock_info(fh)
            alive = info and info.host == socket.gethostname() and _pid_alive(info.pid)
            return info if alive else None
        fcntl.flock(fh, fcntl.LOCK_UN)
    return None


# ---------------------------------------------------------------------------- state


def is_case(path: Path) -> bool:
    """Whether ``path`` is a foamsilo case directory (it has ``foamsilo.json``)."""
    return (Path(path) / METADATA_FILE).is_file()


def read_metadata(case_dir: Path) -> dict[str, Any]:
    """Return the ``foamsilo.json`` metadata of a case.

    Raises
    ------
    CaseStateError
        ``case_dir`` is not a foamsilo case, or its metadata is unreadable.
    """
    path = Path(case_dir) / METADATA_FILE
    if not path.is_file():
        raise CaseStateError(
            Path(case_dir), "not a case", f"{case_dir} is not a foamsilo case (no {METADATA_FILE})"
        )
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise CaseStateError(Path(case_dir), "damaged", f"{path} is unreadable: {exc}") from None
    if not isinstance(data, dict):
        raise CaseStateError(Path(case_dir), "damaged", f"{path} does not hold a JSON object")
    return data


def read_run_record(case_dir: Path) -> dict[str, Any] | None:
    """Return the record of the last run (``run.json``), or None."""
    path = Path(case_dir) / RUN_RECORD
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


@dataclass(frozen=True)
class CaseStatus:
    """What :func:`inspect` found in a directory.

    Attributes
    ----------
    path
        The directory.
    state
        Its :class:`CaseState`.
    foreign
        The directory holds files but is not a foamsilo case.
    latest_time
        Latest complete time directory after 0 (None: none).
    end_time
        The case's end time [s] (None when not a case).
    holder
        Who runs it (state ``running``).
    last_run
        The record of the last run.
    mesh_missing
        ``constant/polyMesh`` is gone.
    """

    path: Path
    state: CaseState
    foreign: bool = False
    latest_time: str | None = None
    end_time: float | None = None
    holder: LockInfo | None = None
    last_run: dict[str, Any] | None = None
    mesh_missing: bool = False

    @property
    def diagnosis(self) -> str:
        """Why the last run failed (state ``failed``), else empty."""
        err = (self.last_run or {}).get("error") or {}
        return str(err.get("message", "")) if isinstance(err, dict) else str(err)

    def advice(self) -> str:
        """Say what was found, and which command moves the case on."""
        c, t = self.path, self.latest_time
        if self.state is CaseState.RUNNING:
            return str(_running_error(c, self.holder))
        if self.state is CaseState.NEW:
            if self.foreign:
                return (
                    f"{c} holds files but is not a foamsilo case (no {METADATA_FILE}); "
                    "foamsilo will not delete it: choose another directory"
                )
            return f"{c} holds no case yet: `foamsilo new SCENE -o {c}` writes one"
        if self.state is CaseState.PREPARED:
            return f"{c} is prepared (never run): `foamsilo run {c}` runs it"
        if self.state is CaseState.INTERRUPTED:
            at = f"latest complete time {t} s of {self.end_time:g} s" if t else "no time written"
            return (
                f"{c} holds an interrupted run ({at}): `foamsilo run {c} --resume` "
                f"continues it; `foamsilo run {c} --rerun` starts it again from t = 0"
            )
        if self.state is CaseState.FAILED:
            at = f"from the latest complete time {t} s" if t else "from t = 0"
            return (
                f"the last run of {c} failed: {self.diagnosis}; `foamsilo run {c} --resume` "
                f"retries {at}, `foamsilo run {c} --rerun` starts over"
            )
        return (
            f"{c} has finished ({self.end_time:g} s): `foamsilo post {c}` reduces it "
            f"again, `foamsilo run {c} --rerun` runs it again"
        )


def inspect(path: Path) -> CaseStatus:
    """Read the state of a case directory (nothing is changed)."""
    path = Path(path)
    if not is_case(path):
        foreign = path.is_dir() and any(path.iterdir()) or (path.exists() and not path.is_dir())
        return CaseStatus(path, CaseState.NEW, foreign=foreign)
    holder = lock_holder(path)
    control = path / "system" / "controlDict"
    end = float(dict_value(control, "endTime", 0.0)) if control.is_file() else None
    times = [t for t in time_directories(path) if float(t) > 0]
    latest = times[-1] if times else None
    latest_f = max(float(latest) if latest else 0.0, latest_processor_time(path))
    record = read_run_record(path)
    mesh_missing = not (path / "constant" / "polyMesh" / "faces").is_file()
    common = dict(latest_time=latest, end_time=end, last_run=record, mesh_missing=mesh_missing)
    if holder is not None:
        return CaseStatus(path, CaseState.RUNNING, holder=holder, **common)  # type: ignore[arg-type]
    if end is not None and latest_f >= end * (1 - 1e-9) and latest_f > 0:
        return CaseStatus(path, CaseState.FINISHED, **common)  # type: ignore[arg-type]
    status = (record or {}).get("status")
    if status == "finished" and (record or {}).get("emptied_at") is not None:
        # the solver ended the run early: the silo had emptied
        return CaseStatus(path, CaseState.FINISHED, **common)  # type: ignore[arg-type]
    if status in ("diverged", "failed", "time-limit"):
        return CaseStatus(path, CaseState.FAILED, **common)  # type: ignore[arg-type]
    if latest is not None or status in ("interrupted", "running"):
        return CaseStatus(path, CaseState.INTERRUPTED, **common)  # type: ignore[arg-type]
    return CaseStatus(path, CaseState.PREPARED, **common)  # type: ignore[arg-type]


def require(status: CaseStatus, allowed: set[CaseState]) -> None:
    """Raise :class:`CaseStateError` (with the advice) unless the case is in ``allowed``."""
    if status.state not in allowed or (status.state is CaseState.NEW and status.foreign):
        raise CaseStateError(status.path, status.state.value, status.advice())


def reset_results(case_dir: Path) -> list[str]:
    """Remove everything a run and its reduction added: back to the prepared case.

    The prepared case's files are the ones listed in ``foamsilo.json``;
    everything else (time directories after 0, processor directories,
    function-object output, logs of the run, summaries, pictures) is removed.
    Returns what was removed (relative paths).
    """
    case_dir = Path(case_dir)
    meta = read_metadata(case_dir)
    keep = set(meta.get("files") or [])
    if not keep:
        raise CaseStateError(
            case_dir,
            "old",
            f"{case_dir} was written by foamsilo {meta.get('foamsilo_version')}, "
            "which did not record its files: `--overwrite` writes it afresh",
        )
    keep |= {METADATA_FILE, LOCK_FILE}
    keep_dirs = {str(Path(f).parent) for f in keep} | {"."}
    removed = []
    for p in sorted(case_dir.rglob("*"), key=lambda q: len(q.parts), reverse=True):
        rel = str(p.relative_to(case_dir))
        if p.is_dir() and not p.is_symlink():
            if rel not in keep_dirs and not any(k.startswith(rel + "/") for k in keep_dirs):
                shutil.rmtree(p, ignore_errors=True)
                removed.append(rel)
        elif rel not in keep:
            p.unlink(missing_ok=True)
            removed.append(rel)
    return removed
