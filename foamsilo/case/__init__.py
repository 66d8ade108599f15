"""Case directories: written from a scene, and one lifecycle every command reads.

:mod:`~foamsilo.case.templates` (the dictionaries a scene needs),
:mod:`~foamsilo.case.create` (the case written whole or not at all),
:mod:`~foamsilo.case.times` (complete and half-written time directories),
:mod:`~foamsilo.case.lifecycle` (new, prepared, running and locked,
interrupted, finished, failed).
"""

from foamsilo.case.create import (
    Case,
    check_case_path,
    create_case,
    rebuild_mesh,
    remove_stale_temporaries,
    write_whole,
)
from foamsilo.case.lifecycle import (
    LOCK_FILE,
    METADATA_FILE,
    RUN_RECORD,
    SCENE_FILE,
    CaseLock,
    CaseState,
    CaseStatus,
    LockInfo,
    inspect,
    is_case,
    lock_holder,
    read_metadata,
    read_run_record,
    require,
    reset_results,
)
from foamsilo.case.templates import (
    SOLVER_NAME,
    decompose_dict,
    render_templates,
    template_context,
    template_list,
)
from foamsilo.case.times import (
    processor_dirs,
    prune_incomplete_times,
    prune_times_past_step_rows,
    time_directories,
)

__all__ = [
    "LOCK_FILE",
    "METADATA_FILE",
    "RUN_RECORD",
    "SCENE_FILE",
    "SOLVER_NAME",
    "Case",
    "CaseLock",
    "CaseState",
    "CaseStatus",
    "LockInfo",
    "check_case_path",
    "create_case",
    "decompose_dict",
    "inspect",
    "is_case",
    "lock_holder",
    "processor_dirs",
    "prune_incomplete_times",
    "prune_times_past_step_rows",
    "read_metadata",
    "read_run_record",
    "rebuild_mesh",
    "remove_stale_temporaries",
    "render_templates",
    "require",
    "reset_results",
    "template_context",
    "template_list",
    "time_directories",
    "write_whole",
]
