"""The README's transcript of `make demo` is that target's real output: the commands of
the Makefile's demo target are run in-process, in a scratch folder, and every line of
the transcript is found in what they print (a line trimmed with "…" up to the "…")."""

from __future__ import annotations

import re
import shlex
from collections.abc import Callable
from pathlib import Path

import pytest

from tests.conftest import CliResult

ROOT = Path(__file__).resolve().parents[3]


def _demo_commands() -> list[list[str]]:
    """The `gonio …` commands of the Makefile's demo target, continuation lines joined."""
    text = (ROOT / "Makefile").read_text(encoding="utf-8").replace("\\\n", " ")
    recipe = re.search(r"^demo:.*\n((?:\t.*\n)+)", text, re.MULTILINE)
    assert recipe, "the Makefile has no demo target"
    commands = []
    for line in recipe.group(1).splitlines():
        words = shlex.split(line.strip().lstrip("@"))
        if words and words[0] == "$(BIN)/gonio":
            commands.append(words[1:])
    return commands


def _transcript() -> list[str]:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    block = re.search(r"`make demo` measures.*?```text\n(.*?)```", readme, re.DOTALL)
    assert block, "the README has no transcript of make demo"
    return [line for line in block.group(1).splitlines() if line.strip()]


def test_the_readme_transcript_is_what_make_demo_prints(
    run_gonio: Callable[..., CliResult], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    commands = _demo_commands()
    assert [c[0] for c in commands] == ["acquire", "info", "evaluate"]
    monkeypatch.chdir(tmp_path)
    (tmp_path / "runs").mkdir()
    printed = []
    for words in commands:
        # The shipped configs stay reachable from here; the run file is made here.
        args = [str(ROOT / w) if w.startswith("configs/") else w for w in words]
        result = run_gonio(*args)
        assert result.returncode == 0, result.stderr
        printed += (result.stdout + result.stderr).splitlines()
    missing = [
        line
        for line in _transcript()
        if not any(out.startswith(line.split("…")[0].rstrip()) for out in printed)
    ]
    assert missing == []
    # The first tutorial's step 2, as it is written, right after make demo: no clash
    tutorial = (ROOT / "docs" / "tutorials" / "first-measurement.md").read_text()
    step = re.search(r"^\$ gonio (acquire configs/plans/quickstart\.yaml .*)$", tutorial, re.M)
    assert step, "the first tutorial has no acquire step"
    words = [str(ROOT / w) if w.startswith("configs/") else w for w in step.group(1).split()]
    result = run_gonio(*words)
    assert result.returncode == 0, result.stderr
