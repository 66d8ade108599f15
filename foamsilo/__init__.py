"""foamsilo: OpenFOAM simulations of granular silo and hopper discharge.

Stages, each importing only the ones before it::

    scene -> mesh, case, solver -> run -> post -> compare

with the plain-Python cross-checks in :mod:`foamsilo.analytic` and
:mod:`foamsilo.hopper`.
"""

__version__ = "0.2.0"
