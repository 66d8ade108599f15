"""Running siloFoam on a case: the runner (serial or MPI, through PyFoam) and its log monitor."""

from foamsilo.run.monitor import LOG_NAME, STEP_TABLE, LogMonitor, Step, log_time
from foamsilo.run.runner import (
    ProgressCallback,
    RunResult,
    StepRelease,
    modifiable_while_running,
    mpi_environment,
    outer_iterations,
    prepare_decomposition,
    run_solver,
    solver_argv,
)

__all__ = [
    "LOG_NAME",
    "STEP_TABLE",
    "LogMonitor",
    "ProgressCallback",
    "RunResult",
    "StepRelease",
    "Step",
    "log_time",
    "modifiable_while_running",
    "mpi_environment",
    "outer_iterations",
    "prepare_decomposition",
    "run_solver",
    "solver_argv",
]
