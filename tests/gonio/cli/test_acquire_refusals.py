"""A refused ``gonio acquire`` or ``gonio simulate`` leaves the folder exactly as it was
and prints nothing as started: no control token beside the run, no "watch and control"
line, no run file, whatever it refused (a resume of a missing or non-run file, of a run
whose scene changed; a bad plan or scene; an output in a missing folder or one that
exists)."""

from __future__ import annotations

import shutil
import sqlite3
from collections.abc import Callable
from pathlib import Path

import pytest

from tests.conftest import CONFIGS, CliResult
from tests.support.folders import listing
from tests.support.runs import plan_spec, scene_spec, simulated_run

Gonio = Callable[..., CliResult]
PLAN = str(CONFIGS / "plans" / "quickstart.yaml")
SCENE = str(CONFIGS / "scenes" / "glossy_metal.yaml")

#: Each refusal: the command's arguments ({d}: the folder) and a word of its one line.
REFUSALS: dict[str, tuple[list[str], str]] = {
    "resume-missing": (["acquire", "--resume", "{d}/missing.sqlite"], "no such run file"),
    "resume-text": (["acquire", "--resume", "{d}/notes.sqlite"], "not a usable run file"),
    "resume-other-db": (["acquire", "--resume", "{d}/other.sqlite"], "not a gonio run file"),
    "resume-changed-scene": (
        ["acquire", "--resume", "{d}/run.sqlite", "--scene", "{d}/scene.yaml"],
        "the scene file changed",
    ),
    "acquire-bad-plan": (["acquire", "{d}/notes.sqlite", "-o", "{d}/new.sqlite"], "notes.sqlite"),
    "acquire-bad-scene": (
        ["acquire", PLAN, "--scene", "{d}/scene.yaml", "-o", "{d}/new.sqlite"],
        "scene.yaml",
    ),
    "acquire-missing-folder": (
        ["acquire", PLAN, "--scene", SCENE, "-o", "{d}/nowhere/new.sqlite"],
        "does not exist",
    ),
    "acquire-exists": (
        ["acquire", PLAN, "--scene", SCENE, "-o", "{d}/run.sqlite"],
        "already exists",
    ),
    "simulate-bad-scene": (
        ["simulate", PLAN, "--scene", "{d}/scene.yaml", "-o", "{d}/new.sqlite"],
        "scene.yaml",
    ),
    "simulate-exists": (
        ["simulate", PLAN, "--scene", SCENE, "-o", "{d}/run.sqlite"],
        "already exists",
    ),
}


@pytest.fixture(scope="module")
def made(runs_dir: Path) -> Path:
    """A finished run (the reconstruction tests' run: one acquisition per worker)."""
    return simulated_run(runs_dir, plan_spec(300), scene_spec("matte", noise=False))


@pytest.mark.parametrize("case", list(REFUSALS))
def test_a_refusal_leaves_the_folder_as_it_was(
    made: Path, tmp_path: Path, run_gonio: Gonio, case: str
) -> None:
    shutil.copy(made, tmp_path / "run.sqlite")
    (tmp_path / "notes.sqlite").write_text("notes, not a run\n")
    (tmp_path / "scene.yaml").write_text("material: nothing\n")
    with sqlite3.connect(tmp_path / "other.sqlite") as conn:
        conn.execute("PRAGMA journal_mode=WAL")
        conn.execute("CREATE TABLE t (x)")
    conn.close()
    args, word = REFUSALS[case]
    before = listing(tmp_path)
    result = run_gonio(*(a.format(d=tmp_path) for a in args))
    assert result.returncode == 2, result.stderr[-2000:]
    lines = result.stderr.strip().splitlines()  # a line per problem (a bad scene has four)
    assert 1 <= len(lines) <= 4 and all(word in line for line in lines), result.stderr[-2000:]
    assert "watch and control" not in result.stdout
    assert listing(tmp_path) == before
