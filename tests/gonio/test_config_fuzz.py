"""Fuzzed configuration files through the real loaders and through `gonio.cli.main`:
every shipped plan, rig and scene mutated (values swapped for other types, ±0, ±inf,
NaN, 1e308, huge integers, yes/no; keys dropped and duplicated; alias bombs; deep
nesting; bytes that are not UTF-8), and documents generated from nothing. Whatever the
file, a loader either accepts it or raises `ConfigError` with one short line, within a
bounded time and memory; the CLI exits 0 or 2, a refusal in at most 3 lines, never a
traceback."""

from __future__ import annotations

import copy
import functools
import math
import os
import resource
import shutil
import signal
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from types import FrameType
from typing import Any

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gonio.config import SHOWN_PROBLEMS, ConfigError
from gonio.planner.files import load_plan_source
from gonio.rig.model import Rig
from gonio.scene import load_scene
from gonio.tradeoff.grid import load_sweep
from tests.conftest import CONFIGS, CliResult

#: CPU seconds one case may take (loading a config takes milliseconds). CPU time, not the
#: wall clock: a loaded machine slows a case down without making it do more work.
CASE_SECONDS = 10
#: Growth of the process's peak memory one case may cause, in KiB.
CASE_KIB = 300 * 1024


def examples(default: int) -> int:
    """Examples per property: lean in the suite, ``FUZZ_EXAMPLES=N`` for a longer search."""
    return int(os.environ.get("FUZZ_EXAMPLES", default))


LOADERS: dict[str, Callable[[Path], object]] = {
    "plans": load_plan_source,
    "rigs": Rig.from_yaml,
    "scenes": load_scene,
    "sweeps": load_sweep,
}
SHIPPED = sorted(p.relative_to(CONFIGS) for p in CONFIGS.glob("*/*.yaml"))

WEIRD = st.sampled_from(
    [
        0.0,
        -0.0,
        math.inf,
        -math.inf,
        math.nan,
        1e308,
        -1e308,
        5e-324,
        2**64,
        -(2**63) - 1,
        10**30,
        True,
        False,
        None,
        "",
        "x" * 2000,
        "../../../etc/passwd",
        [],
        {},
        [1, 2, 3],
        {"kind": "nope"},
        [math.nan] * 3,
    ]
)
#: Documents from nothing: nested mappings and lists of scalars.
DOCUMENTS = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=20),
    lambda inner: (
        st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner, max_size=4)
    ),
    max_leaves=20,
)


@pytest.fixture(scope="module")
def configs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A copy of configs/ to write mutants next to the files they name (../rigs/…)."""
    root = tmp_path_factory.mktemp("fuzz") / "configs"
    shutil.copytree(CONFIGS, root)
    return root


def paths(data: Any, prefix: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
    """Every path to a value in nested mappings and lists."""
    if isinstance(data, dict):
        for key, value in data.items():
            yield (*prefix, key)
            yield from paths(value, (*prefix, key))
    elif isinstance(data, list):
        for i, value in enumerate(data):
            yield (*prefix, i)
            yield from paths(value, (*prefix, i))


def parent_of(data: Any, path: tuple[Any, ...]) -> Any:
    for key in path[:-1]:
        data = data[key]
    return data


@functools.cache
def parsed(shipped: Path) -> Any:
    """A shipped file's YAML, parsed once (`mutants` mutates a deep copy)."""
    return yaml.safe_load((CONFIGS / shipped).read_text())


@st.composite
def mutants(draw: st.DrawFn, shipped: Path, *, text_level: bool = True) -> bytes:
    """The shipped file's text, mutated once or twice."""
    data = copy.deepcopy(parsed(shipped))
    for _ in range(draw(st.integers(1, 2))):
        where = list(paths(data))
        ops = ["replace", "drop"] + (["document"] if text_level else [])
        op = draw(st.sampled_from(ops))
        if op == "document":
            data = draw(DOCUMENTS)
            break
        if not where:
            break
        path = draw(st.sampled_from(where))
        parent = parent_of(data, path)
        if op == "replace":
            parent[path[-1]] = copy.deepcopy(draw(WEIRD))
        elif isinstance(parent, dict):
            del parent[path[-1]]
        else:
            parent.pop(path[-1])
    text = yaml.safe_dump(data, sort_keys=False, allow_unicode=True)
    if not text_level:
        return text.encode()
    hostile = draw(st.sampled_from(["none", "duplicate", "laughs", "deep", "bytes", "alias"]))
    if hostile == "duplicate" and isinstance(data, dict) and data:
        first = text.splitlines()[0]
        text = f"{first}\n{text}"
    elif hostile == "laughs":
        levels = draw(st.integers(3, 9))
        lines = ['a0: &a0 "lol"'] + [
            f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 10)}]" for i in range(1, levels + 1)
        ]
        text = "\n".join(lines) + "\n" + (text if isinstance(data, dict) else "")
    elif hostile == "deep":
        depth = draw(st.sampled_from([50, 70, 1000, 100_000]))
        text += "deep: " + "[" * depth + "]" * depth + "\n"
    elif hostile == "bytes":
        raw = bytearray(text.encode())
        raw.insert(draw(st.integers(0, len(raw))), draw(st.sampled_from([0xFF, 0xC3, 0x80, 0x00])))
        return bytes(raw)
    elif hostile == "alias":
        text = "x: &x [1, *x]\n" + text
    return text.encode()


