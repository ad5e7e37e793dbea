"""`gonio export --format bluesky`: JSON lines of ``[name, document]`` read back with the
json module and validated with event-model's own schemas."""

from __future__ import annotations

import json
from pathlib import Path

import event_model
import numpy as np
import pytest

from gonio.analysis.calibrated import calibrate
from gonio.cli import main
from gonio.store import open_run


@pytest.fixture(scope="module")
def out(run_file: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("bluesky") / "run.jsonl"
    assert main(["export", str(run_file), "--format", "bluesky", "-o", str(path), "-q"]) == 0
    return path


@pytest.fixture(scope="module")
def docs(out: Path) -> list[tuple[str, dict]]:
    return [tuple(json.loads(line)) for line in out.read_text(encoding="utf-8").splitlines()]


def test_every_document_is_valid_by_the_event_model_schemas(docs):
    for name, doc in docs:
        event_model.schema_validators[event_model.DocumentNames[name]].validate(doc)


def test_start_descriptors_events_stop_in_order(docs, run_file):
    run = open_run(run_file)
    names = [name for name, _ in docs]
    assert names[0] == "start" and names[-1] == "stop"
    assert names.count("start") == names.count("stop") == 1
    assert names.count("descriptor") == 2
    assert names.count("event") == len(run) + len(run.events)
    start, stop = docs[0][1], docs[-1][1]
    assert stop["run_start"] == start["uid"]
    assert stop["exit_status"] == "success"  # the run completed
    assert stop["num_events"] == {"primary": len(run), "journal": len(run.events)}
    assert start["gonio"]["plan_name"] == run.meta["plan_name"]
    assert start["gonio"]["hashes"] == run.meta["hashes"]
    assert start["columns"]["brdf_per_sr"]["units"] == "sr^-1"


def test_one_primary_event_per_sample_with_the_runs_values(docs, run_file):
    run = open_run(run_file)
    descriptors = {d["uid"]: d for name, d in docs if name == "descriptor"}
    primary = next(d for d in descriptors.values() if d["name"] == "primary")
    keys = primary["data_keys"]
    assert keys["brdf_per_sr"]["units"] == "sr^-1"
    assert keys["wi_x"]["dtype"] == "number" and keys["target"]["dtype"] == "integer"
    events = [d for name, d in docs if name == "event" and d["descriptor"] == primary["uid"]]
    assert [e["seq_num"] for e in events] == list(range(1, len(run) + 1))
    assert set(events[0]["data"]) == set(keys)
    cal = calibrate(run)
    np.testing.assert_array_equal([e["data"]["brdf_per_sr"] for e in events], cal.brdf)
    np.testing.assert_array_equal([e["data"]["target"] for e in events], run.target)
    np.testing.assert_array_equal([e["data"]["wo_z"] for e in events], run.samples["wo_z"])


def test_the_journal_stream_holds_every_event(docs, run_file):
    run = open_run(run_file)
    journal = next(d for name, d in docs if name == "descriptor" and d["name"] == "journal")
    events = [d for name, d in docs if name == "event" and d["descriptor"] == journal["uid"]]
    assert [e["data"]["kind"] for e in events] == [e.kind for e in run.events]
    assert json.loads(events[0]["data"]["data"]) == json.loads(json.dumps(dict(run.events[0].data)))


def test_the_same_run_gives_the_same_file(out, run_file, tmp_path):
    again = tmp_path / "again.jsonl"
    assert main(["export", str(run_file), "--format", "bluesky", "-o", str(again), "-q"]) == 0
    assert again.read_bytes() == out.read_bytes()
