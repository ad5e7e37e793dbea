"""Stored plans: a plan written and read back is the same plan bit for bit, frozen, named
by the hash of the texts it was built from; a bad or altered file is one `ConfigError`
line naming the file, never a traceback."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from gonio.config import ConfigError
from gonio.planner import build, content_hash, load_plan, load_plan_source, read_plan
from gonio.planner.model import ARRAYS, Plan
from gonio.planner.schema import PlanSpec
from gonio.planner.stored import MAGIC, columns, write_plan
from gonio.rig.model import Rig
from gonio.rig.schema import RigSpec
from tests.conftest import CONFIGS

PLANS = CONFIGS / "plans"


def spec(**fields: Any) -> PlanSpec:
    data: dict[str, Any] = {
        "name": "stored",
        "parametrization": "hybrid",
        "sampling": {"strategy": "sobol", "target": 150},
        "kicks": 50,  # a short search: these tests are about storing, not the tour
    }
    data.update(fields)
    return PlanSpec.model_validate(data)


ADAPT = {
    "material": {"name": "cook_torrance", "alpha": 0.2, "fresnel": "schlick", "f0": 0.04},
    "min_s": 0.02,
    "max_s": 0.5,
    "max_averages": 4,
}

#: (id, rig, spec, bounds): isotropic and anisotropic, both rigs, a grid, adapted exposure.
VARIANTS = [
    ("arch-iso", "arch", spec(), True),
    ("arch-aniso", "arch", spec(isotropic=False), False),
    ("in_plane-aniso", "in_plane", spec(isotropic=False, max_moves=40), True),
    (
        "in_plane-grid",
        "in_plane",
        spec(sampling={"strategy": "grid", "counts": {"hbar": 5, "k": 4, "phi_k_minus_phi_h": 3}}),
        False,
    ),
    ("arch-adapted", "arch", spec(exposure={"seconds": 0.1, "adapt": ADAPT}), False),
]


def assert_identical(a: Plan, b: Plan) -> None:
    """Every array equal and of identical bits; spec, texts and summary equal."""
    for name, dtype in ARRAYS.items():
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype == dtype, name
        assert np.array_equal(x, y), name
        if dtype == np.float64:
            assert np.array_equal(x.view(np.int64), y.view(np.int64)), name
    assert a.spec == b.spec
    assert a.summary == b.summary
    assert a.plan_text == b.plan_text and a.rig.text == b.rig.text
    assert a.coordinate_names == b.coordinate_names
    assert a == b


@pytest.mark.parametrize(
    ("rig", "s", "bounds"), [v[1:] for v in VARIANTS], ids=[v[0] for v in VARIANTS]
)
def test_write_then_read_is_the_same_plan_bit_for_bit(
    rigs: dict[str, Rig], tmp_path: Path, rig: str, s: PlanSpec, bounds: bool
) -> None:
    plan = build(s, rigs[rig], bounds=bounds)
    path = tmp_path / "plan.csv"
    write_plan(plan, path)
    again = read_plan(path)  # the rig rebuilt from the text the file carries
    assert_identical(again, plan)
    assert again.rig.axes == plan.rig.axes
    assert np.array_equal(again.rig.limits, plan.rig.limits)
    assert again.ordering is None  # the search's diagnostics are not stored
    assert_identical(read_plan(path, rig=plan.rig), plan)
    # Written again, byte for byte the same file.
    write_plan(again, tmp_path / "again.csv")
    assert (tmp_path / "again.csv").read_bytes() == path.read_bytes()


def test_awkward_floats_survive(rigs: dict[str, Rig], tmp_path: Path) -> None:
    """Signed zeros, subnormals, the extremes of float64 and values with no short
    decimal form come back as the same bits."""
    plan = build(spec(), rigs["arch"])
    n = len(plan)
    awkward = np.array([-0.0, 5e-324, 2.2250738585072014e-308, 1.7976931348623157e308, 0.1 + 0.2])
    values = np.resize(awkward, n) * np.where(np.arange(n) % 2 == 0, 1.0, -1.0)
    values[np.arange(n) % 7 == 3] = 1.0 / 3.0
    odd = dataclasses.replace(plan, arrival_s=values, coords=plan.coords + values[:, None] * 1e-300)
    write_plan(odd, tmp_path / "odd.csv")
    back = read_plan(tmp_path / "odd.csv", rig=plan.rig)
    assert_identical(back, odd)
    assert np.signbit(back.arrival_s[0]) and back.arrival_s[0] == 0.0


def test_a_plan_is_frozen_and_owns_its_arrays(rigs: dict[str, Rig], tmp_path: Path) -> None:
    plan = build(spec(), rigs["arch"])
    for name in ARRAYS:
        array = getattr(plan, name)
        assert not array.flags.writeable, name
        with pytest.raises(ValueError, match="read-only"):
            array[0] = array[0]
    with pytest.raises(dataclasses.FrozenInstanceError):
        plan.angles = plan.angles  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        plan.summary.kept = 3  # type: ignore[misc]
    with pytest.raises(TypeError):
        plan.summary.refused["theta_max"] = 0  # type: ignore[index]
    # A plan made from arrays someone else holds keeps its own copies.
    angles = np.array(plan.angles)
    made = dataclasses.replace(plan, angles=angles)
    angles[0, 0] = 99.0
    assert made.angles[0, 0] == plan.angles[0, 0]
    write_plan(plan, tmp_path / "p.csv")
    back = read_plan(tmp_path / "p.csv")
    assert not any(getattr(back, name).flags.writeable for name in ARRAYS)
    with pytest.raises(dataclasses.FrozenInstanceError):
        back.summary.moves = 0  # type: ignore[misc]


def test_plans_differing_in_one_bit_are_not_equal(rigs: dict[str, Rig]) -> None:
    plan = build(spec(), rigs["arch"])
    arrival = np.array(plan.arrival_s)
    arrival[5] = np.nextafter(arrival[5], np.inf)
    assert dataclasses.replace(plan, arrival_s=arrival) != plan
    zero = np.array(plan.angles)
    assert np.any(zero == 0.0)
    zero[zero == 0.0] = -0.0  # equal as numbers, not as bits
    assert dataclasses.replace(plan, angles=zero) != plan
    assert dataclasses.replace(plan) == plan


def test_layout_is_the_documented_one(tmp_path: Path) -> None:
    source = load_plan_source(PLANS / "quick.yaml")
    plan = source.build()
    path = tmp_path / "quick.csv"
    write_plan(plan, path)
    lines = path.read_text(encoding="utf-8").split("\n")
    assert lines[0] == MAGIC == "# gonio-plan v1"
    keys = [line[2:].partition(":")[0] for line in lines[1:7]]
    assert keys == ["spec", "plan_text", "rig", "rig_text", "summary", "hashes"]
    header = {
        k: json.loads(line.partition(": ")[2]) for k, line in zip(keys, lines[1:7], strict=True)
    }
    assert PlanSpec.model_validate(header["spec"]) == source.spec
    assert header["plan_text"].encode() == (PLANS / "quick.yaml").read_bytes()
    assert header["rig"] == "arch-4axis"
    assert header["rig_text"].encode() == (CONFIGS / "rigs" / "arch.yaml").read_bytes()
    assert header["summary"]["kept"] == 500 and header["summary"]["stopped"] == "converged"
    hashes = header["hashes"]
    assert hashes["plan_sha256"] == hashlib.sha256(source.text).hexdigest()
    assert hashes["rig_sha256"] == hashlib.sha256(source.rig.text).hexdigest()
    assert hashes["content"] == source.content_hash() == plan.content_hash()
    without = "\n".join(lines[:6] + lines[7:]).encode("utf-8")
    assert hashes["file_sha256"] == hashlib.sha256(without).hexdigest()
    assert lines[7].split(",") == columns(plan.coordinate_names, plan.rig.axes)
    assert lines[7].split(",")[-4:] == ["exposure_s", "averages", "travel_s", "arrival_s"]
    assert len(lines) == 8 + 500 + 1 and lines[-1] == ""  # one row per target, final newline


def test_content_hash_framing() -> None:
    """The documented framing, recomputed by hand; the lengths keep the parts apart."""
    expected = hashlib.sha256(b"gonio content v1\nplan 2\nabrig 1\ncscene -\n").hexdigest()
    assert content_hash(b"ab", b"c") == expected
    assert content_hash(b"ab", b"c", None) == expected
    assert content_hash(b"ab", b"c") != content_hash(b"a", b"bc")
    assert content_hash(b"a", b"b", b"") != content_hash(b"a", b"b")
    assert content_hash(b"a", b"b", b"c") != content_hash(b"a", b"bc", None)
    with_scene = hashlib.sha256(b"gonio content v1\nplan 1\narig 1\nbscene 3\nxyz").hexdigest()
    assert content_hash(b"a", b"b", b"xyz") == with_scene
    assert len(expected) == 64
    aligned = hashlib.sha256(
        b"gonio content v1\nplan 1\narig 1\nbscene -\nalignment 2\nqq"
    ).hexdigest()
    assert content_hash(b"a", b"b", None, b"qq") == aligned
    assert content_hash(b"a", b"b", None, b"") != content_hash(b"a", b"b")


def test_load_plan_source_keeps_the_files_bytes(rigs: dict[str, Rig]) -> None:
    source = load_plan_source(PLANS / "quick.yaml")
    assert source.text == (PLANS / "quick.yaml").read_bytes()
    assert source.rig.text == (CONFIGS / "rigs" / "arch.yaml").read_bytes()
    scene = (CONFIGS / "scenes" / "matte.yaml").read_bytes()
    assert source.content_hash(scene) == content_hash(source.text, source.rig.text, scene)
    spec_, rig = load_plan(PLANS / "quick.yaml")  # the old signature still works
    assert spec_ == source.spec and rig.text == source.rig.text
    # A spec made in code has its YAML as text, which reads back as the same spec.
    made = build(spec(), rigs["arch"])
    assert made.plan_text.startswith(b"name: stored\n")
    assert PlanSpec.model_validate(yaml.safe_load(made.plan_text)) == made.spec
    in_code = Rig(rigs["in_plane"].spec)
    assert RigSpec.model_validate(yaml.safe_load(in_code.text)) == in_code.spec


# --- files that are refused --------------------------------------------------------


@pytest.fixture(scope="module")
def stored(quick_plan: Plan, tmp_path_factory: pytest.TempPathFactory) -> tuple[Plan, bytes]:
    plan = quick_plan
    path = tmp_path_factory.mktemp("stored") / "quick.csv"
    write_plan(plan, path)
    return plan, path.read_bytes()


def rehash(data: bytes) -> bytes:
    """The file with its file_sha256 recomputed, as a deliberate edit would."""
    lines = data.split(b"\n")
    at = next(i for i, line in enumerate(lines) if line.startswith(b"# hashes: "))
    hashes = json.loads(lines[at][len(b"# hashes: ") :])
    rest = b"\n".join(lines[:at] + lines[at + 1 :])
    hashes["file_sha256"] = hashlib.sha256(rest).hexdigest()
    lines[at] = b"# hashes: " + json.dumps(hashes).encode()
    return b"\n".join(lines)


def edit_line(data: bytes, number: int, change: Any) -> bytes:
    lines = data.split(b"\n")
    lines[number - 1] = change(lines[number - 1])
    return b"\n".join(lines)


def drop_column(data: bytes, name: bytes) -> bytes:
    lines = data.split(b"\n")
    j = lines[7].split(b",").index(name)
    for i in range(7, len(lines) - 1):
        cells = lines[i].split(b",")
        lines[i] = b",".join(cells[:j] + cells[j + 1 :])
    return b"\n".join(lines)


def test_an_older_plan_with_wall_times_in_its_summary_reads(
    tmp_path: Path, stored: tuple[Plan, bytes]
) -> None:
    """Plans stored before the wall times left the summary (figures of the machine, so
    a stored plan is the same bytes on any machine) read back as the same plan."""
    plan, data = stored
    assert b'"ordering_s"' not in data and b'"bound_wall_s"' not in data
    older = rehash(
        data.replace(b'"dwell_s": ', b'"ordering_s": 0.3, "bound_wall_s": null, "dwell_s": ', 1)
    )
    path = tmp_path / "older.csv"
    path.write_bytes(older)
    again = read_plan(path)
    assert again == plan and again.ordering_s is None


BAD: list[tuple[str, Any, str]] = [
    ("empty", lambda d: b"", r":1: not a stored gonio plan: expected '# gonio-plan v1'"),
    ("yaml", lambda d: (PLANS / "quick.yaml").read_bytes(), r":1: not a stored gonio plan"),
    (
        "version",
        lambda d: d.replace(b"# gonio-plan v1", b"# gonio-plan v2", 1),
        r":1: format version 'v2'; this gonio reads 'gonio-plan v1' only",
    ),
    (
        "missing-summary",
        lambda d: b"\n".join(x for x in d.split(b"\n") if not x.startswith(b"# summary")),
        r": header: expected a '# summary: …' line before the CSV",
    ),
    (
        "bad-json",
        lambda d: edit_line(d, 6, lambda x: x[:-5]),
        r":6: summary: not valid JSON",
    ),
    (
        "unknown-key",
        lambda d: edit_line(d, 4, lambda x: x.replace(b"# rig:", b"# rigg:")),
        r":4: expected a header line '# KEY: JSON' with KEY one of",
    ),
    (
        "changed-value",
        lambda d: d.replace(b",0.05,1,", b",0.06,1,", 1),
        r": the file does not match hashes.file_sha256: it was changed or cut short",
    ),
    (
        "truncated",
        lambda d: d[: len(d) // 2],
        r": the file does not match hashes.file_sha256",
    ),
    (
        "changed-summary",
        lambda d: d.replace(b'"kept": 500', b'"kept": 499', 1),
        r": the file does not match hashes.file_sha256",
    ),
    (
        "changed-rig-text",
        lambda d: rehash(d.replace(b"max_deg: 85", b"max_deg: 86", 1)),
        r":5: rig_text: does not match hashes.rig_sha256; the file was changed",
    ),
    (
        "missing-column",
        lambda d: rehash(drop_column(d, b"travel_s")),
        r":8: columns: missing column 'travel_s'; expected index,generated,",
    ),
    (
        "not-a-number",
        lambda d: rehash(d.replace(b",0.05,1,", b",0.05x,1,", 1)),
        r":9: exposure_s: expected a number, got '0.05x'",
    ),
    (
        "infinite",
        lambda d: rehash(d.replace(b",0.05,1,", b",inf,1,", 1)),
        r":9: exposure_s: expected a finite number, got 'inf'",
    ),
    (
        "row-missing",
        lambda d: rehash(d[: d.rstrip(b"\n").rfind(b"\n") + 1]),
        r": expected 500 targets \(summary.kept\), got 499",
    ),
    (
        "short-row",
        lambda d: rehash(edit_line(d, 9, lambda x: x.rsplit(b",", 1)[0])),
        r":9: expected 19 fields, got 18",
    ),
]


@pytest.mark.parametrize(("change", "message"), [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_files_are_one_line_errors(
    tmp_path: Path, stored: tuple[Plan, bytes], change: Any, message: str
) -> None:
    path = tmp_path / "bad.csv"
    path.write_bytes(change(stored[1]))
    with pytest.raises(ConfigError) as info:
        read_plan(path)
    text = str(info.value)
    assert text.startswith(str(path)), text
    assert "\n" not in text
    assert re.search(message, text), text


def test_another_rig_is_refused_by_hash(
    rigs: dict[str, Rig], tmp_path: Path, stored: tuple[Plan, bytes]
) -> None:
    path = tmp_path / "quick.csv"
    path.write_bytes(stored[1])
    for other in (rigs["in_plane"], CONFIGS / "rigs" / "in_plane.yaml"):
        with pytest.raises(ConfigError, match=r":4: rig: the plan was built for rig 'arch-4axis'"):
            read_plan(path, rig=other)
    # The same rig with one comment changed is another file: refused too.
    text = (CONFIGS / "rigs" / "arch.yaml").read_bytes() + b"# moved to lab 2\n"
    (tmp_path / "arch.yaml").write_bytes(text)
    with pytest.raises(ConfigError, match="not the same rig file"):
        read_plan(path, rig=tmp_path / "arch.yaml")
    assert read_plan(path, rig=CONFIGS / "rigs" / "arch.yaml") == stored[0]


def test_unreadable_files(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"missing.csv: cannot read the plan"):
        read_plan(tmp_path / "missing.csv")
    (tmp_path / "latin1.csv").write_bytes(b"# gonio-plan v1\n# spec: \xe9\n")
    with pytest.raises(ConfigError, match=r"latin1.csv: not UTF-8 text"):
        read_plan(tmp_path / "latin1.csv")
