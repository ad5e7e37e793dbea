"""The `drivers.base.LightSource` contract on every light backend."""

from __future__ import annotations

import pytest

from drivers.errors import DeviceClosed
from tests.drivers.contract.conftest import LightHarness


def test_switching_changes_the_device_and_is_on_follows(lights: LightHarness) -> None:
    with lights.make() as light:
        light.on()
        assert light.is_on and lights.device_on()
        light.off()
        assert not light.is_on and not lights.device_on()
        light.on()
        assert light.is_on and lights.device_on()


def test_lifecycle_close_is_idempotent_and_a_closed_source_switches_nothing(
    lights: LightHarness,
) -> None:
    light = lights.make()
    light.close()
    with pytest.raises(DeviceClosed):
        light.off()
    with light:
        light.open()
        assert light.is_open
        light.off()
    assert not light.is_open
    light.close()
    with pytest.raises(DeviceClosed):
        light.on()
    assert not light.is_on and not lights.device_on()  # still as last switched
