"""A benchmark records the commit its runs ran at, read before they run.

A commit made while a benchmark runs (a long one takes an hour) is not the
code its figures were measured with; the suite's reruns had the same fault
(tests/test_suite.py::test_a_rerun_records_the_commit_its_cases_ran_at).
The runs stand in here: what is checked is when the commit is read.
"""

from __future__ import annotations

from types import SimpleNamespace


def test_the_solver_benchmark_records_the_commit_read_before_its_runs(monkeypatch, tmp_path):
    from foamsilo.studies import bench

    commits = iter(["abc1234", "fed4321"])
    monkeypatch.setattr(bench, "git_commit", lambda: next(commits))
    run = {"end_time": 0.1, "start_time": 0.0, "steps": 10, "cpu_seconds": 1.0,
           "wall_seconds": 1.0, "max_rss_mb": 1.0}  # fmt: skip
    summary = {"cells": 100, "run": run, "Q_dimensionless": 0.16,
               "Q_from_volume_dimensionless": 0.16, "mass_balance_rel_error": 0.0}  # fmt: skip

    def fake_run_case(spec, of=None, progress=None):
        bench.git_commit()  # a commit made while the case runs (read here)
        return SimpleNamespace(case=spec.case_dir, as_json=lambda: summary)

    monkeypatch.setattr(bench, "run_case", fake_run_case)
    monkeypatch.setattr(bench, "find_openfoam", lambda: None)
    res = bench.bench_solver([16], 0.1, tmp_path, reference=False, keep=True)
    assert [r["cells_across"] for r in res["rows"]] == [16]
    assert res["commit"] == "abc1234"
