"""The output folder's store: rows read back bit for bit, a line torn by a kill dropped
(and cut off the file, so the next row starts on a line of its own), a damaged line
refused in one line, one sweep at a time, and the CSV rendering."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from gonio.config import ConfigError
from gonio.tradeoff.store import RESULTS_JSONL, csv_text, open_store

ROW = {"id": "a1", "x": 0.1 + 0.2, "tiny": 5e-324, "none": None, "text": 'ω, "q"'}


def test_rows_read_back_bit_for_bit(tmp_path: Path) -> None:
    with open_store(tmp_path / "out") as store:
        assert store.rows == {}
        store.append(ROW)
        store.append({**ROW, "id": "b2"})
    with open_store(tmp_path / "out") as store:
        assert list(store.rows) == ["a1", "b2"]
        assert store.rows["a1"] == ROW and store.rows["a1"]["x"] == 0.30000000000000004


def test_a_torn_last_line_is_dropped(tmp_path: Path) -> None:
    out = tmp_path / "out"
    with open_store(out) as store:
        store.append(ROW)
    path = out / RESULTS_JSONL
    with open(path, "ab") as stream:
        stream.write(b'{"id": "b2", "x": 0.')
    with open_store(out) as store:
        assert list(store.rows) == ["a1"]
        store.append({**ROW, "id": "c3"})
    with open_store(out) as store:
        assert list(store.rows) == ["a1", "c3"]


def test_a_damaged_line_and_a_second_sweep_are_refused(tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / RESULTS_JSONL).write_text('{"id": "a1"}\n[1, 2]\n')
    with pytest.raises(ConfigError, match=r"results.jsonl:2: not a results row"):
        open_store(out).__enter__()
    (out / RESULTS_JSONL).write_text("")
    with open_store(out), pytest.raises(ConfigError, match="another sweep is writing"):
        open_store(out).__enter__()
    (tmp_path / "file").write_text("")
    with pytest.raises(ConfigError, match="is a file; expected an output folder"):
        open_store(tmp_path / "file").__enter__()
    with pytest.raises(ConfigError, match="cannot use it"):
        open_store(tmp_path / "no" / "such").__enter__()


def test_csv_writes_floats_exactly_and_none_as_empty() -> None:
    text = csv_text([ROW], ["id", "x", "tiny", "none", "text", "missing"])
    header, line = text.splitlines()
    assert header == "id,x,tiny,none,text,missing"
    assert line == 'a1,0.30000000000000004,5e-324,,"ω, ""q""",'
    assert float(line.split(",")[2]) == 5e-324 and not math.isnan(float(line.split(",")[1]))


def test_a_row_with_nan_is_refused(tmp_path: Path) -> None:
    with open_store(tmp_path / "out") as store, pytest.raises(ValueError, match="JSON"):
        store.append({"id": "x", "v": math.nan})