class Timeout(Exception):
    pass


def bounded(run: Callable[[], object]) -> object:
    """``run()`` within `CASE_SECONDS` of CPU time and `CASE_KIB` more peak memory."""

    def alarm(signum: int, frame: FrameType | None) -> None:
        raise Timeout(f"a case took more than {CASE_SECONDS} s of CPU time")

    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    previous = signal.signal(signal.SIGPROF, alarm)
    signal.setitimer(signal.ITIMER_PROF, CASE_SECONDS)
    try:
        return run()
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0)
        signal.signal(signal.SIGPROF, previous)
        grown = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before
        assert grown < CASE_KIB, f"a case grew the peak memory by {grown} KiB"


def check_loader(configs: Path, shipped: Path, raw: bytes) -> None:
    path = configs / shipped.parent / f"fuzzed-{shipped.name}"
    path.write_bytes(raw)
    try:
        bounded(lambda: LOADERS[shipped.parent.name](path))
    except ConfigError as exc:
        message = str(exc)
        lines = message.splitlines()  # one problem a line, the first few, each naming a file
        assert 1 <= len(lines) <= SHOWN_PROBLEMS + 1, message[:2000]
        for line in lines:  # this one, or one it names (a sweep's plan, a plan's rig)
            assert line.startswith(("/", str(path.parent.parent))) and len(line) < 600, message


@pytest.mark.parametrize("shipped", SHIPPED, ids=str)
@settings(max_examples=examples(25), suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_mutated_configs_load_or_are_refused_in_one_line(
    configs: Path, shipped: Path, data: st.DataObject
) -> None:
    check_loader(configs, shipped, data.draw(mutants(shipped)))


@pytest.mark.parametrize("kind", sorted(LOADERS))
@settings(max_examples=examples(25), suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(document=DOCUMENTS)
def test_generated_documents_load_or_are_refused_in_one_line(
    configs: Path, kind: str, document: Any
) -> None:
    raw = yaml.safe_dump(document).encode()
    check_loader(configs, Path(kind) / "generated.yaml", raw)


QUICK = Path("plans") / "quick.yaml"


@settings(max_examples=examples(15), suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(raw=mutants(QUICK))
def test_gonio_plan_exits_0_or_2_in_a_line_per_problem(
    configs: Path, run_gonio: Callable[..., CliResult], raw: bytes
) -> None:
    path = configs / "plans" / "fuzzed-cli.yaml"
    path.write_bytes(raw)
    result = bounded(lambda: run_gonio("plan", str(path)))
    assert isinstance(result, CliResult)
    assert result.returncode in (0, 2), result.stderr[-2000:]
    assert "Traceback" not in result.stderr
    if result.returncode == 2:  # the first few problems, a line each (and how many more)
        assert len(result.stderr.strip().splitlines()) <= SHOWN_PROBLEMS + 3, result.stderr[:2000]


def test_the_fuzzer_reaches_each_hostile_kind(configs: Path) -> None:
    """Pinned cases of the classes above, each refused (not only survived)."""
    text = (CONFIGS / QUICK).read_text()
    cases = {
        "laughs": "a0: &a0 [1]\n"
        + "".join(f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 10)}]\n" for i in range(1, 9)),
        "deep": text + "deep: " + "[" * 100_000 + "]" * 100_000 + "\n",
        "duplicate": "name: twice\n" + text,
        "recursive": "x: &x [1, *x]\n" + text,
    }
    for _name, case in cases.items():
        with pytest.raises(ConfigError):
            check_loader_strict(configs, case.encode())
    with pytest.raises(ConfigError):
        check_loader_strict(configs, text.encode().replace(b"quick", b"qu\xffick"))


def check_loader_strict(configs: Path, raw: bytes) -> None:
    path = configs / "plans" / "pinned.yaml"
    path.write_bytes(raw)
    bounded(lambda: load_plan_source(path))


if sys.platform != "linux":  # pragma: no cover - ru_maxrss is in bytes on macOS
    CASE_KIB *= 1024


def test_the_case_bound_counts_cpu_time_not_the_wall_clock(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A case that waits costs no CPU and passes; one that computes past the bound fails."""
    monkeypatch.setattr(sys.modules[__name__], "CASE_SECONDS", 0.2)
    bounded(lambda: time.sleep(0.4))
    with pytest.raises(Timeout, match="CPU time"):
        bounded(lambda: sum(i * i for i in range(10**9)))
