"""Many cases on a Slurm cluster: each case one batch job, followed to its end.

The Slurm backend runs the worker the local backend runs (``python -m
foamsilo.pipeline``: prepare, run and reduce one case, resumable) inside a
batch job: ``sbatch`` with ``--ntasks`` set to the case's MPI ranks (the
solver runs under ``mpirun`` in the job's allocation) and the partition,
account, time limit and extra ``#SBATCH`` lines of :class:`SlurmOptions`.
The jobs are followed with ``squeue``; a job that has left the queue ended:
its case's result is the worker's :class:`~foamsilo.pipeline.Outcome`, or,
where the job was cancelled, timed out or failed before the worker could
write one, the job's final state (``sacct``, or ``scontrol`` where
accounting is off) and the tail of its log.

A case's job files lie beside it, in ``<case>.slurm/``:

``spec.json``
    the case (:class:`~foamsilo.pipeline.CaseSpec`), the worker's input;
``job.sh``
    the batch script as submitted;
``job.json``
    the job id, when it was submitted, and the case it runs;
``outcome.json``
    the worker's outcome, written whole when the job ends;
``slurm-<id>.out``
    the job's output (the worker's log).

Running the same cases again skips those whose job finished with a result
(unless the case is to be written afresh or rerun), follows those still
queued or running, and submits again those whose job was cancelled, failed
or never ran (a resumable case goes on from its latest complete time).
Ctrl-C stops the following, never the jobs: it says how to cancel them.
"""

from __future__ import annotations

import json
import os
import shlex
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from foamsilo.case import write_whole
from foamsilo.errors import FoamsiloError, SceneError, ToolchainError
from foamsilo.jsonio import dumps
from foamsilo.pipeline import CaseSpec, Outcome, case_ranks
from foamsilo.process import run_command

Say = Callable[[str], None]

#: Slurm's client programs, and what installs them on Debian
INSTALL = "apt-get install slurm-client (or load your cluster's Slurm module)"

#: Job files of a case, beside it: ``<case>.slurm/``
JOB_SUFFIX = ".slurm"

_OPTION_KEYS = {"partition", "account", "time_limit", "sbatch", "poll_seconds"}


class SchedulerError(FoamsiloError):
    """A Slurm command failed; carries the command line and its captured output.

    Parameters
    ----------
    argv
        The command.
    returncode
        Its exit status.
    output
        Its stdout and stderr.
    """

    def __init__(self, argv: list[str], returncode: int, output: str) -> None:
        self.command = " ".join(shlex.quote(a) for a in argv)
        self.returncode = returncode
        self.output = output
        super().__init__(f"{self.command} failed (status {returncode}): {output.strip()[-2000:]}")


class JobsLeftQueuedError(FoamsiloError):
    """Ctrl-C while jobs were followed: they stay in Slurm's queue; the message says how to act.

    Parameters
    ----------
    job_ids
        The jobs still queued or running.
    """

    def __init__(self, job_ids: list[str]) -> None:
        self.job_ids = job_ids
        ids = " ".join(job_ids)
        super().__init__(
            f"interrupted (Ctrl-C): stopped following; {len(job_ids)} job(s) stay in Slurm's "
            f"queue ({ids}): run the same command again to follow them, or cancel them with: "
            f"scancel {ids}"
        )


@dataclass(frozen=True)
class SlurmOptions:
    """How the cases' jobs are submitted.

    Attributes
    ----------
    partition
        ``--partition`` (None: the cluster's default).
    account
        ``--account`` (None: the user's default).
    time_limit
        ``--time`` per job, in Slurm's format (``MM``, ``HH:MM:SS``, ``D-HH``).
    sbatch
        Further ``#SBATCH`` options, one per item (``--qos=short``).
    poll_seconds
        How often the queue is read while jobs run.
    """

    partition: str | None = None
    account: str | None = None
    time_limit: str | None = None
    sbatch: tuple[str, ...] = ()
    poll_seconds: float = 5.0

    def __post_init__(self) -> None:
        for i, line in enumerate(self.sbatch):
            if not line.startswith("-") or "\n" in line:
                raise SceneError(
                    f"slurm.sbatch[{i}]",
                    f"got {line!r}; allowed: one sbatch option on one line, such as '--qos=short'",
                )
        for name in ("partition", "account", "time_limit"):
            value = getattr(self, name)
            if value is not None and (not str(value).strip() or any(c.isspace() for c in value)):
                raise SceneError(f"slurm.{name}", f"got {value!r}; allowed: one word")
        if not self.poll_seconds > 0:
            raise SceneError("slurm.poll_seconds", f"got {self.poll_seconds!r}; allowed: > 0")

    @classmethod
    def from_table(cls, table: dict[str, Any], where: str = "slurm") -> SlurmOptions:
        """Read a ``[slurm]`` table (a sweep file's); unknown keys are refused by name."""
        unknown = sorted(set(table) - _OPTION_KEYS)
        if unknown:
            raise SceneError(
                f"{where}.{unknown[0]}", f"unknown key; allowed: {sorted(_OPTION_KEYS)}"
            )
        data = dict(table)
        extra = data.get("sbatch", [])
        if isinstance(extra, str) or not isinstance(extra, list):
            raise SceneError(f"{where}.sbatch", f"got {extra!r}; allowed: a list of sbatch options")
        data["sbatch"] = tuple(str(x) for x in extra)
        for key in ("partition", "account", "time_limit"):
            if key in data:
                data[key] = str(data[key])
        return cls(**data)

    def merged(self, **changes: Any) -> SlurmOptions:
        """Return a copy with the options given (not None) replaced: the command line's."""
        from dataclasses import replace

        given = {k: v for k, v in changes.items() if v not in (None, (), [])}
        if "sbatch" in given:
            given["sbatch"] = (*self.sbatch, *given["sbatch"])
        return replace(self, **given)


