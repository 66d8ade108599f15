"""Data package: the C++ sources of siloFoam and its mu(I) library, shipped inside foamsilo.

Not Python code: foamsilo.resources.solver_source_dir() finds this directory;
foamsilo.solver builds it with wmake.
"""
