"""The plan file's acquisition policies (its ``acquisition`` section), validated.

How `gonio acquire` runs a plan: when the reference standard is read, what a target
does after a transient fault or a motor's hardware error, what a saturated reading
does, and when the motors' health is checked (docs/explanations/acquisition.md).
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from gonio.config import Strict

#: The longest interval a policy gives in minutes (a week): a calibration or a health
#: check less often than that is none (``null``), and a pause longer than that is a run
#: left unattended.
MAX_MINUTES = 7 * 24 * 60.0
#: The longest wait for a hot motor to cool (a day): a Dynamixel's housing cools with a
#: time constant of minutes, so a motor still hot after a day is not cooling.
MAX_COOL_DOWN_MINUTES = 24 * 60.0
#: The most targets between two calibrations or health checks: more than a plan holds
#: (`gonio.planner.schema.MAX_TARGETS`, a million).
MAX_EVERY_SAMPLES = 1_000_000
#: The shortest and the longest health poll while paused (s): more often than ten times
#: a second only loads the bus (and a simulated clock would poll without end), less often
#: than hourly leaves a cooled motor waiting.
POLL_RANGE_S = (0.1, 3600.0)


class CalibrationSpec(Strict):
    """When the reference standard is read: always at the start and at the end of a
    run, and again after ``every_samples`` targets or ``every_minutes`` of run time
    (whichever comes first; none: never in between). ``dark``: a dark reading (light
    off) with each reference reading. ``averages``: exposures per calibration reading
    (at least 4: their spread estimates the noise model every sample's uncertainty comes
    from, with n − 1 degrees of freedom a reading, and Student's t needs more than 2 in
    all to give a finite σ, even from one calibration: `gonio.analysis.calibrated`)."""

    every_samples: int | None = Field(
        None,
        ge=1,
        le=MAX_EVERY_SAMPLES,
        description="Read the standard again after this many targets (none: never).",
    )
    every_minutes: float | None = Field(
        None,
        gt=0,
        le=MAX_MINUTES,
        description="Read the standard again after this much run time (min; none: never).",
    )
    dark: bool = Field(
        True, description="Take a dark reading (light off) with each reference reading."
    )
    averages: int = Field(
        16, ge=4, le=1000, description="Exposures per calibration reading (at least 4)."
    )


class MotorFaultSpec(Strict):
    """What a motor's hardware error (its Hardware Error Status: overload, overheating,
    input voltage, encoder) does: ``stop`` every axis and end the run resumable, or
    ``recover``: journal the motor's error flags, temperature and load, hold every axis,
    wait until it has cooled below the rig's ``health.max_temperature_c`` when the cause
    is heat (at most ``cool_down_minutes``), reboot it into its configuration, check its
    position against where it held (the rig's ``health.position_tolerance_deg``) and
    measure the target in flight again; at most ``max_recoveries`` times per motor per
    run, after which the run stops resumable. A motion timeout always stops."""

    action: Literal["stop", "recover"] = Field(
        "stop",
        description="stop: end the run resumable (reboot the motor by hand); recover: reboot "
        "it and go on (journaled step by step).",
    )
    max_recoveries: int = Field(
        3, ge=1, le=1000, description="recover: reboots per motor per run, then stop."
    )
    cool_down_minutes: float = Field(
        30.0,
        gt=0,
        le=MAX_COOL_DOWN_MINUTES,
        description="recover: the longest wait for a hot motor to cool below the rig's "
        "health.max_temperature_c (min); then stop.",
    )


class OnFaultSpec(Strict):
    """What a target does when a transient fault strikes (`CommError`, `DetectorError`):
    try again up to ``retries`` times, then ``skip`` it (the reason journaled) or
    ``abort`` the run (resumable). A calibration's reading is retried the same way and,
    after the last attempt, ends the run resumable. A motor's hardware error follows
    ``motor``; a motion timeout always stops every axis and ends the run resumable."""

    retries: int = Field(2, ge=0, le=100, description="Attempts after the first.")
    then: Literal["skip", "abort"] = Field(
        "skip",
        description="After the last attempt: skip the target (journaled) or abort the run "
        "(resumable).",
    )
    motor: MotorFaultSpec = Field(
        default_factory=MotorFaultSpec,
        description="What a motor's hardware error does: stop (default) or recover.",
    )


class SaturationSpec(Strict):
    """A saturated reading is measured again at half the exposure (never below the
    detector's shortest), up to ``attempts`` more times, when ``remeasure``; a reading
    still saturated is kept and flagged."""

    remeasure: bool = Field(
        True, description="Measure a saturated reading again at half the exposure."
    )
    attempts: int = Field(6, ge=1, le=60, description="Halvings at most, per reading.")


class HealthSpec(Strict):
    """Motor health (temperature, voltage: limits in the rig file's ``health``) checked
    every ``every_samples`` targets or ``every_minutes``; beyond a limit the run pauses
    with the axes holding, checks again every ``poll_s`` and resumes once the condition
    clears, or ends resumable after ``pause_timeout_minutes``."""

    every_samples: int | None = Field(
        100,
        ge=1,
        le=MAX_EVERY_SAMPLES,
        description="Check after this many targets (none: not by count).",
    )
    every_minutes: float | None = Field(
        5.0,
        gt=0,
        le=MAX_MINUTES,
        description="Check after this much run time (min; none: not by time).",
    )
    poll_s: float = Field(
        10.0,
        ge=POLL_RANGE_S[0],
        le=POLL_RANGE_S[1],
        description="While paused, check again this often (s).",
    )
    pause_timeout_minutes: float = Field(
        30.0,
        gt=0,
        le=MAX_MINUTES,
        description="End the run resumable after a pause this long (min).",
    )


class AcquisitionSpec(Strict):
    """How `gonio acquire` runs the plan (docs/explanations/acquisition.md)."""

    calibration: CalibrationSpec = Field(
        default_factory=CalibrationSpec, description="When the reference standard is read."
    )
    on_fault: OnFaultSpec = Field(
        default_factory=OnFaultSpec, description="What a target does after a transient fault."
    )
    saturation: SaturationSpec = Field(
        default_factory=SaturationSpec, description="What a saturated reading does."
    )
    health: HealthSpec = Field(
        default_factory=HealthSpec, description="When the motors' health is checked."
    )
