"""Hostile YAML: aliases expanded beyond bounds ("billion laughs"), deep nesting, huge
files, self-referencing aliases, duplicate keys under aliases, and huge values in
messages are each refused with one short line, quickly, through `gonio.config`."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

import pytest
import yaml

from gonio.config import ConfigError, read_yaml
from gonio.config import yaml_files as config
from gonio.planner.files import load_plan_source
from tests.conftest import CONFIGS, CliResult

Gonio = Callable[..., CliResult]
ARCH = CONFIGS / "rigs" / "arch.yaml"


def laughs(levels: int, width: int = 10) -> str:
    """A "billion laughs" document: ``width ** levels`` values from a few hundred bytes."""
    lines = ['a0: &a0 "lol"']
    for i in range(1, levels + 1):
        refs = ", ".join([f"*a{i - 1}"] * width)
        lines.append(f"a{i}: &a{i} [{refs}]")
    return "\n".join(lines) + "\n"


def refusal(tmp_path: Path, text: str | bytes) -> str:
    path = tmp_path / "hostile.yaml"
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    with pytest.raises(ConfigError) as caught:
        read_yaml(path)
    message = str(caught.value)
    assert "\n" not in message and len(message) < 300, message
    assert message.startswith(str(path))
    return message


@pytest.mark.timing
def test_billion_laughs_is_refused_quickly(tmp_path: Path, run_gonio: Gonio) -> None:
    plan = tmp_path / "plan.yaml"
    plan.write_text(f"rig: {ARCH}\n" + laughs(9))
    # CPU time, the work's own clock: a loaded host stretches the wall time, not this
    start = time.process_time()
    result = run_gonio("plan", str(plan))
    elapsed = time.process_time() - start
    assert result.returncode == 2
    assert len(result.stderr.strip().splitlines()) == 1, result.stderr[:500]
    assert "values (aliases expanded)" in result.stderr
    assert elapsed < 2.0


@pytest.mark.timing
def test_duplicate_key_under_many_aliases_in_linear_time(tmp_path: Path) -> None:
    # Within the expansion bound, yet 10 ** 4 paths to the innermost mapping: each
    # node is checked once.
    text = "b: {x: 1, x: 2}\n" + laughs(4).replace('"lol"', "{x: 1, y: 2}")
    start = time.process_time()
    message = refusal(tmp_path, text)
    assert "x: this key is given twice" in message
    assert time.process_time() - start < 1.0


def test_deep_nesting_is_one_line(tmp_path: Path) -> None:
    message = refusal(tmp_path, "a: " + "[" * 100_000 + "]" * 100_000 + "\n")
    assert "nested more than" in message
    message = refusal(tmp_path, "a: " + "{b: " * 5000 + "1" + "}" * 5000 + "\n")
    assert "nested more than" in message


@pytest.mark.timing
def test_deep_nesting_is_refused_in_linear_time(tmp_path: Path) -> None:
    # PyYAML's pure-Python scanner looks ahead over every open bracket at each one
    # (0.2 s of CPU for 1000 on a line); libyaml's own bound refuses it in a millisecond
    start = time.process_time()
    for depth in range(1000, 1020):
        message = refusal(tmp_path, "a: 1\nb: " + "[" * depth + "]" * depth + "\n")
        expected = "nested more than 64 levels deep; expected a flatter document"
        assert message == f"{tmp_path / 'hostile.yaml'}:2: {expected}"
    assert time.process_time() - start < 1.0


def test_nesting_through_aliases_counts(tmp_path: Path) -> None:
    lines = ["a0: &a0 [1]"] + [f"a{i}: &a{i} [[[[[[[[[[*a{i - 1}]]]]]]]]]]" for i in range(1, 8)]
    assert "nested more than" in refusal(tmp_path, "\n".join(lines) + "\n")


def test_too_many_aliases(tmp_path: Path) -> None:
    text = "a: &a 1\nb: [" + ", ".join(["*a"] * (config.MAX_ALIASES + 1)) + "]\n"
    assert "aliases" in refusal(tmp_path, text)


def test_alias_inside_the_value_it_names(tmp_path: Path) -> None:
    assert "inside the value it names" in refusal(tmp_path, "a: &a [1, *a]\n")
    assert "inside the value it names" in refusal(tmp_path, "a: &a {b: *a}\n")


def test_oversized_file(tmp_path: Path) -> None:
    text = "a: '" + "x" * (config.MAX_BYTES + 1) + "'\n"
    assert "bytes; expected at most" in refusal(tmp_path, text)


def test_not_utf8(tmp_path: Path) -> None:
    assert "cannot read" in refusal(tmp_path, b"a: \xff\xfe\n")


def test_a_huge_value_is_shown_as_a_short_excerpt(tmp_path: Path) -> None:
    plan = tmp_path / "plan.yaml"
    plan.write_text(f"rig: {ARCH}\nname: [" + ", ".join(["'lol'"] * 20_000) + "]\n")
    with pytest.raises(ConfigError) as caught:
        load_plan_source(plan)
    assert len(str(caught.value)) < 300


def test_aliases_within_bounds_still_load(tmp_path: Path) -> None:
    path = tmp_path / "ok.yaml"
    path.write_text(laughs(3) + "b: *a3\n")
    data, _ = read_yaml(path)
    assert len(data["b"]) == 10 and data["b"][0][0][0] == "lol"


BROKEN = [
    "a: [1, 2\n",
    "a: 1\n b: 2\n",
    "a: b: c\n",
    "a: *undefined\n",
    "a: 1\n---\nb: 2\n",
    "a: !!python/object:os.system 1\n",
    "a:\n  - 1\n  b: 2\n",
    "\tx: 1\n",
]


@pytest.mark.parametrize("text", BROKEN)
def test_c_and_python_loaders_say_the_same(tmp_path: Path, text: str) -> None:
    """The C loader (when installed) gives the line and problem the pure-Python one does."""
    path = tmp_path / "broken.yaml"
    path.write_text(text)
    messages = []
    for loader in (yaml.SafeLoader, config.Loader):
        with pytest.MonkeyPatch.context() as patch:
            patch.setattr(config, "Loader", loader)
            with pytest.raises(ConfigError) as caught:
                read_yaml(path)
            messages.append(str(caught.value))
    assert messages[0] == messages[1]


def test_same_data_and_lines_from_both_loaders() -> None:
    for path in sorted(CONFIGS.glob("*/*.yaml")):
        with pytest.MonkeyPatch.context() as patch:
            patch.setattr(config, "Loader", yaml.SafeLoader)
            slow, slow_node = read_yaml(path)
        fast, fast_node = read_yaml(path)
        assert fast == slow
        assert yaml.serialize(fast_node) == yaml.serialize(slow_node)


def test_a_long_unknown_key_is_cut(tmp_path: Path) -> None:
    plan = tmp_path / "plan.yaml"
    text = (CONFIGS / "plans" / "quick.yaml").read_text().replace("../rigs/arch.yaml", str(ARCH))
    plan.write_text(f"{text}? {'k' * 100_000}\n: 1\n")
    with pytest.raises(ConfigError) as caught:
        load_plan_source(plan)
    assert len(str(caught.value)) < 300 and "kkk…: unknown field" in str(caught.value)
