"""Every command refuses a damaged or hostile file with one line naming the file or the
field and exit code 2: never a traceback, a hang, or an allocation the file's size
fields ask for (docs/reference/damaged-files.md). Real files in
tmp_path, each command run in-process through `gonio.cli.main`:

- run files, for ``info``, ``evaluate``, ``fit``, ``plot``, ``export``, ``watch``,
  ``acquire --resume`` and ``serve`` (its folder listing and its endpoints): zero
  bytes, truncated, random bytes, an SQLite file that is not a run, a newer schema, the
  stored plan or texts edited (to garbage, or to a value that parses but is not what
  the writer stores), a run locked by another process;
- measured-material files (MERL, UTIA, RGL ``.bsdf``, the factored format) truncated or
  with absurd sizes in their header, through a scene of ``gonio simulate``;
- sweep files of ``gonio tradeoff``: an alias bomb, an unknown axis, a billion
  combinations; and a scheduler address that does not answer, or answers garbage.
"""

from __future__ import annotations

import contextlib
import os
import random
import shutil
import socket
import sqlite3
import struct
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest
import yaml

from gonio.brdf import merl, tensor_file, utia
from gonio.store import readonly
from gonio.tradeoff import executors
from tests.conftest import CONFIGS, CliResult
from tests.gonio.test_config_fuzz import bounded
from tests.gonio.tradeoff.conftest import SMALL, write_sweep
from tests.support.acquire import acquire, plan_file, scene_file

Gonio = Callable[..., CliResult]


def one_line(result: CliResult, *words: str) -> str:
    """The refusal's line: exit code 2, one line on stderr holding ``words``."""
    assert result.returncode == 2, (result.returncode, result.stderr[-2000:])
    assert "Traceback" not in result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr[-2000:]
    for word in words:
        assert word in lines[0], lines[0]
    return lines[0]


# -- run files ---------------------------------------------------------------------------


