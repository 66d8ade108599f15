"""Reduce a run to the numbers of the experiments (and nothing above that).

:mod:`~foamsilo.post.series` (function-object tables, read strictly),
:mod:`~foamsilo.post.discharge` (Q(t), V(t)), :mod:`~foamsilo.post.steady`
(the stationary regime), :mod:`~foamsilo.post.pore_pressure`,
:mod:`~foamsilo.post.fields` (pyvista: free surface, profiles, pictures),
:mod:`~foamsilo.post.reduce` (all of it as one typed :class:`Reduction`).
Comparing with the laws and writing reports sit above, in
:mod:`foamsilo.compare` and :mod:`foamsilo.report`.
"""

from foamsilo.post.discharge import DISCHARGE_CSV, Discharge, read_discharge
from foamsilo.post.fields import CASE_TYPES, CaseFields, FieldSummary, field_summary
from foamsilo.post.pore_pressure import PorePressure, pore_pressure
from foamsilo.post.reduce import Reduction, reduce_case
from foamsilo.post.series import (
    DamagedOutputError,
    Series,
    read_function_object,
    read_probes,
)
from foamsilo.post.steady import SteadyState, find_steady

__all__ = [
    "CASE_TYPES",
    "DISCHARGE_CSV",
    "CaseFields",
    "DamagedOutputError",
    "Discharge",
    "FieldSummary",
    "PorePressure",
    "Reduction",
    "Series",
    "SteadyState",
    "field_summary",
    "find_steady",
    "pore_pressure",
    "read_discharge",
    "read_function_object",
    "read_probes",
    "reduce_case",
]