def job_dir(case_dir: Path) -> Path:
    """Where the job files of a case lie: ``<case>.slurm/`` beside it."""
    case_dir = Path(case_dir).resolve()
    return case_dir.parent / f"{case_dir.name}{JOB_SUFFIX}"


# ----------------------------------------------------------------------------- commands


def _slurm(argv: list[str], timeout: float = 60.0) -> str:
    """Run a Slurm client command; its output, or :class:`SchedulerError`."""
    try:
        res = run_command(argv, env=dict(os.environ), timeout=timeout)
    except FileNotFoundError:
        raise ToolchainError("slurm", f"{argv[0]} not found", INSTALL) from None
    if res.returncode != 0:
        raise SchedulerError(argv, res.returncode, res.output)
    return res.output


def queued_jobs() -> dict[str, str]:
    """Return the user's jobs in Slurm's queue (pending, running, completing): id -> state."""
    out = _slurm(["squeue", "--noheader", "--me", "--format=%i|%T"])
    jobs = {}
    for line in out.splitlines():
        parts = line.strip().split("|")
        if len(parts) == 2:
            jobs[parts[0]] = parts[1]
    return jobs


def final_state(job_id: str) -> str:
    """How a job that left the queue ended (``COMPLETED``, ``CANCELLED``, ``TIMEOUT``...).

    ``sacct`` where accounting is on; else ``scontrol``, which remembers a
    job for a few minutes (``MinJobAge``); ``unknown`` past that.
    """
    try:
        out = _slurm(["sacct", "--noheader", "--allocations", "--parsable2",
                      "--format=State", f"--jobs={job_id}"])  # fmt: skip
        for line in out.splitlines():
            if line.strip():
                return line.split()[0]  # "CANCELLED by 0" -> CANCELLED
    except (SchedulerError, ToolchainError):
        pass  # accounting off
    try:
        out = _slurm(["scontrol", "--oneliner", "show", "job", job_id])
    except SchedulerError:
        return "unknown"
    for token in out.split():
        key, _, value = token.partition("=")
        if key == "JobState":
            return value
    return "unknown"


def batch_script(spec: CaseSpec, ranks: int, options: SlurmOptions) -> str:
    """Return the batch script of one case: the worker, its spec in, its outcome out."""
    jd = job_dir(spec.case_dir)
    name = (spec.label or Path(spec.case_dir).name).replace(" ", "_")
    lines = [
        "#!/bin/bash",
        f"#SBATCH --job-name=foamsilo-{name}"[:80],
        f"#SBATCH --ntasks={ranks}",
        f"#SBATCH --output={jd}/slurm-%j.out",
        f"#SBATCH --chdir={jd}",
    ]
    if options.partition:
        lines.append(f"#SBATCH --partition={options.partition}")
    if options.account:
        lines.append(f"#SBATCH --account={options.account}")
    if options.time_limit:
        lines.append(f"#SBATCH --time={options.time_limit}")
    lines += [f"#SBATCH {x}" for x in options.sbatch]
    py = shlex.quote(sys.executable)
    part, done = shlex.quote(str(jd / "outcome.part")), shlex.quote(str(jd / "outcome.json"))
    lines += [
        "# the same worker as a local run: prepare, run, reduce (resumable)",
        f"{py} -m foamsilo.pipeline < {shlex.quote(str(jd / 'spec.json'))} > {part}",
        "status=$?",
        f"[ -s {part} ] && mv {part} {done}",
        "exit $status",
        "",
    ]
    return "\n".join(lines)


