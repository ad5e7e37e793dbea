"""`SerialLightSwitch` against the simulated lamp on a pty: acknowledgements, refusals,
silence, retries, warm-up and configuration errors (the lifecycle rules are in the
contract suite)."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from drivers.base import LightError
from drivers.light import SerialLightConfig, SerialLightSwitch
from sim.clock import ManualClock
from sim.serial_light import SerialLamp


@pytest.fixture
def lamp() -> Iterator[SerialLamp]:
    with SerialLamp() as device:
        yield device
        assert device.error is None


def test_commands_on_the_wire_and_warm_up_on_the_clock(lamp: SerialLamp) -> None:
    clock = ManualClock()
    with SerialLightSwitch(lamp.config(warmup_s=2.5), clock=clock) as light:
        assert not light.is_on  # nothing is assumed about a device just opened
        light.on()
        assert clock.now() == 2.5  # the lamp's warm-up, waited on the run's clock
        light.off()
        assert clock.now() == 2.5
    assert lamp.commands == ["ON", "OFF"]


def test_a_refusal_is_retried_then_raised_and_the_state_kept(lamp: SerialLamp) -> None:
    with SerialLightSwitch(lamp.config(retries=1)) as light:
        light.on()
        lamp.refuse(1)
        light.off()  # refused once, acknowledged on the retry
        assert not light.is_on and lamp.commands == ["ON", "OFF", "OFF"]
        lamp.refuse(2)
        with pytest.raises(LightError, match=r"'ON' was not acknowledged after 2 attempt\(s\) "
                           r"\(the answer 'ERR lamp failure'\)"):  # fmt: skip
            light.on()
        assert not light.is_on and not lamp.is_on


def test_silence_is_a_light_error_after_the_timeout(lamp: SerialLamp) -> None:
    with SerialLightSwitch(lamp.config(timeout_s=0.05, retries=0)) as light:
        lamp.silent()
        with pytest.raises(LightError, match=r"after 1 attempt\(s\) \(no answer\)"):
            light.on()


def test_a_missing_port_is_one_line() -> None:
    with pytest.raises(LightError, match="light switch /dev/no-such-lamp: cannot open the port"):
        SerialLightSwitch(SerialLightConfig(port="/dev/no-such-lamp")).open()


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("ack", "(", "ack: not a regular expression"),
        ("on", " ", "on and off must be non-empty"),
        ("line_ending", ";", "line_ending must be"),
        ("timeout_s", 0.0, "timeout_s must be > 0"),
        ("retries", -1, "retries must be ≥ 0"),
    ],
)
def test_bad_configuration_is_refused(field: str, value: object, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        SerialLightConfig(port="/dev/null", **{field: value})  # type: ignore[arg-type]
