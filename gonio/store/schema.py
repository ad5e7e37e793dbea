"""The run journal's ``samples`` table, defined once (docs/reference/journal.md).

Each column has its name, its SQL type, the numpy dtype `gonio.store.open_run` reads it
as, and whether it may be NULL. The writer (`gonio.store.journal`: the ``CREATE TABLE``
and the insert), the reader (`gonio.store.read`) and the engine's row builder
(`gonio.acquire.engine`) all take the table from here. The columns of a rig's axes and a
plan's coordinates are named by `commanded`, `read_back` and `coordinate`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

SqlType = Literal["INTEGER", "REAL", "TEXT"]

INT64 = np.dtype(np.int64)
BOOL = np.dtype(np.bool_)
FLOAT64 = np.dtype(np.float64)
OBJECT = np.dtype(object)


@dataclass(frozen=True)
class Column:
    """One column of the ``samples`` table: ``sql`` its SQLite type, ``dtype`` the numpy
    dtype it is read as (a NULL of a float64 column reads as NaN, of an object column
    as None), ``nullable`` whether it may be NULL, ``key`` whether it is the primary
    key."""

    name: str
    sql: SqlType
    dtype: np.dtype[Any]
    nullable: bool = False
    key: bool = False

    def ddl(self) -> str:
        """The column's definition in ``CREATE TABLE samples``."""
        null = "" if self.nullable else " NOT NULL"
        key = " PRIMARY KEY" if self.key else ""
        return f'"{self.name}" {self.sql}{null}{key}'


def commanded(axis: str) -> str:
    """The column of the pose sent to ``axis`` (rad)."""
    return f"{axis}_commanded_rad"


def read_back(axis: str) -> str:
    """The column of ``axis``'s pose read back after settling (rad)."""
    return f"{axis}_read_back_rad"


def coordinate(name: str) -> str:
    """The column of the plan coordinate ``name``."""
    return f"coord_{name}"


def _real(name: str) -> Column:
    return Column(name, "REAL", FLOAT64)


def _integer(name: str) -> Column:
    return Column(name, "INTEGER", INT64)


def samples_table(axes: Sequence[str], coordinate_names: Sequence[str]) -> tuple[Column, ...]:
    """The ``samples`` table's columns, in order, for a rig's axes and a plan's
    coordinates (units: docs/reference/journal.md)."""
    return (
        Column("target", "INTEGER", INT64, key=True),
        _integer("session"),
        _integer("attempts"),
        *(_real(commanded(a)) for a in axes),
        *(_real(read_back(a)) for a in axes),
        *map(_real, ("wi_x", "wi_y", "wi_z", "wo_x", "wo_y", "wo_z")),
        *(_real(coordinate(c)) for c in coordinate_names),
        _real("exposure_s"),
        _integer("averages"),
        _integer("n"),
        _real("counts"),
        Column("counts_std", "REAL", FLOAT64, nullable=True),  # a device's average: no spread
        Column("saturated", "INTEGER", BOOL),  # stored 0/1
        _integer("remeasured"),
        _real("settled_s"),
        _real("started_s"),
        _real("ended_s"),
        Column("utc", "TEXT", OBJECT),
        Column("temperatures_c", "TEXT", OBJECT, nullable=True),  # JSON
        Column("sim_state", "TEXT", OBJECT, nullable=True),  # JSON
        # Version 2: a fly reading's smear and timing uncertainty (rad; NULL stop-and-go)
        Column("smear_rad", "REAL", FLOAT64, nullable=True),
        Column("timing_rad", "REAL", FLOAT64, nullable=True),
    )


#: Columns a version-1 run file lacks (read as NaN).
ADDED_IN_2 = ("smear_rad", "timing_rad")


def samples_ddl(table: Sequence[Column]) -> str:
    """``CREATE TABLE samples (…)`` of ``table``."""
    return f"CREATE TABLE samples ({', '.join(c.ddl() for c in table)})"
