"""The samples table, defined once (`gonio.store.schema`): the DDL the writer makes from
it is schema v2's (v1's and the fly columns), the reader's dtypes are the table's, and a
version-1 run file (made here with SQL from a written one: the sweep tables and the fly
columns dropped) is read and resumed."""

from __future__ import annotations

import contextlib
import sqlite3
from pathlib import Path

import numpy as np
import pytest

from gonio import workflows
from gonio.config import ConfigError
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
#: Version 2 adds a fly reading's smear and timing uncertainty.
V2_SAMPLES_SQL = V1_SAMPLES_SQL[:-1] + ', "smear_rad" REAL, "timing_rad" REAL)'


def _samples_sql(conn: sqlite3.Connection) -> str:
    row = conn.execute("SELECT sql FROM sqlite_master WHERE name = 'samples'").fetchone()
    return str(row[0])


def test_the_ddl_made_from_the_table_is_schema_v2() -> None:
    axes, coords = ["theta_l", "phi_d"], ["theta_h", "phi_h"]
    assert samples_ddl(samples_table(axes, coords)) == V2_SAMPLES_SQL
    meta = {"axes": axes, "coordinate_names": coords}
    with Journal.create(None, meta, b"", durable=False) as journal:
        assert _samples_sql(journal.conn) == V2_SAMPLES_SQL


def _as_version_1(path: Path) -> None:
    """Turn a written run file into version 1's layout (closed: its WAL folded in)."""
    with contextlib.closing(sqlite3.connect(path)) as conn, conn:
        for table in ("stream", "polls", "sweeps"):
            conn.execute(f"DROP TABLE {table}")
        for column in ("smear_rad", "timing_rad"):
            conn.execute(f"ALTER TABLE samples DROP COLUMN {column}")
        conn.execute("UPDATE meta SET value = '1' WHERE key = 'schema_version'")
        conn.execute("PRAGMA user_version=1")


def test_a_version_1_run_is_read_and_resumed(tmp_path: Path) -> None:
    out = tmp_path / "v1.sqlite"
    acquire(plan_file(tmp_path, target=5), scene_file(tmp_path), out)
    expected = open_run(out)
    _as_version_1(out)
    with sqlite3.connect(out) as conn:
        assert "smear_rad" not in _samples_sql(conn)
        conn.execute("DELETE FROM samples WHERE target >= 3")
    run = open_run(out)
    assert len(run) == 3 and run.sweeps == ()
    assert np.isnan(run.samples["smear_rad"]).all() and np.isnan(run.samples["timing_rad"]).all()
    np.testing.assert_array_equal(run.samples["counts"], expected.samples["counts"][:3])
    with Journal.reopen(out, durable=False) as journal:  # reopened as it is …
        assert journal.conn.execute("PRAGMA user_version").fetchone()[0] == 1
        journal.upgrade()  # … and brought to version 2 once a resume's checks passed
        assert journal.conn.execute("PRAGMA user_version").fetchone()[0] == 2
    run = open_run(out)
    assert run.meta["schema_version"] == 2 and len(run) == 3


def test_a_refused_resume_of_a_version_1_run_leaves_it_as_it_was(tmp_path: Path) -> None:
    out = tmp_path / "v1.sqlite"
    scene = scene_file(tmp_path)
    acquire(plan_file(tmp_path, target=3), scene, out)
    _as_version_1(out)
    before = out.read_bytes()
    scene.write_text(scene.read_text(encoding="utf-8") + "\n# changed\n", encoding="utf-8")
    with pytest.raises(ConfigError, match="the scene file changed since the run started"):
        workflows.resume(out, scene_path=scene)
    assert out.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.yaml", "small.yaml", "v1.sqlite"]


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