def submit(spec: CaseSpec, options: SlurmOptions, ranks: int | None = None) -> str:
    """Write a case's job files and submit its job; return the job id."""
    jd = job_dir(spec.case_dir)
    jd.mkdir(parents=True, exist_ok=True)
    for stale in ("outcome.json", "outcome.part"):
        (jd / stale).unlink(missing_ok=True)
    ranks = ranks or case_ranks(spec)
    write_whole(jd / "spec.json", dumps(spec.as_dict()) + "\n")
    write_whole(jd / "job.sh", batch_script(spec, ranks, options))
    out = _slurm(["sbatch", "--parsable", str(jd / "job.sh")])
    job_id = out.strip().splitlines()[-1].split(";")[0]
    record = {"job_id": job_id, "submitted": time.strftime("%Y-%m-%dT%H:%M:%S"),
              "ranks": ranks, "spec": spec.as_dict()}  # fmt: skip
    write_whole(jd / "job.json", dumps(record) + "\n")
    return job_id


def _key(spec: CaseSpec) -> Any:
    """Return the spec as ``job.json`` stores it (JSON and back), to compare."""
    return json.loads(dumps(spec.as_dict()))


def _read_json(path: Path) -> dict[str, Any] | None:
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def stored_outcome(spec: CaseSpec) -> Outcome | None:
    """Return the outcome a finished job left for ``spec`` (None: none, or of another spec)."""
    jd = job_dir(spec.case_dir)
    record = _read_json(jd / "job.json")
    data = _read_json(jd / "outcome.json")
    if record is None or data is None or record.get("spec") != _key(spec):
        return None
    return Outcome(spec, data.get("status", "crash"), data.get("summary"), data.get("error"),
                   data.get("wall_s", 0.0))  # fmt: skip


def _lost(spec: CaseSpec, job_id: str) -> Outcome:
    """Return the outcome of a job that ended without the worker's: its state, its log."""
    jd = job_dir(spec.case_dir)
    state = final_state(job_id)
    log = jd / f"slurm-{job_id}.out"
    try:
        tail = log.read_text(errors="replace")[-1500:]
    except OSError:
        tail = ""
    message = (
        f"the Slurm job {job_id} ended {state} without a result (log: {log}); the case is "
        f"kept at {spec.case_dir}, and running the same command again submits it again"
    )
    error = {"type": "SlurmJobError", "message": message, "job_id": job_id, "state": state,
             "log": str(log), "output": tail, "case_dir": str(spec.case_dir)}  # fmt: skip
    return Outcome(spec, "SlurmJobError", error=error)


@dataclass
class SlurmBackend:
    """Run many cases as Slurm jobs (the :class:`~foamsilo.pipeline.Backend` of a cluster).

    Attributes
    ----------
    options
        How the jobs are submitted.
    say
        Where progress lines go (one per submitted, skipped or finished case).
    """

    options: SlurmOptions = field(default_factory=SlurmOptions)
    say: Say = field(default=lambda _: None)

    def run(
        self, specs: list[CaseSpec], on_done: Callable[[Outcome], None] | None = None
    ) -> list[Outcome]:
        """Submit (or skip, or follow) each case's job; return the outcomes, in order.

        Raises
        ------
        JobsLeftQueuedError
            Ctrl-C: the jobs stay queued; the message says how to cancel
            them or follow them again.
        SchedulerError, ToolchainError
            A Slurm command failed or is missing.
        """
        results: dict[int, Outcome] = {}
        waiting: dict[int, str] = {}  # spec index -> job id

        def finish(i: int, outcome: Outcome) -> None:
            results[i] = outcome
            if on_done is not None:
                on_done(outcome)

        queued = queued_jobs()
        for i, spec in enumerate(specs):
            name = spec.label or Path(spec.case_dir).name
            record = _read_json(job_dir(spec.case_dir) / "job.json")
            same = record is not None and record.get("spec") == _key(spec)
            old = str(record["job_id"]) if same and record else None
            done = stored_outcome(spec)
            # a case to write afresh or run again from t = 0 is never skipped
            fresh = spec.overwrite or spec.rerun
            if done is not None and done.ok and not fresh:
                self.say(f"{name}: finished in job {old}, not submitted again")
                finish(i, done)
            elif old is not None and old in queued:
                self.say(f"{name}: job {old} is {queued[old].lower()}: following it")
                waiting[i] = old
            else:
                why = (
                    f" (job {old} ended {done.status if done else final_state(old)})" if old else ""
                )
                waiting[i] = submit(spec, self.options)
                self.say(f"{name}: submitted as job {waiting[i]}{why}")
        try:
            while waiting:
                time.sleep(self.options.poll_seconds)
                queued = queued_jobs()
                for i, job_id in list(waiting.items()):
                    if job_id in queued:
                        continue
                    del waiting[i]
                    outcome = stored_outcome(specs[i]) or _lost(specs[i], job_id)
                    finish(i, outcome)
        except KeyboardInterrupt:
            raise JobsLeftQueuedError(list(waiting.values())) from None
        return [results[i] for i in range(len(specs))]


__all__ = [
    "JobsLeftQueuedError",
    "SchedulerError",
    "SlurmBackend",
    "SlurmOptions",
    "batch_script",
    "final_state",
    "job_dir",
    "queued_jobs",
    "stored_outcome",
    "submit",
]