@pytest.fixture(scope="module")
def original(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A small complete run on the simulated backend, made once."""
    folder = tmp_path_factory.mktemp("damaged-run")
    out = folder / "run.sqlite"
    acquire(plan_file(folder, target=8), scene_file(folder), out)
    return out


#: The commands that read a run file: name → arguments (the run file and a work folder).
READERS: dict[str, Callable[[Path, Path], list[str]]] = {
    "info": lambda run, tmp: ["info", str(run)],
    "evaluate": lambda run, tmp: ["evaluate", str(run)],
    "fit": lambda run, tmp: ["fit", str(run), "--model", "lambert"],
    "plot": lambda run, tmp: ["plot", str(run), "--kind", "coverage", "-o", str(tmp / "p.png")],
    "export": lambda run, tmp: ["export", str(run), "--format", "csv", "-o", str(tmp / "x.csv")],
    "resume": lambda run, tmp: ["acquire", "--resume", str(run), "-q"],
    "watch": lambda run, tmp: ["watch", str(run), "--once"],
}


@contextlib.contextmanager
def editing(path: Path) -> Iterator[sqlite3.Connection]:
    """A connection to ``path`` whose changes are committed and checkpointed into the
    file when the block ends (the last connection closed)."""
    conn = sqlite3.connect(path)
    try:
        with conn:
            yield conn
    finally:
        conn.close()


def _sql(*statements: str) -> Callable[[Path], None]:
    def edit(path: Path) -> None:
        with editing(path) as conn:
            for statement in statements:
                conn.execute(statement)

    return edit


def _bytes(make: Callable[[bytes], bytes]) -> Callable[[Path], None]:
    def edit(path: Path) -> None:
        path.write_bytes(make(path.read_bytes()))

    return edit


def _not_a_run(path: Path) -> None:
    path.unlink()
    _sql("CREATE TABLE t (x)", "INSERT INTO t VALUES (1)")(path)


def _plan_edited(path: Path) -> None:
    """The stored plan with one digit of its table changed (it still parses)."""
    with editing(path) as conn:
        raw = conn.execute("SELECT value FROM meta WHERE key = 'plan_file'").fetchone()[0]
        head, sep, body = bytes(raw).partition(b"\nindex,")
        body = body.replace(b"0.", b"1.", 1)
        conn.execute("UPDATE meta SET value = ? WHERE key = 'plan_file'", (head + sep + body,))


def _scene_text(text: str) -> Callable[[Path], None]:
    def edit(path: Path) -> None:
        with editing(path) as conn:
            conn.execute("UPDATE meta SET value = json_quote(?) WHERE key = 'scene_text'", (text,))

    return edit


LAUGHS = 'a0: &a0 "lol"\n' + "".join(
    f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 10)}]\n" for i in range(1, 10)
)

#: Damage → (the edit of a copy of the run file, words of the refusal).
DAMAGE: dict[str, tuple[Callable[[Path], None], str]] = {
    "zero bytes": (_bytes(lambda raw: b""), "not a gonio run file"),
    "truncated": (_bytes(lambda raw: raw[: len(raw) // 2]), "database disk image is malformed"),
    "truncated mid-page": (_bytes(lambda raw: raw[:5000]), "database disk image is malformed"),
    "random bytes": (
        _bytes(lambda raw: random.Random(1).randbytes(len(raw))),
        "file is not a database",
    ),
    "an SQLite file, not a run": (_not_a_run, "not a gonio run file"),
    "a newer schema": (_sql("PRAGMA user_version=99"), "schema version 99"),
    "plan: garbage": (
        _sql("UPDATE meta SET value = x'00ff' WHERE key = 'plan_file'"),
        "plan_file:1: not a stored gonio plan",
    ),
    "plan: edited": (_plan_edited, "does not match hashes.file_sha256"),
    "meta: not JSON": (
        _sql("UPDATE meta SET value = '{' WHERE key = 'axes'"),
        "meta.axes: expected JSON text",
    ),
    "meta: another type": (
        _sql("UPDATE meta SET value = '5' WHERE key = 'backend'"),
        "meta.backend: expected a text, got 5",
    ),
    "meta: unknown backend": (
        _sql("""UPDATE meta SET value = '"warp"' WHERE key = 'backend'"""),
        "meta.backend: expected one of simulated",
    ),
    "meta: a key missing": (
        _sql("DELETE FROM meta WHERE key = 'coordinate_names'"),
        "meta.coordinate_names: missing",
    ),
    "meta: axes not the plan's": (
        _sql("""UPDATE meta SET value = '["a","b","c","d"]' WHERE key = 'axes'"""),
        "meta.axes: expected the stored plan's rig axes",
    ),
    "event: not JSON": (
        _sql("UPDATE events SET data = '{' WHERE kind = 'calibration'"),
        ".data: expected JSON text",
    ),
    "event: a field missing": (
        _sql(
            "UPDATE events SET data = json_remove(data, '$.reference.exposure_s') "
            "WHERE kind = 'calibration'"
        ),
        ".data.reference.exposure_s: missing",
    ),
    "event: NaN": (
        _sql(
            "UPDATE events SET data = replace(data, '\"albedo\":0.99', '\"albedo\":NaN') "
            "WHERE kind = 'calibration'"
        ),
        ".data: expected JSON text",
    ),
    "event: a recovery's number as a text": (
        _sql(
            'UPDATE events SET kind = \'recovery\', data = \'{"step":"diagnosed",'
            '"axis":"light_elevation","temperature_c":"hot"}\' WHERE kind = \'health\''
        ),
        ".data.temperature_c: expected a finite number, got 'hot'",
    ),
    "event: a recovery's axis missing": (
        _sql(
            "UPDATE events SET kind = 'recovery', data = '{\"step\":\"rebooted\"}' "
            "WHERE kind = 'health'"
        ),
        ".data.axis: missing",
    ),
    "session: a list": (_sql("UPDATE sessions SET info = '[]'"), "info: expected a JSON object"),
    "sample: text for a number": (
        _sql("UPDATE samples SET counts = 'abc' WHERE target = 3"),
        "samples.counts (row 3): expected a finite number, got 'abc'",
    ),
    "sample: infinite": (
        _sql("UPDATE samples SET counts = 1e999 WHERE target = 3"),
        "samples.counts (row 3): expected a finite number, got inf",
    ),
    "sample: not a unit vector": (
        _sql("UPDATE samples SET wi_x = 1e300 WHERE target = 3"),
        "samples.wi_x, _y, _z (row 3): expected a unit vector",
    ),
    "sample: no exposure": (
        _sql("UPDATE samples SET exposure_s = 0 WHERE target = 3"),
        "samples.exposure_s (row 3): expected a positive time",
    ),
    "sample: a target the plan lacks": (
        _sql("UPDATE samples SET target = 999 WHERE target = 3"),
        "samples.target: 999; expected 0 … 7",
    ),
    "sample: a column missing": (
        _sql("ALTER TABLE samples DROP COLUMN counts_std"),
        "samples: column 'counts_std' missing",
    ),
}


#: The damage to the file as a whole, tried with every reader; the damage to a value,
#: which `open_run` refuses for all of them alike, with four (evaluate also reads the
#: stored scene and the calibrations; resume writes; watch follows the file as it grows,
#: `gonio.store.follow`, with the same checks).
WHOLE_FILE = ("zero bytes", "truncated", "random bytes", "an SQLite file, not a run")
CASES = [
    (damage, command)
    for damage in DAMAGE
    for command in (READERS if damage in WHOLE_FILE else ("info", "evaluate", "resume", "watch"))
]


@pytest.mark.parametrize(("damage", "command"), CASES)
def test_a_damaged_run_file_is_one_line(
    original: Path, tmp_path: Path, run_gonio: Gonio, damage: str, command: str
) -> None:
    path = tmp_path / "run.sqlite"
    shutil.copy(original, path)
    edit, words = DAMAGE[damage]
    edit(path)
    before = path.read_bytes()
    result = bounded(lambda: run_gonio(*READERS[command](path, tmp_path)))
    assert isinstance(result, CliResult)
    one_line(result, str(path.name), words)
    assert path.read_bytes() == before  # refused before anything is written to it


@pytest.mark.parametrize("command", list(READERS))
def test_the_intact_copy_is_read(
    original: Path, tmp_path: Path, run_gonio: Gonio, command: str
) -> None:
    """The damage above is the only difference: an intact copy passes every reader."""
    path = tmp_path / "run.sqlite"
    shutil.copy(original, path)
    result = run_gonio(*READERS[command](path, tmp_path))
    assert result.returncode == 0, result.stderr[-2000:]


def test_a_served_folder_of_damaged_run_files_lists_each_as_unreadable(
    original: Path, tmp_path: Path
) -> None:
    """``gonio serve`` over a folder holding every damaged file beside an intact copy:
    the listing shows each damaged one as unreadable with the one-line reason, its
    endpoints answer a JSON error (422) naming the file, and the intact one is served."""
    pytest.importorskip("starlette", reason="gonio serve needs the live extra")
    from gonio.live import server  # optional: the live extra (Starlette)
    from tests.gonio.live.conftest import serving
    from tests.gonio.live.test_server import call

    folder = tmp_path / "runs"
    folder.mkdir()
    shutil.copy(original, folder / "intact.sqlite")
    files = {}
    for i, (damage, (edit, words)) in enumerate(DAMAGE.items()):
        path = folder / f"damaged-{i:02d}.sqlite"
        shutil.copy(original, path)
        edit(path)
        files[path.name] = (damage, words)
    with serving(server.Served(folder)) as url:
        status, body, _ = call(f"{url}/api/runs")
        assert status == 200, body
        listed = {run["name"]: run for run in body["runs"]}
        assert listed["intact.sqlite"]["state"] == "completed"
        for name, (damage, words) in files.items():
            run = listed[name]
            assert run["state"] == "unreadable", (damage, run)
            assert "\n" not in run["error"] and name in run["error"], (damage, run)
            assert words in run["error"], (damage, run)
            for view in ("overview", "points"):
                status, answer, _ = call(f"{url}/api/{view}?run={name}")
                assert status == 422 and name in answer["error"], (damage, view, answer)
        for view in ("overview", "points"):
            assert call(f"{url}/api/{view}?run=intact.sqlite")[0] == 200


#: An edited stored scene → (its text, words of the refusal, the commands that read
#: what is wrong: the YAML is parsed for the detector's band, the material for a truth).
SCENE_TEXTS = {
    "not YAML": ("scene: [", "not valid YAML", ("evaluate", "fit", "plot")),
    "an alias bomb": (LAUGHS, "values (aliases expanded)", ("evaluate", "fit", "plot")),
    "a material of another shape": (
        "material: {name: lambert, albedo: nope}\n",
        "material.",
        ("evaluate",),
    ),
}


@pytest.mark.parametrize("command", ["info", "evaluate", "fit", "plot", "resume"])
@pytest.mark.parametrize("case", list(SCENE_TEXTS))
def test_an_edited_stored_scene_is_one_line_where_it_is_read(
    original: Path, tmp_path: Path, run_gonio: Gonio, case: str, command: str
) -> None:
    """The stored scene is parsed within a configuration file's bounds by the commands
    that compare with it; a resume refuses any edited stored text (its sha256); a
    command that does not read it reads the run."""
    path = tmp_path / "run.sqlite"
    shutil.copy(original, path)
    text, words, readers = SCENE_TEXTS[case]
    _scene_text(text)(path)
    result = bounded(lambda: run_gonio(*READERS[command](path, tmp_path)))
    assert isinstance(result, CliResult)
    if command == "resume":
        one_line(result, path.name, "the stored scene text does not match")
    elif command in readers:
        one_line(result, words)
    else:
        assert result.returncode == 0, result.stderr[-2000:]


HOLDER = """
import sqlite3, sys
conn = sqlite3.connect(sys.argv[1], isolation_level=None)
conn.execute("PRAGMA locking_mode=EXCLUSIVE")
conn.execute("BEGIN EXCLUSIVE")
conn.execute("INSERT INTO events (session, kind, t_s, utc, data) VALUES (1, 'x', 0, '', '{}')")
print("locked", flush=True)
sys.stdin.read()
"""


@contextlib.contextmanager
def holding(script: str, path: Path, ready: str) -> Iterator[None]:
    """Another process running ``script`` on ``path`` until the block ends (it prints
    ``ready`` once it holds what it holds)."""
    with subprocess.Popen(
        [sys.executable, "-c", script, str(path)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    ) as child:
        assert child.stdin is not None and child.stdout is not None
        try:
            assert child.stdout.readline().strip() == ready
            yield
        finally:
            child.stdin.close()
            child.wait(timeout=30)


@pytest.fixture
def held(original: Path, tmp_path: Path) -> Iterator[Path]:
    """A copy of the run that another process holds locked whole (a writer that took
    SQLite's exclusive lock: no reader gets in)."""
    path = tmp_path / "run.sqlite"
    shutil.copy(original, path)
    with holding(HOLDER, path, "locked"):
        yield path


@pytest.mark.timing
@pytest.mark.parametrize("command", ["info", "evaluate", "export", "watch"])
def test_a_run_locked_by_another_process_is_one_line_in_bounded_time(
    held: Path, tmp_path: Path, run_gonio: Gonio, monkeypatch: pytest.MonkeyPatch, command: str
) -> None:
    monkeypatch.setattr(readonly, "BUSY_TIMEOUT_S", 0.5)
    start = time.monotonic()
    result = run_gonio(*READERS[command](held, tmp_path))
    assert time.monotonic() - start < 5.0
    one_line(result, "another process holds the run file locked", "0.5 s waited")


#: What gonio's writer holds while it writes (`gonio.store.journal`): an exclusive flock
#: on the file and, in WAL mode, a write transaction (plain Python: a quick start).
WRITER = """
import fcntl, os, sqlite3, sys
fd = os.open(sys.argv[1], os.O_RDWR)
fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
conn = sqlite3.connect(sys.argv[1], isolation_level=None)
conn.execute("PRAGMA journal_mode=WAL")
conn.execute("BEGIN IMMEDIATE")
conn.execute("DELETE FROM samples")
print("writing", flush=True)
sys.stdin.read()
"""


def test_a_run_gonio_is_writing_is_read_as_its_last_commit(
    original: Path, tmp_path: Path, run_gonio: Gonio
) -> None:
    """gonio's own writer (its flock, a transaction open in WAL mode) never blocks a
    reader: the reader sees the last committed state."""
    path = tmp_path / "run.sqlite"
    shutil.copy(original, path)
    with holding(WRITER, path, "writing"):
        result = run_gonio("info", str(path), "--json")
        assert result.returncode == 0, result.stderr
        assert '"measured": 8' in result.stdout
        one_line(run_gonio("acquire", "--resume", str(path)), "another gonio acquire is writing")


# -- measured-material files --------------------------------------------------------------


def _merl_absurd(path: Path) -> None:
    path.write_bytes(struct.pack("<3i", 10**9, 10**9, 10**9) + b"\0" * 64)


def _merl_absurd_full_size(path: Path) -> None:
    with open(path, "wb") as f:
        f.write(struct.pack("<3i", 10**9, 10**9, 10**9))
        f.truncate(merl.FILE_SIZE)


def _merl_truncated(path: Path) -> None:
    with open(path, "wb") as f:
        f.write(struct.pack("<3i", *merl.SHAPE))
        f.truncate(merl.FILE_SIZE - 8)


def _merl_absurd_values(path: Path) -> None:
    """A well-formed MERL file whose values are finite but near float64's largest."""
    values = np.full(3 * merl.BINS, 1e307)
    path.write_bytes(struct.pack("<3i", *merl.SHAPE) + values.astype("<f8").tobytes())


def _utia_absurd_values(path: Path) -> None:
    path.write_bytes(np.full(utia.FILE_SIZE // 8, 1e306).astype("<f8").tobytes())


def _utia_truncated(path: Path) -> None:
    with open(path, "wb") as f:
        f.truncate(utia.FILE_SIZE - 1)


def _tensor(shape: tuple[int, ...], *, data: int = 64) -> bytes:
    header = tensor_file.MAGIC + struct.pack("<BBI", 1, 0, 1)
    field = struct.pack("<H", 4) + b"vndf" + struct.pack("<HBQ", len(shape), 10, 64)
    return header + field + struct.pack(f"<{len(shape)}Q", *shape) + b"\0" * data


#: The factored format's header fields after ``param`` (docs/reference/formats_factored.md).
FACTORED_LABELS = (
    "outer terms ('J' in paper)",
    "inner terms ('K' in paper)",
    "theta_out_count",
    "phi_out_count",
    "theta_p_count",
    "z_count",
    "phi_p_count",
)


def _factored(counts: tuple[int, ...], rows: int = 3) -> str:
    head = "param: halfangle\n" + "".join(
        f"{label}: {n}\n" for label, n in zip(FACTORED_LABELS, counts, strict=True)
    )
    return head + "INTENSITY DATA\nF_0\n" + "1 1\n" * rows


#: Material → (its ``name`` in a scene, the file's suffix, the damage, words of the refusal).
MATERIALS: dict[str, tuple[str, str, Callable[[Path], None], str]] = {
    "MERL: absurd header, short file": ("merl", ".binary", _merl_absurd, "not a MERL BRDF file"),
    "MERL: absurd header, full size": (
        "merl",
        ".binary",
        _merl_absurd_full_size,
        "MERL header (1000000000, 1000000000, 1000000000)",
    ),
    "MERL: truncated": ("merl", ".binary", _merl_truncated, "not a MERL BRDF file"),
    "MERL: zero bytes": ("merl", ".binary", lambda p: p.write_bytes(b""), "0 bytes"),
    "MERL: values of 1e307": (
        "merl",
        ".binary",
        _merl_absurd_values,
        "MERL values up to 1.11e+304 (4374000 beyond 1e+08); expected at most 1e+08",
    ),
    "UTIA: truncated": ("utia", ".bin", _utia_truncated, "not a UTIA BRDF file"),
    "UTIA: values of 1e306": (
        "utia",
        ".bin",
        _utia_absurd_values,
        "UTIA values up to 1e+306 (248832 beyond 1e+08); expected at most 1e+08",
    ),
    "factored: values of 1e307": (
        "factored",
        ".txt",
        lambda p: p.write_text(
            _factored((1, 1, 1, 1, 1, 1, 1), rows=12).replace("1 1\n", "1e307\n")
        ),
        "F_0: row 0: values up to 1e+307",
    ),
    "RGL: a shape of 2^40 × 2^40": (
        "rgl",
        ".bsdf",
        lambda p: p.write_bytes(_tensor((2**40, 2**40))),
        "runs past the end",
    ),
    "RGL: a side of 2^64 - 1 beside a 0": (
        "rgl",
        ".bsdf",
        lambda p: p.write_bytes(_tensor((0, 2**64 - 1))),
        "a side longer than the file",
    ),
    "RGL: truncated": (
        "rgl",
        ".bsdf",
        lambda p: p.write_bytes(_tensor((4, 4, 4, 4), data=0)[:40]),
        "truncated in",
    ),
    "factored: absurd counts": (
        "factored",
        ".txt",
        lambda p: p.write_text(_factored((10**9, 10**9, 10**9, 10**9, 10**9, 10**9, 10**9))),
        "the header states",
    ),
    "factored: truncated": (
        "factored",
        ".txt",
        lambda p: p.write_text(_factored((1, 1, 4, 2, 4, 4, 4), rows=2)),
        "the header states",
    ),
}


@pytest.mark.parametrize("case", list(MATERIALS))
def test_a_damaged_material_file_is_one_line(tmp_path: Path, run_gonio: Gonio, case: str) -> None:
    name, suffix, damage, words = MATERIALS[case]
    path = tmp_path / f"material{suffix}"
    damage(path)
    scene = tmp_path / "scene.yaml"
    spec = yaml.safe_load((CONFIGS / "scenes" / "matte.yaml").read_text())
    spec["material"] = {"name": name, "path": str(path)}
    scene.write_text(yaml.safe_dump(spec))
    plan = plan_file(tmp_path, target=8)
    result = bounded(lambda: run_gonio("simulate", str(plan), "--scene", str(scene), "-q"))
    assert isinstance(result, CliResult)
    one_line(result, path.name, words)


# -- sweep files and schedulers -----------------------------------------------------------

SWEEPS: dict[str, tuple[Callable[[Path], Path], str]] = {
    "an alias bomb": (
        lambda folder: _text(folder, LAUGHS + yaml.safe_dump(SMALL)),
        "values (aliases expanded)",
    ),
    "an unknown axis": (
        lambda folder: write_sweep(folder, axes={**SMALL["axes"], "colour": ["red"]}),
        "axes.colour",
    ),
    "a billion combinations": (
        lambda folder: write_sweep(
            folder,
            axes={
                **SMALL["axes"],
                "samples": list(range(10, 1010)),
                "exposure_s": [round(0.01 + k * 1e-4, 6) for k in range(1000)],
                "velocity_scale": [round(1.0 + k * 1e-3, 6) for k in range(1000)],
            },
        ),
        "4,000,000,000 combinations; expected at most 100,000",
    ),
}


def _text(folder: Path, text: str) -> Path:
    path = folder / "sweep.yaml"
    path.write_text(text)
    return path


@pytest.mark.timing
@pytest.mark.parametrize("case", list(SWEEPS))
def test_a_hostile_sweep_is_one_line_at_once(tmp_path: Path, run_gonio: Gonio, case: str) -> None:
    make, words = SWEEPS[case]
    sweep = make(tmp_path)
    start = time.monotonic()
    result = bounded(lambda: run_gonio("tradeoff", str(sweep), "-o", str(tmp_path / "out")))
    assert time.monotonic() - start < 10.0
    assert isinstance(result, CliResult)
    one_line(result, sweep.name, words)
    assert not (tmp_path / "out").exists()


@pytest.fixture(params=["silent", "garbage"])
def peer(request: pytest.FixtureRequest) -> Iterator[str]:
    """A TCP server that accepts and never answers, or answers random bytes."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(8)
    held: list[socket.socket] = []

    def serve() -> None:
        while True:
            try:
                conn, _ = server.accept()
            except OSError:
                return
            held.append(conn)
            if request.param == "garbage":
                conn.sendall(os.urandom(4096))

    threading.Thread(target=serve, daemon=True).start()
    yield f"tcp://127.0.0.1:{server.getsockname()[1]}"
    server.close()
    for conn in held:
        conn.close()


@pytest.mark.timing
def test_a_scheduler_that_does_not_answer_is_one_line_within_the_timeout(
    tmp_path: Path, run_gonio: Gonio, monkeypatch: pytest.MonkeyPatch, peer: str
) -> None:
    pytest.importorskip("distributed")
    monkeypatch.setattr(executors, "CONNECT_TIMEOUT_S", 1.0)
    sweep = write_sweep(tmp_path)
    start = time.monotonic()
    result = run_gonio("tradeoff", str(sweep), "-o", str(tmp_path / "out"), "--scheduler", peer)
    assert time.monotonic() - start < 15.0
    one_line(result, f"--scheduler {peer}: cannot reach the scheduler")


@pytest.mark.timing
def test_the_scheduler_timeout_is_a_parameter(peer: str) -> None:
    pytest.importorskip("distributed")
    start = time.monotonic()
    with pytest.raises(executors.ConfigError, match="cannot reach the scheduler"):
        executors.run_dask([], peer, lambda row: None, timeout_s=0.5)
    assert time.monotonic() - start < 5.0
