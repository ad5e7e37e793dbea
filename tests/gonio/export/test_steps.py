"""An export names each long step on a terminal as it runs (and nothing off a terminal or
when quiet); the reconstruction evaluated block by block is the one evaluated at once."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest

from gonio import progress
from gonio.analysis.measured import Measured
from gonio.export import export, steps
from gonio.export.merl import representative_pairs
from gonio.reconstruct.methods import reconstruction
from gonio.reconstruct.result import values_and_support


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_a_terminal_sees_every_long_step_of_a_merl_export(run_file: Path, tmp_path: Path) -> None:
    stream = Terminal()
    with progress.shown_on(stream, delay_s=0.0):
        export(run_file, "merl", tmp_path / "out.binary")
    shown = stream.getvalue()
    for step in (
        "export: reading and calibrating the run",
        "export: reconstructing (linear) from",
        "export: filling the MERL table",
        "export: writing 35 MB",
    ):
        assert step in shown, step
    assert "pair" in shown  # the fill's bar counts pairs


def test_nothing_is_shown_off_a_terminal_or_when_quiet(run_file: Path, tmp_path: Path) -> None:
    pipe = io.StringIO()
    with progress.shown_on(pipe, delay_s=0.0):
        export(run_file, "csv", tmp_path / "out.csv")
    assert pipe.getvalue() == ""
    terminal = Terminal()
    with progress.shown_on(terminal, delay_s=0.0), progress.quiet():
        export(run_file, "csv", tmp_path / "out.csv")
    assert terminal.getvalue() == ""


def test_the_blocks_evaluate_what_one_evaluation_gives(
    run_file: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    surface = reconstruction(Measured.from_run(run_file), "linear", None)
    wi, wo, ok = representative_pairs()
    wi, wo = wi[ok][::50][: 7 * 3000], wo[ok][::50][: 7 * 3000]
    expected, supported = values_and_support(surface, wi, wo)
    monkeypatch.setattr(steps, "BLOCK", 997)
    got, got_supported = steps.evaluated(
        surface, wi.reshape(-1, 7, 3), wo.reshape(-1, 7, 3), "evaluating"
    )
    assert got.shape == (len(wi) // 7, 7)
    np.testing.assert_array_equal(got.ravel(), expected)
    assert supported is not None and got_supported is not None
    np.testing.assert_array_equal(got_supported.ravel(), supported)
