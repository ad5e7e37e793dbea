"""The rig file (YAML), validated: axes, kinematic chains, physical constraints, and
what the instrument is — the light's kind and switch, the detector's limits and
interface, the reference standard (`gonio.rig.instrument`) — real or simulated.

Angles in the file are degrees (fields say ``_deg``), lengths millimetres (``_mm``),
times seconds. Everything is converted to radians once, in `gonio.rig.model`.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

from pydantic import Field, field_validator, model_validator

from drivers.dynamixel import BAUD_RATES, AxisConfig
from drivers.dynamixel import MODEL_NAMES as MODELS
from gonio.config import Strict, excerpt, field_error
from gonio.config_schema import InSchema
from gonio.rig.instrument import LENGTH_RANGE_MM, DetectorSpec, LightSpec, ReferenceSpec

#: The largest magnitude of a vector's component: its square stays far from overflow.
COMPONENT_LIMIT = 1e100
Component = Annotated[float, Field(ge=-COMPONENT_LIMIT, le=COMPONENT_LIMIT)]
Vector = tuple[Component, Component, Component]
#: The largest joint angle in magnitude (°): the widest travel an X-series motor's
#: extended position mode covers (±256 turns) through a gear ratio of 0.1.
JOINT_LIMIT_DEG = 921_600.0
#: Gear ratios (motor turns per joint turn) a rig can have: from a 1:100 step-up to a
#: 10 000:1 reduction (a worm gear after a gearbox).
GEAR_RATIO_RANGE = (0.01, 10_000.0)
#: Joint speeds (°/s) and accelerations (°/s²) a trapezoidal move may use: the slowest
#: turns a degree in about a quarter of an hour (a move's time and its square stay finite),
#: the fastest is beyond any motor (an X-series at 1:100 step-up turns 1.4·10⁵ °/s).
VELOCITY_RANGE_DEG_S = (1e-3, 1e6)
ACCELERATION_RANGE_DEG_S2 = (1e-3, 1e8)
#: A vector's JSON Schema says what `AxisSpec` checks: not the zero vector.
NonZero = Annotated[Vector, InSchema(**{"not": {"const": [0, 0, 0]}})]


class AxisSpec(Strict):
    """One revolute axis: its rotation axis in the parent frame, range, motor and dynamics.

    The joint angle is the kinematic variable (0 = the chain's home pose); the motor
    drives it as joint = zero_offset + direction · motor angle / gear_ratio.
    """

    axis: NonZero = Field(
        description="The rotation axis in the parent frame [x, y, z] (normalized when read)."
    )
    min_deg: float = Field(
        ge=-JOINT_LIMIT_DEG,
        le=JOINT_LIMIT_DEG,
        description="The lowest joint angle (°; 0 = the home pose).",
    )
    max_deg: float = Field(
        ge=-JOINT_LIMIT_DEG,
        le=JOINT_LIMIT_DEG,
        description="The highest joint angle (°), above min_deg.",
    )
    motor_id: int = Field(ge=0, le=252, description="The Dynamixel ID of the axis's motor.")
    gear_ratio: float = Field(
        1.0,
        ge=GEAR_RATIO_RANGE[0],
        le=GEAR_RATIO_RANGE[1],
        description="Motor turns per joint turn.",
    )
    direction: Literal[1, -1] = Field(
        1, description="+1 or −1: which way the joint turns when the motor angle grows."
    )
    zero_offset_deg: float = Field(
        0.0,
        ge=-JOINT_LIMIT_DEG,
        le=JOINT_LIMIT_DEG,
        description="The joint angle at the motor's zero position (°).",
    )
    mode: Literal["position", "extended_position"] = Field(
        "position",
        description="The motor's operating mode: position (one turn, 0…4095 ticks) or "
        "extended_position (multi-turn).",
    )
    max_velocity_deg_s: float = Field(
        ge=VELOCITY_RANGE_DEG_S[0],
        le=VELOCITY_RANGE_DEG_S[1],
        description="The joint's top speed (°/s) of its trapezoidal moves.",
    )
    max_acceleration_deg_s2: float = Field(
        ge=ACCELERATION_RANGE_DEG_S2[0],
        le=ACCELERATION_RANGE_DEG_S2[1],
        description="The joint's acceleration and deceleration (°/s²).",
    )
    motor_model: (
        Annotated[str, InSchema(enum=list(MODELS.values()))]
        | Annotated[int, Field(ge=0, le=0xFFFF)]
        | None
    ) = Field(
        None,
        description="The motor the axis must find at motor_id (checked before the first "
        f"move): a model name ({', '.join(MODELS.values())}) or a model number; none: any.",
    )
    motor_firmware: int | None = Field(
        None,
        ge=0,
        le=255,
        description="The firmware version the motor must answer with; none: any.",
    )

    @field_validator("axis")
    @classmethod
    def _unit_axis(cls, v: Vector) -> Vector:
        norm = sum(c * c for c in v) ** 0.5
        if not norm > 0:
            raise ValueError("a rotation axis must not be the zero vector")
        return (v[0] / norm, v[1] / norm, v[2] / norm)

    @field_validator("motor_model", mode="before")
    @classmethod
    def _known_model(cls, v: object) -> object:
        known = isinstance(v, str) and v in MODELS.values()
        number = isinstance(v, int) and not isinstance(v, bool) and 0 <= v <= 0xFFFF
        if v is not None and not isinstance(v, bool) and not known and not number:
            raise ValueError(
                f"expected a model name ({', '.join(MODELS.values())}) or a model number 0…65535"
            )
        return v

    def motor_model_number(self) -> int | None:
        """`motor_model` as a model number (None: any model)."""
        if isinstance(self.motor_model, str):
            return next(n for n, name in MODELS.items() if name == self.motor_model)
        return self.motor_model

    def axis_config(self, name: str) -> AxisConfig:
        """This axis, named ``name``, as the driver's `AxisConfig` (degrees to radians);
        ValueError where the driver refuses it."""
        return AxisConfig(
            name=name,
            motor_id=self.motor_id,
            min_rad=math.radians(self.min_deg),
            max_rad=math.radians(self.max_deg),
            gear_ratio=self.gear_ratio,
            zero_offset_rad=math.radians(self.zero_offset_deg),
            direction=self.direction,
            mode=self.mode,
            profile_velocity_rad_s=math.radians(self.max_velocity_deg_s),
            profile_acceleration_rad_s2=math.radians(self.max_acceleration_deg_s2),
            model=self.motor_model_number(),
            firmware=self.motor_firmware,
        )

    @model_validator(mode="after")
    def _ordered_limits(self) -> AxisSpec:
        if not self.min_deg < self.max_deg:
            raise field_error(
                "max_deg", f"expected more than min_deg ({self.min_deg}), got {self.max_deg}"
            )
        return self


class KinematicChainSpec(Strict):
    """A chain of axes from the lab frame outward, and the unit vector that the last
    frame points along (for the light and the detector: toward the source / sensor)."""

    axes: list[str] = Field(
        min_length=1, description="The chain's axes (names of axes), from the lab frame outward."
    )
    pointing: Vector = Field(
        (0.0, 0.0, 1.0),
        description="The unit vector the last frame points along (both rig types: [0, 0, 1]).",
    )


JointDeg = Annotated[float, Field(ge=-JOINT_LIMIT_DEG, le=JOINT_LIMIT_DEG)]


class CollisionSpec(Strict):
    """A keep-out box in joint space: a collision when every listed axis is in its range."""

    name: str = Field(description="What collides, as messages name it.")
    ranges_deg: dict[str, tuple[JointDeg, JointDeg]] = Field(
        min_length=1, description="Per axis: [low, high] joint angles (°) of the box."
    )


class ConstraintSpec(Strict):
    """What the rig cannot measure: pairs beyond its polar angle, in the detector's shadow
    on the beam, with the lit spot off the sample or out of the detector's view, or at a
    pose in a keep-out box."""

    theta_max_deg: float = Field(
        80.0, gt=0, le=90, description="The largest polar angle of the light and the detector (°)."
    )
    min_separation_deg: float = Field(
        8.0,
        ge=0,
        lt=180,
        description="The smallest angle between ωi and ωo (°): the detector head shadows the "
        "beam closer than this.",
    )
    collisions: tuple[CollisionSpec, ...] = Field((), description="Keep-out boxes in joint space.")
    #: The collimated beam's diameter (none for a point source, which floods the sample).
    beam_diameter_mm: float | None = Field(
        None,
        ge=LENGTH_RANGE_MM[0],
        le=LENGTH_RANGE_MM[1],
        description="The collimated beam's diameter (mm); required for light.kind: collimated, "
        "none for a point source (it floods the sample).",
    )
    sample_diameter_mm: float = Field(
        ge=LENGTH_RANGE_MM[0], le=LENGTH_RANGE_MM[1], description="The sample's diameter (mm)."
    )
    #: The diameter of the spot the detector sees, perpendicular to ωo.
    detector_fov_mm: float = Field(
        ge=LENGTH_RANGE_MM[0],
        le=LENGTH_RANGE_MM[1],
        description="The diameter of the spot the detector sees, perpendicular to ωo (mm).",
    )


class LightChainSpec(KinematicChainSpec, LightSpec):
    """The light: its chain, its kind and its switch."""


class DetectorChainSpec(KinematicChainSpec, DetectorSpec):
    """The detector: its chain, its limits and its interface."""


class BusSpec(Strict):
    """The motors: ``simulated`` (virtual motors: the simulated backend) or
    ``dynamixel`` (X-series servos on ``port`` at ``baud``: the hardware backend;
    ``gonio acquire --rehearse`` puts the byte-level emulator in their place)."""

    kind: Literal["simulated", "dynamixel"] = Field(
        "simulated",
        description="simulated: virtual motors; dynamixel: X-series servos on port.",
    )
    port: str = Field("/dev/ttyUSB0", description="The motors' serial port (dynamixel).")
    baud: Annotated[int, InSchema(enum=list(BAUD_RATES.values()))] = Field(
        57_600, description="The motors' baud rate (dynamixel): one the X series knows."
    )
    retries: int = Field(
        3,
        ge=0,
        le=10,
        description="Extra attempts of a transaction whose status was lost or corrupt, "
        "before the run stops resumable (dynamixel; measured in docs/results/bus_retries.md).",
    )

    @field_validator("baud")
    @classmethod
    def _known_baud(cls, v: int) -> int:
        if v not in BAUD_RATES.values():
            raise ValueError(
                f"expected one of {', '.join(str(b) for b in BAUD_RATES.values())} (bit/s)"
            )
        return v


#: The highest supply voltage a health limit may name (V): twice the 24 V of the highest
#: rated Dynamixel; a motor reports at most 25.5 V.
MAX_VOLTAGE_V = 48.0


class HealthLimitsSpec(Strict):
    """The motors' safe operating range, checked during a run (`gonio acquire` pauses
    beyond it): the highest internal temperature (°C) and the input voltage range (V).
    The defaults are inside the X-series limits (72 °C shutdown, 9.5–16 V at 12 V). A
    recovering run (the plan's ``acquisition.on_fault.motor``) waits for a hot motor to
    cool below ``max_temperature_c`` and checks a rebooted motor's position to within
    ``position_tolerance_deg``."""

    max_temperature_c: float = Field(
        65.0, gt=0, le=100, description="The highest internal temperature of a motor (°C)."
    )
    min_voltage_v: float = Field(
        10.0,
        gt=0,
        le=MAX_VOLTAGE_V,
        description="The lowest input voltage (V), below max_voltage_v.",
    )
    max_voltage_v: float = Field(
        14.8, gt=0, le=MAX_VOLTAGE_V, description="The highest input voltage (V)."
    )
    position_tolerance_deg: float = Field(
        0.5,
        gt=0,
        le=360,
        description="How far a rebooted motor's joint may read from where it held before the "
        "reboot (°); beyond it a recovering run stops.",
    )

    @model_validator(mode="after")
    def _range(self) -> HealthLimitsSpec:
        if not self.min_voltage_v < self.max_voltage_v:
            raise field_error(
                "min_voltage_v",
                f"expected less than max_voltage_v ({self.max_voltage_v}), "
                f"got {self.min_voltage_v}",
            )
        return self


class RigSpec(Strict):
    """A whole rig: its type (which closed-form inverse kinematics applies), its axes and
    the chains of the light, the detector and the sample holder (sample → lab)."""

    name: str = Field(description="The rig's name, shown in summaries and stored in the run.")
    type: Literal["arch", "in_plane"] = Field(
        description="Which closed-form inverse kinematics applies: arch (the axes "
        "light_elevation, detector_azimuth, detector_elevation, sample_rotation) or in_plane "
        "(light_arm, detector_arm, sample_tilt, sample_rotation).",
    )
    axes: dict[str, AxisSpec] = Field(
        min_length=1, description="The revolute axes by name: the axes of the rig's type."
    )
    light: LightChainSpec = Field(description="The light: its chain, kind and switch.")
    detector: DetectorChainSpec = Field(
        description="The detector: its chain, limits and interface."
    )
    sample: KinematicChainSpec = Field(
        description="The sample holder's chain (sample frame → lab)."
    )
    constraints: ConstraintSpec = Field(description="What the rig cannot measure, and sizes.")
    reference: ReferenceSpec = Field(
        ReferenceSpec(), description="The Lambertian standard read for calibration."
    )
    settle_s: float = Field(0.2, ge=0, description="The wait after each move, before exposing (s).")
    bus: BusSpec = Field(BusSpec(), description="The motors.")
    health: HealthLimitsSpec = Field(
        HealthLimitsSpec(), description="The motors' safe operating range, checked during a run."
    )
    alignment: str | None = Field(
        None,
        min_length=1,
        description="The rig's measured misalignment: the path of an alignment file (with its "
        "fit record), relative to this file. Forward and inverse kinematics then "
        "work in the true geometry, and a run stores the alignment file's text. None: the "
        "rig is as this file says.",
    )

    @model_validator(mode="after")
    def _known_axes(self) -> RigSpec:
        for chain in ("light", "detector", "sample"):
            for i, name in enumerate(getattr(self, chain).axes):
                if name not in self.axes:
                    what = f"{excerpt(name)} is not one of the axes"
                    raise field_error(f"{chain}.axes.{i}", what)
        for b, box in enumerate(self.constraints.collisions):
            where = f"constraints.collisions.{b}.ranges_deg"
            for name, (lo, hi) in box.ranges_deg.items():
                if name not in self.axes:
                    raise field_error(
                        f"{where}.{name}", f"collision {box.name!r} names unknown axis {name!r}"
                    )
                if not lo < hi:
                    raise field_error(
                        f"{where}.{name}",
                        f"collision {box.name!r}: expected [low, high], got [{lo}, {hi}]",
                    )
        beam = self.constraints.beam_diameter_mm
        if self.light.kind == "collimated" and beam is None:
            raise field_error(
                "constraints.beam_diameter_mm",
                "Field required for a collimated light (light.kind: collimated)",
            )
        if self.light.kind == "point" and beam is not None:
            raise field_error(
                "constraints.beam_diameter_mm",
                "a point source floods the sample and has no beam diameter; expected it "
                "only with light.kind: collimated",
            )
        seen: dict[int, str] = {}
        for name, axis in self.axes.items():
            if axis.motor_id in seen:
                raise field_error(
                    f"axes.{name}.motor_id",
                    f"motor ID {axis.motor_id} is already used by {seen[axis.motor_id]}",
                )
            seen[axis.motor_id] = name
        expected = {"arch": ARCH_AXES, "in_plane": IN_PLANE_AXES}[self.type]
        if set(self.axes) != set(expected):
            raise field_error("axes", f"a {self.type!r} rig has the axes {', '.join(expected)}")
        return self


#: The axes each closed-form rig type expects (the chains say how they are connected).
ARCH_AXES = ("light_elevation", "detector_azimuth", "detector_elevation", "sample_rotation")
IN_PLANE_AXES = ("light_arm", "detector_arm", "sample_tilt", "sample_rotation")
