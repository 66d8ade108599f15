"""OpenFOAM from Python: its utilities, its dictionaries and fields.

Programs are started through :mod:`foamsilo.process` (the one subprocess helper).
:mod:`~foamsilo.foam.utilities` (one function per utility: ``gmsh_to_foam``,
``check_mesh``, ``decompose_par`` ...), :mod:`~foamsilo.foam.dictionary`
(dictionaries and fields through PyFoam's parser).
"""

from foamsilo.foam.dictionary import (
    dict_value,
    edit_dict,
    patch_types,
    read_dict,
    read_internal_field,
    set_patch_types,
    write_internal_field,
)
from foamsilo.foam.utilities import (
    CheckMeshResult,
    block_mesh,
    check_mesh,
    decompose_par,
    gmsh_to_foam,
    granular_volume,
    parse_check_mesh,
    reconstruct_par,
    run_utility,
    set_alpha_field,
    topo_set,
)
from foamsilo.process import CommandResult, run_command, shell_line, tied_to_parent

__all__ = [
    "CheckMeshResult",
    "CommandResult",
    "block_mesh",
    "check_mesh",
    "decompose_par",
    "dict_value",
    "edit_dict",
    "gmsh_to_foam",
    "granular_volume",
    "parse_check_mesh",
    "patch_types",
    "read_dict",
    "read_internal_field",
    "reconstruct_par",
    "run_command",
    "run_utility",
    "set_alpha_field",
    "set_patch_types",
    "shell_line",
    "tied_to_parent",
    "topo_set",
    "write_internal_field",
]
