"""Injected faults: the ``faults:`` section of a scene, the rules the simulated devices'
injector (`sim.virtual.faults`) consults, so every fault path of an engine can be exercised
in milliseconds.

A rule names a fault ``kind`` and when it fires — at chosen sample indices (``at``), or
at random with a probability per sample (``rate``, drawn from the run's counter-based
streams, so a resumed run sees exactly the faults an uninterrupted one does):

- ``motor_fault``: a motor reports a hardware error half-way through the move into the
  sample: that axis stops where it is and keeps reporting ``flags`` (its latched
  Hardware Error Status) until the bus is rebooted; `MotorFault` is raised by
  ``wait_settled`` after every axis was told to hold. With the ``overheating`` flag the
  axis also shows ``temperature_c`` for ``for_s`` seconds (a reboot before it cooled
  latches the error again); ``shift_deg`` makes its encoder reading jump when its motor
  is rebooted (what the recovery's position check must catch);
- ``comm_error``: a status poll fails half-way through the move: every axis is held
  and ``wait_settled`` raises `CommError`; ``packet`` says how (``lost``: no status
  packet came; ``corrupt``: one came with a wrong CRC);
- ``motion_timeout``: an axis is blocked: after the caller's timeout every axis is held
  and ``wait_settled`` raises `MotionTimeout`;
- ``detector_error``: ``measure`` raises `DetectorError` (nothing is exposed);
- ``saturated``: ``measure`` returns a reading at the sensor's full scale, flagged
  saturated;
- ``stream_gap``: a stream started for the sample loses `STREAM_GAP` consecutive
  windows from its `STREAM_GAP_FROM`-th on (a host that stalled: their lines never
  arrive), nothing else changes;
- ``overheat``: from the move into the sample on, ``axis`` reports ``temperature_c``
  in its health for ``for_s`` seconds of the run's clock, then cools back (a health
  check sees it; nothing else changes);
- ``supply_sag``: from the move into the sample on, every axis (they share the supply)
  reports ``voltage_v`` in its health for ``for_s`` seconds of the run's clock, then
  the supply recovers.

A rule fires on the first ``burst`` attempts at a sample (default 1: the first move into
it, or its first measurement): a sample retried past the burst succeeds, as after a
transient fault on hardware; a burst longer than the plan's retries skips the sample.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import Field, field_validator, model_validator

from gonio.config import Strict, field_error
from gonio.config_schema import InSchema
from gonio.rig import JOINT_LIMIT_DEG

FaultKind = Literal[
    "motor_fault",
    "comm_error",
    "motion_timeout",
    "detector_error",
    "saturated",
    "stream_gap",
    "overheat",
    "supply_sag",
]
#: The windows a ``stream_gap`` loses, and the first of them (from the stream's start).
STREAM_GAP = 40
STREAM_GAP_FROM = 100
#: The kinds the motor bus raises or shows; the others belong to the detector.
MOTOR_KINDS = frozenset({"motor_fault", "comm_error", "motion_timeout", "overheat", "supply_sag"})
#: Hardware Error Status flags a motor_fault may name (`drivers.dynamixel.control_table`).
MOTOR_FLAGS = frozenset(
    {"input_voltage", "overheating", "motor_encoder", "electrical_shock", "overload"}
)


class FaultRule(Strict):
    """One injected fault (see the module docstring)."""

    kind: FaultKind = Field(description="What goes wrong (see docs/explanations/simulator.md).")
    at: tuple[Annotated[int, InSchema(minimum=0)], ...] | None = Field(
        None, description="The sample indices it strikes at (one or a list; or rate)."
    )
    rate: float | None = Field(
        None, ge=0, le=1, description="The probability it strikes each sample (or at)."
    )
    axis: str | None = Field(
        None,
        description="motor_fault, overheat: the axis (default: the first); the rig's axis names.",
    )
    flags: tuple[Annotated[str, InSchema(enum=sorted(MOTOR_FLAGS))], ...] = Field(
        ("overload",),
        description="motor_fault: its Hardware Error Status flags.",
        json_schema_extra={"minItems": 1},
    )
    temperature_c: float = Field(
        80.0,
        gt=-50,
        lt=200,
        description="overheat, and a motor_fault with the overheating flag: the temperature "
        "the axis shows (°C).",
    )
    for_s: float = Field(
        60.0,
        gt=0,
        description="overheat, supply_sag, and a motor_fault with the overheating flag: how "
        "long the axis stays hot or the supply low, in seconds of the run's clock (s).",
    )
    shift_deg: float = Field(
        0.0,
        ge=-JOINT_LIMIT_DEG,
        le=JOINT_LIMIT_DEG,
        description="motor_fault: how far the axis's encoder reading jumps when its motor is "
        "rebooted (°; a multi-turn motor that lost its turn count), 0: not at all.",
    )
    voltage_v: float = Field(
        9.0, ge=0, lt=100, description="supply_sag: the supply voltage every axis shows (V)."
    )
    packet: Literal["lost", "corrupt"] = Field(
        "lost",
        description="comm_error: the status packet is lost, or arrives with a wrong CRC.",
    )
    burst: int = Field(
        1,
        ge=1,
        le=1000,
        description="The attempts at its sample it strikes in a row (a burst longer than "
        "the plan's retries skips the sample).",
    )

    @field_validator(
        "at",
        mode="before",
        json_schema_input_type=Annotated[int, InSchema(minimum=0)]
        | list[Annotated[int, InSchema(minimum=0)]]
        | None,
    )
    @classmethod
    def _one_index(cls, v: Any) -> Any:
        return (v,) if isinstance(v, int) and not isinstance(v, bool) else v

    @model_validator(mode="after")
    def _when(self) -> FaultRule:
        if (self.at is None) == (self.rate is None):
            raise field_error("at", "expected exactly one of at (sample indices) or rate")
        if self.at is not None and any(i < 0 for i in self.at):
            raise field_error("at", f"expected sample indices ≥ 0, got {list(self.at)}")
        bad = [f for f in self.flags if f not in MOTOR_FLAGS]
        if bad or not self.flags:
            raise field_error(
                "flags", f"expected some of {', '.join(sorted(MOTOR_FLAGS))}, got {bad or '[]'}"
            )
        if self.kind != "motor_fault" and self.shift_deg:
            raise field_error("shift_deg", f"only a motor_fault shifts, not a {self.kind}")
        if self.kind not in ("motor_fault", "overheat") and self.axis is not None:
            raise field_error(
                "axis", f"only a motor_fault or an overheat names an axis, not a {self.kind}"
            )
        return self
