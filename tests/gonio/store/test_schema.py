"""The samples table, defined once (`gonio.store.schema`): the DDL the writer makes from
it is schema v1's, and the reader's dtypes are the table's."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import numpy as np
import pytest

from gonio.store import Journal, open_run
from gonio.store.schema import samples_ddl, samples_table
from tests.support.acquire import acquire, plan_file, scene_file

#: ``CREATE TABLE samples`` of schema v1 for axes (theta_l, phi_d) and coordinates
#: (theta_h, phi_h), as run files hold it.
V1_SAMPLES_SQL = (
    'CREATE TABLE samples ("target" INTEGER NOT NULL PRIMARY KEY, "session" INTEGER NOT NULL, '
    '"attempts" INTEGER NOT NULL, "theta_l_commanded_rad" REAL NOT NULL, '
    '"phi_d_commanded_rad" REAL NOT NULL, "theta_l_read_back_rad" REAL NOT NULL, '
    '"phi_d_read_back_rad" REAL NOT NULL, "wi_x" REAL NOT NULL, "wi_y" REAL NOT NULL, '
    '"wi_z" REAL NOT NULL, "wo_x" REAL NOT NULL, "wo_y" REAL NOT NULL, "wo_z" REAL NOT NULL, '
    '"coord_theta_h" REAL NOT NULL, "coord_phi_h" REAL NOT NULL, "exposure_s" REAL NOT NULL, '
    '"averages" INTEGER NOT NULL, "n" INTEGER NOT NULL, "counts" REAL NOT NULL, '
    '"counts_std" REAL, "saturated" INTEGER NOT NULL, "remeasured" INTEGER NOT NULL, '
    '"settled_s" REAL NOT NULL, "started_s" REAL NOT NULL, "ended_s" REAL NOT NULL, '
    '"utc" TEXT NOT NULL, "temperatures_c" TEXT, "sim_state" TEXT)'
)


def _samples_sql(conn: sqlite3.Connection) -> str:
    row = conn.execute("SELECT sql FROM sqlite_master WHERE name = 'samples'").fetchone()
    return str(row[0])


def test_the_ddl_made_from_the_table_is_schema_v1() -> None:
    axes, coords = ["theta_l", "phi_d"], ["theta_h", "phi_h"]
    assert samples_ddl(samples_table(axes, coords)) == V1_SAMPLES_SQL
    meta = {"axes": axes, "coordinate_names": coords}
    with Journal.create(None, meta, b"", durable=False) as journal:
        assert _samples_sql(journal.conn) == V1_SAMPLES_SQL


@pytest.fixture(scope="module")
def run_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("schema")
    out = folder / "run.sqlite"
    acquire(plan_file(folder, target=5), scene_file(folder), out)
    return out


def test_a_written_file_holds_the_tables_ddl(run_path: Path) -> None:
    run = open_run(run_path)
    table = samples_table(run.meta["axes"], run.meta["coordinate_names"])
    with sqlite3.connect(run_path) as conn:
        assert _samples_sql(conn) == samples_ddl(table)
        names = [r[1] for r in conn.execute("PRAGMA table_info(samples)")]
    assert names == [c.name for c in table] == list(run.samples)


def test_the_reader_gives_each_column_the_tables_dtype(run_path: Path) -> None:
    run = open_run(run_path)
    table = samples_table(run.meta["axes"], run.meta["coordinate_names"])
    assert {n: a.dtype for n, a in run.samples.items()} == {c.name: c.dtype for c in table}
    assert run.samples["saturated"].dtype == np.bool_
    assert run.samples["remeasured"].dtype == np.int64
    assert run.samples["counts_std"].dtype == np.float64
    assert run.samples["utc"].dtype == object
