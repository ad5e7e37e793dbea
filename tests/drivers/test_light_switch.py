"""`SerialLightSwitch` against the simulated lamp on a pty: acknowledgements, refusals,
silence, retries, warm-up and configuration errors (the lifecycle rules are in the
contract suite)."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from drivers.errors import LightError
from drivers.light import SerialLightConfig
from drivers.light.serial_switch import SerialLightSwitch
from sim.clock import ManualClock
from sim.peers.serial_light import SerialLamp


@pytest.fixture
def lamp() -> Iterator[SerialLamp]:
    with SerialLamp() as device:
        yield device
        assert device.error is None


def test_commands_on_the_wire_and_warm_up_on_the_clock(lamp: SerialLamp) -> None:
    clock = ManualClock()
    with SerialLightSwitch(lamp.config(warmup_s=2.5), clock=clock) as light:
        assert not light.is_on  # asked on open: the lamp is off at power-up
        light.on()
        assert clock.now() == 2.5  # the lamp's warm-up, waited on the run's clock
        light.off()
        assert clock.now() == 2.5
    assert lamp.commands == ["STATE?", "ON", "OFF"]


def test_open_asks_the_state_and_without_a_query_assumes_nothing(lamp: SerialLamp) -> None:
    with SerialLightSwitch(lamp.config()) as light:
        light.on()
    with SerialLightSwitch(lamp.config()) as light:
        assert light.is_on  # the lamp said ON
    plain = lamp.config(query=None, on_reply=None, off_reply=None)
    with SerialLightSwitch(plain) as light:
        assert not light.is_on  # no way to know: off until switched


def test_a_device_that_never_answers_is_switched_once_the_command_is_sent(
    lamp: SerialLamp,
) -> None:
    config = lamp.config(ack=None, query=None, on_reply=None, off_reply=None)
    with SerialLightSwitch(config) as light:
        lamp.silent()  # whatever it would say, nothing is read
        light.on()
        assert light.is_on


def test_an_unclear_state_on_open_is_a_light_error_and_the_port_is_released(
    lamp: SerialLamp,
) -> None:
    light = SerialLightSwitch(lamp.config(on_reply="^LIT$", off_reply="^DARK$", timeout_s=0.05))
    with pytest.raises(LightError, match="did not say whether the light is on"):
        light.open()
    assert not light.is_open


def test_a_refusal_is_retried_then_raised_and_the_state_kept(lamp: SerialLamp) -> None:
    with SerialLightSwitch(lamp.config(retries=1)) as light:
        light.on()
        lamp.refuse(1)
        light.off()  # refused once, acknowledged on the retry
        assert not light.is_on and lamp.commands == ["STATE?", "ON", "OFF", "OFF"]
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
        ("query", "STATE?", "query, on_reply and off_reply go together"),
    ],
)
def test_bad_configuration_is_refused(field: str, value: object, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        SerialLightConfig(port="/dev/null", **{field: value})  # type: ignore[arg-type]
