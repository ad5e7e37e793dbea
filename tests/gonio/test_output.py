"""No command writes over one of its inputs: `gonio.output.refuse_inputs` on its own, and
every command with an output given its own input as that output (one line, exit 2, the
input unchanged). A figure cannot be one of them: its format check refuses a name that
does not end as an image does."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from gonio.config import ConfigError
from gonio.output import refuse_inputs
from tests.conftest import CliResult
from tests.support.acquire import RunFiles


def test_the_same_file_under_any_spelling_or_link_is_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    source = tmp_path / "run.sqlite"
    source.write_bytes(b"journal")
    link = tmp_path / "link.sqlite"
    link.symlink_to(source)
    monkeypatch.chdir(tmp_path)
    for out in (source, link, Path("run.sqlite"), tmp_path / "sub" / ".." / "run.sqlite"):
        with pytest.raises(ConfigError, match=r"^-o .*: is .*run\.sqlite, an input of this"):
            refuse_inputs(out, "-o", [source])
    refuse_inputs(tmp_path / "other.csv", "-o", [source, None])  # another file: fine
    refuse_inputs(tmp_path / "new.csv", "-o", [tmp_path / "missing.sqlite"])


def test_a_device_written_in_place_is_no_input_to_protect() -> None:
    refuse_inputs("/dev/null", "-o", ["/dev/null"])


@pytest.fixture
def small_run(tmp_path: Path, run_files: Callable[..., RunFiles]) -> tuple[RunFiles, Path]:
    files = run_files(5)
    path = tmp_path / "run.sqlite"
    assert files.start(path).report.outcome == "completed"
    return files, path


@pytest.mark.parametrize(
    "command",
    [
        ("export", "{run}", "--format", "csv", "-o", "{run}"),
        ("export", "{run}", "--format", "hdf5", "-o", "{run}"),
        ("fit", "{run}", "--model", "lambert", "-o", "{run}"),
        ("plan", "{plan}", "-o", "{plan}"),
        ("acquire", "{plan}", "--scene", "{scene}", "-o", "{scene}", "--overwrite"),
        ("simulate", "{plan}", "--scene", "{scene}", "-o", "{plan}", "--overwrite"),
    ],
    ids=["export csv", "export hdf5", "fit", "plan", "acquire", "simulate"],
)
def test_no_command_writes_over_its_input(
    run_gonio: Callable[..., CliResult], small_run: tuple[RunFiles, Path], command: tuple[str, ...]
) -> None:
    files, run = small_run
    names = {"run": str(run), "plan": str(files.plan), "scene": str(files.scene)}
    before = {p: p.read_bytes() for p in (run, files.plan, files.scene)}
    r = run_gonio(*(word.format(**names) for word in command))
    assert r.returncode == 2, (r.stdout, r.stderr)
    assert r.stderr.count("\n") == 1 and "an input of this command" in r.stderr, r.stderr
    assert {p: p.read_bytes() for p in before} == before
