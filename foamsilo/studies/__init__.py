"""Studies: the validation suite, the paper reproductions and the benchmarks.

Each runs its cases through :func:`foamsilo.pipeline.run_many` and keeps the
cases (scenes and overrides) and the tolerances of its checks, each with its
reason, as data in a TOML file beside it: ``suite.toml``
(:mod:`~foamsilo.studies.suite`), ``validation.toml``
(:mod:`~foamsilo.studies.gas`), ``bench.toml`` (:mod:`~foamsilo.studies.bench`).
Their reports are written from the results only.
"""
