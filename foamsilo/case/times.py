"""Time directories of a case: which are complete, which a killed run left half-written.

A time directory is complete when the fields a restart needs are there and
every file in it was written whole (OpenFOAM ends each file with its footer
line). In a decomposed case a time counts when every processor directory
holds it complete, or when it was reconstructed.
"""

from __future__ import annotations

import shutil
from pathlib import Path

#: Fields a time directory must hold, whole, to restart from it
RESTART_FIELDS = ("U", "p_rgh", "alpha.granular", "phi", "uniform/time")
_FOOTER = b"// ************************************************************************* //"


def written_whole(path: Path) -> bool:
    """Whether an OpenFOAM file ends with its footer (a killed write does not)."""
    try:
        size = path.stat().st_size
        with open(path, "rb") as fh:
            fh.seek(max(0, size - 200))
            return _FOOTER in fh.read()
    except OSError:
        return False


def is_time_name(name: str) -> bool:
    """Whether a directory name reads as a time (``0``, ``0.25``, ``1e-07``)."""
    try:
        float(name)
    except ValueError:
        return False
    return True


def time_dirs(root: Path) -> list[Path]:
    """Directories of ``root`` named as a time, oldest first (complete or not)."""
    root = Path(root)
    if not root.is_dir():
        return []
    out = [p for p in root.iterdir() if is_time_name(p.name) and p.is_dir()]
    return sorted(out, key=lambda p: float(p.name))


def is_complete(tdir: Path) -> bool:
    """Whether a restart can start from this time directory."""
    if float(tdir.name) == 0.0:
        return (tdir / "U").exists() and (tdir / "alpha.granular").exists()
    # the restart fields, and every other file written whole: the solver
    # also reads some of the others (alphaPhi0 is READ_IF_PRESENT), and a
    # truncated one stops the restart with a fatal IO error
    if not all((tdir / f).is_file() for f in RESTART_FIELDS):
        return False
    return all(written_whole(p) for p in tdir.rglob("*") if p.is_file())


def _complete_names(root: Path) -> set[str]:
    return {p.name for p in time_dirs(root) if is_complete(p)}


def processor_dirs(case: Path) -> list[Path]:
    """Return the ``processorN`` directories of a decomposed case, in rank order."""
    procs = [p for p in Path(case).glob("processor*") if p.name[9:].isdigit()]
    return sorted(procs, key=lambda p: int(p.name[9:]))


def complete_on_every_rank(case: Path) -> set[str]:
    """Return the times complete in every processor directory (none: not decomposed)."""
    procs = processor_dirs(case)
    return set.intersection(*[_complete_names(pd) for pd in procs]) if procs else set()


def time_directories(case: Path) -> list[str]:
    """Complete time directories of a case (serial or decomposed), oldest first."""
    names = _complete_names(case) | complete_on_every_rank(case)
    return sorted(names, key=float)


def latest_root_time(case: Path) -> float:
    """Latest complete time of the case directory itself (0 when none)."""
    return max((float(n) for n in _complete_names(case)), default=0.0)


def latest_processor_time(case: Path) -> float:
    """Latest time complete on every rank (-1 when not decomposed)."""
    return max((float(n) for n in complete_on_every_rank(case)), default=-1.0)


def prune_incomplete_times(case: Path) -> list[str]:
    """Remove time directories that are not complete (a killed write).

    Returns the names removed. The solver restarts from the latest time
    directory it finds (``startFrom latestTime``), so a half-written one must
    not be left for it.
    """
    procs = processor_dirs(case)
    keep_root, keep_procs = _complete_names(case), complete_on_every_rank(case)
    removed = []
    for root, keep in [(Path(case), keep_root), *[(pd, keep_procs) for pd in procs]]:
        for p in time_dirs(root):
            if float(p.name) > 0 and p.name not in keep:
                shutil.rmtree(p)
                removed.append(str(p.relative_to(case)))
    return removed


#: Function objects that write a row every step (templates/system/controlDict)
#: and that the mass balance reads. OpenFOAM runs them after the step's write,
#: at the next step's start (``Time::run``): a run killed in between leaves a
#: complete time whose step has no row, and a restart from it never adds one
STEP_ROW_TABLES = ("orificeFlow", "granularVolume")


