"""Planning shows its long stages on a terminal and nothing elsewhere."""

from __future__ import annotations

import io

from gonio import progress
from gonio.planner import build
from gonio.planner.schema import PlanSpec
from gonio.rig.model import Rig


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def small_plan(rig: Rig) -> None:
    spec = PlanSpec.model_validate(
        {"name": "progress", "sampling": {"strategy": "sobol", "target": 200}, "kicks": 20}
    )
    build(spec, rig)


def test_a_terminal_sees_every_long_stage(rigs: dict[str, Rig]) -> None:
    stream = Terminal()
    with progress.shown_on(stream, delay_s=0.0):
        small_plan(rigs["arch"])
    shown = stream.getvalue()
    for stage in (
        "placing the targets",
        "nearest-neighbour construction",
        "improving the order",
        "choosing the poses",
    ):
        assert f"planning: {stage}" in shown, stage


def test_nothing_is_shown_off_a_terminal_quiet_or_before_the_delay(
    rigs: dict[str, Rig],
) -> None:
    pipe = io.StringIO()
    with progress.shown_on(pipe, delay_s=0.0):
        small_plan(rigs["arch"])
    assert pipe.getvalue() == ""
    terminal = Terminal()
    with progress.shown_on(terminal, delay_s=0.0), progress.quiet():
        small_plan(rigs["arch"])
    assert terminal.getvalue() == ""
    with progress.shown_on(terminal, delay_s=60.0):
        small_plan(rigs["arch"])
    assert terminal.getvalue() == ""
