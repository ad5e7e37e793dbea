"""The same sweep on a Dask cluster (a `LocalCluster` of two worker processes, through
``gonio tradeoff --scheduler``) gives the rows of the in-process run bit for bit, wall
times aside; an unreachable scheduler is one line."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest
from distributed import LocalCluster

from gonio.cli import main
from gonio.tradeoff import executors
from tests.conftest import CliResult
from tests.gonio.tradeoff.conftest import Reference, rows_of


def test_a_dask_cluster_gives_the_rows_of_the_local_run(
    reference: Reference, tmp_path: Path
) -> None:
    out = tmp_path / "out"
    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address="127.0.0.1:0"
    ) as cluster:
        code = main(
            [
                "tradeoff",
                str(reference.sweep),
                "-o",
                str(out),
                "-q",
                "--scheduler",
                cluster.scheduler_address,
            ]
        )
    assert code == 0
    assert rows_of(out) == rows_of(reference.out)


def test_an_unreachable_scheduler_is_one_line(
    reference: Reference,
    tmp_path: Path,
    run_gonio: Callable[..., CliResult],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(executors, "CONNECT_TIMEOUT_S", 1.0)
    result = run_gonio(
        "tradeoff",
        str(reference.sweep),
        "-o",
        str(tmp_path / "out"),
        "--scheduler",
        "tcp://127.0.0.1:1",
    )
    assert result.returncode == 2
    assert result.stderr.count("\n") == 1 and "cannot reach the scheduler" in result.stderr


def test_a_scheduler_that_is_no_address_is_one_line(
    reference: Reference, tmp_path: Path, run_gonio: Callable[..., CliResult]
) -> None:
    result = run_gonio(
        "tradeoff", str(reference.sweep), "-o", str(tmp_path / "out"), "--scheduler", "nonsense"
    )
    assert result.returncode == 2 and result.stderr.count("\n") == 1
    assert "expected an address tcp://HOST:PORT" in result.stderr
