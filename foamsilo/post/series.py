"""Function-object output of a run, read strictly and merged over restarts.

Sources are the ``postProcessing/<name>/<t0>/*.dat`` tables the case writes
every time step. A restart from t0 writes a new ``<t0>`` directory whose
rows replace the earlier ones from t0 on. Output is read strictly: a row
that is not a row of numbers, or a value that is not finite, stops the
reduction with the file, the line and what was found; only a last row cut
short by a killed writer is dropped (and noted).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from foamsilo.errors import FoamsiloError, InputError


class DamagedOutputError(InputError):
    """Function-object output that cannot be trusted (garbage, NaN): exit status 2."""


@dataclass
class Series:
    """One function object's table over the whole run.

    Attributes
    ----------
    columns
        Column names (the first is ``Time``).
    data
        The rows, sorted by time.
    notes
        What was dropped on the way (a last row cut short by a killed run).
    """

    columns: list[str]
    data: np.ndarray
    notes: list[str] = field(default_factory=list)


def _text(path: Path) -> str:
    raw = path.read_bytes()
    try:
        return raw.decode("ascii")
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        raise DamagedOutputError(
            f"{path}:{line}: not text (byte {exc.start} is {raw[exc.start]:#04x}): the file is "
            "damaged; rerun the case (`foamsilo run CASE --rerun`)"
        ) from None


def _parse_rows(path: Path, text: str, notes: list[str]) -> tuple[list[str], list[list[float]]]:
    """Header columns and numeric rows of one table; damage raises."""
    lines = text.split("\n")
    cut = not text.endswith("\n")
    header: list[str] = []
    rows: list[list[float]] = []
    width = None
    for number, raw in enumerate(lines, start=1):
        line = raw.strip()
        if not line:
            continue
        if line.startswith("#"):
            cols = [c.strip() for c in line.lstrip("#").split("\t") if c.strip()]
            header = cols or header
            continue
        last = number == len(lines) or (number == len(lines) - 1 and not lines[-1])
        words = line.replace("(", " ").replace(")", " ").split()
        try:
            values = [float(w) for w in words]
        except ValueError:
            if last and cut:
                notes.append(f"{path.name}: the last row, cut short by a killed run, dropped")
                continue
            raise DamagedOutputError(
                f"{path}:{number}: not a row of numbers: {line[:80]!r}"
            ) from None
        if width is None:
            width = len(values)
        if len(values) != width:
            if last and cut:
                notes.append(f"{path.name}: the last row, cut short by a killed run, dropped")
                continue
            raise DamagedOutputError(
                f"{path}:{number}: {len(values)} values where the rows above have {width}"
            )
        bad = [k for k, v in enumerate(values) if not math.isfinite(v)]
        if bad:
            k = bad[0]
            name = header[k] if k < len(header) else f"column {k + 1}"
            raise DamagedOutputError(
                f"{path}:{number}: {name} is {words[k]} at t = {words[0]}: the run wrote "
                "non-finite output (it diverged); nothing after it can be reduced"
            )
        rows.append(values)
    return header, rows


def _tables(root: Path, pattern: str) -> list[tuple[float, Path]]:
    """Return the newest table of each restart directory with its start time, oldest first."""
    starts = []
    for p in root.iterdir():
        try:
            t0 = float(p.name)
        except ValueError:
            continue
        if p.is_dir():
            starts.append((t0, p))
    files = []
    for t0, start in sorted(starts):
        # a rerun from the same time writes <name>_<time>.dat beside the old
        # file: the newest one is this run's
        found = sorted(start.glob(pattern), key=lambda f: f.stat().st_mtime)
        if found:
            files.append((t0, found[-1]))
    return files


def _before_restart(rows: np.ndarray, t0: float, block: np.ndarray) -> np.ndarray:
    """Return the rows of earlier runs that a restart from ``t0`` (first rows ``block``) keeps.

    The restart goes on from t0: every earlier row after t0 is of the
    abandoned run, also one between t0 and the end of the restart's first
    step (which may be longer than the abandoned run's).
    """
    return rows[rows[:, 0] <= min(t0, block[0, 0]) * (1 + 1e-9)]


def read_function_object(case: Path, name: str) -> Series:
    """Read ``postProcessing/<name>/<t0>/*.dat``, merged over restarts.

    Raises
    ------
    FoamsiloError
        No output (the case has not run), or only empty tables.
    DamagedOutputError
        A row is not numbers, has the wrong width, or holds NaN or Inf.
    """
    root = Path(case) / "postProcessing" / name
    if not root.is_dir():
        raise FoamsiloError(f"no function-object output {root} (has the case run?)")
    columns: list[str] = []
    data = np.empty((0, 0))
    notes: list[str] = []
    for t0, path in _tables(root, "*.dat"):
        header, rows = _parse_rows(path, _text(path), notes)
        if not rows:
            continue
        block = np.array(rows)
        columns = header or columns
        if data.size:
            if block.shape[1] != data.shape[1]:
                raise DamagedOutputError(
                    f"{path}: {block.shape[1]} columns where the earlier output has {data.shape[1]}"
                )
            data = np.vstack([_before_restart(data, t0, block), block])
        else:
            data = block
    if not data.size:
        raise FoamsiloError(f"function-object output {root} is empty")
    return Series(columns, data, notes)


def read_probes(
    case: Path, name: str, field_name: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Probe locations, times and values of ``postProcessing/<name>/<t0>/<field>``.

    Returns
    -------
    locations (n, 3), times (m,), values (m, n), merged over restarts.
    """
    root = Path(case) / "postProcessing" / name
    if not root.is_dir():
        raise FoamsiloError(f"no probe output {root}")
    locs: list[list[float]] = []
    blocks: list[np.ndarray] = []
    notes: list[str] = []
    for t0, path in _tables(root, f"{field_name}*"):
        text = _text(path)
        found = [
            [float(v) for v in ln.split("(")[1].split(")")[0].split()]
            for ln in text.splitlines()
            if ln.startswith("# Probe ") and "(" in ln
        ]
        locs = found or locs
        _, rows = _parse_rows(path, text, notes)
        if not rows:
            continue
        block = np.array(rows)
        if blocks:
            blocks = [_before_restart(b, t0, block) for b in blocks]
        blocks.append(block)
    if not blocks:
        raise FoamsiloError(f"probe output {root} is empty")
    data = np.vstack(blocks)
    return np.array(locs), data[:, 0], data[:, 1:]


def read_vector_series(case: Path, name: str) -> tuple[np.ndarray, np.ndarray]:
    """Return the times and (n, 3) vectors of a ``volFieldValue`` of a vector field."""
    s = read_function_object(case, name)
    return s.data[:, 0], s.data[:, 1:4]