def last_step_row(case: Path, name: str) -> float | None:
    """Time of the last row of ``postProcessing/<name>`` (its latest restart's table).

    None when the case has no such table or it holds no row yet.
    """
    root = Path(case) / "postProcessing" / name
    starts = time_dirs(root)
    for start in reversed(starts):
        tables = sorted(start.glob("*.dat"), key=lambda f: f.stat().st_mtime)
        if not tables:
            continue
        for line in reversed(tables[-1].read_text(errors="replace").splitlines()):
            words = line.split()
            if words and not words[0].startswith("#"):
                try:
                    return float(words[0])
                except ValueError:
                    return None  # a row cut off by the kill: no verdict
        return None
    return None


def resumable_times(case: Path) -> list[str]:
    """Complete times a restart can go on from, oldest first.

    The complete times without the latest ones whose step the function objects
    have no row for: a restart from such a time would leave a gap in the
    per-step tables (the mass balance and Q read them).
    """
    times = time_directories(case)
    rows = [last_step_row(case, n) for n in STEP_ROW_TABLES]
    while times and float(times[-1]) > 0:
        latest = float(times[-1])
        if all(t is None or t >= latest * (1 - 1e-6) for t in rows):
            break
        times.pop()
    return times


def prune_times_past_step_rows(case: Path) -> list[str]:
    """Remove the latest times whose step the function objects have no row for.

    The time before is restarted from instead (:func:`resumable_times`).
    Returns the names removed.
    """
    complete = time_directories(case)
    keep = resumable_times(case)
    if len(keep) == len(complete):
        return []
    return remove_times_from(case, float(complete[len(keep)]))


#: Fields whose values a restart takes over; a NaN or Inf in one poisons the run
CHECKED_FIELDS = ("U", "p_rgh", "alpha.granular")
#: Suffix of a time directory set aside because its fields hold NaN or Inf
NONFINITE_SUFFIX = ".nonfinite"


def nonfinite_fields(tdir: Path) -> list[str]:
    """Return the restart fields of a time directory that hold NaN or Inf (empty: none)."""
    import numpy as np

    from foamsilo.errors import FoamsiloError
    from foamsilo.foam import read_internal_field

    bad = []
    for name in CHECKED_FIELDS:
        path = Path(tdir) / name
        if not path.is_file():
            continue
        try:
            values = read_internal_field(path)
        except FoamsiloError:
            bad.append(name)  # unreadable is as bad as NaN for a restart
            continue
        if not np.all(np.isfinite(values)):
            bad.append(name)
    return bad


def set_aside_nonfinite_times(case: Path) -> list[str]:
    """Set aside the latest time directories whose fields hold NaN or Inf.

    Checks the latest complete time after 0 (of the case and of every
    processor directory); a bad one is renamed ``<time>.nonfinite`` (kept for
    inspection, invisible to OpenFOAM), and the one before it is checked in
    turn. Returns the directories set aside (relative to the case).
    """
    case = Path(case)
    removed: list[str] = []
    roots = [case, *processor_dirs(case)]
    while True:
        times = [t for t in time_directories(case) if float(t) > 0]
        if not times:
            return removed
        latest = times[-1]
        bad = [r / latest for r in roots if (r / latest).is_dir() and nonfinite_fields(r / latest)]
        if not bad:
            return removed
        for r in roots:
            d = r / latest
            if d.is_dir():
                d.rename(d.with_name(d.name + NONFINITE_SUFFIX))
                removed.append(str(d.relative_to(case)))


def remove_times_from(case: Path, time: float) -> list[str]:
    """Remove the time directories at or after ``time`` (a diverged step may have written one)."""
    case = Path(case)
    removed = []
    for root in [case, *processor_dirs(case)]:
        for p in time_dirs(root):
            if float(p.name) > 0 and float(p.name) >= time * (1 - 1e-12):
                shutil.rmtree(p)
                removed.append(str(p.relative_to(case)))
    return removed
