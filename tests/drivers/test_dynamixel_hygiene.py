"""Bus hygiene (`drivers.dynamixel.hygiene`): the adapter's latency timer on a fake sysfs
tree, the port's permissions, and the motors' model, firmware, Status Return Level and
Return Delay Time through the real `DynamixelLink` against the byte-level emulator."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import pytest

from drivers.dynamixel.axis import AxisConfig
from drivers.dynamixel.hygiene import (
    Expected,
    Finding,
    access_finding,
    blocking,
    check_bus,
    latency_finding,
    motor_findings,
)
from drivers.dynamixel.latency import (
    DEFAULT_LATENCY_MS,
    UDEV_RULE,
    adapter_latency_ms,
    assumed_adapter_ms,
    return_delay_budget_us,
)
from drivers.dynamixel.link import DynamixelLink
from sim.peers.dynamixel.emulator import DxlEmulator
from sim.peers.dynamixel.faults import Fault

Emulator = Callable[..., DxlEmulator]


def usb_port(tmp_path: Path, latency: str | None) -> tuple[str, Path]:
    """(/dev/serial/by-id/… symlink to a fake ttyUSB3, a sysfs root) where the adapter's
    latency timer reads ``latency`` (None: an adapter without one, not FTDI)."""
    dev = tmp_path / "dev"
    (dev / "serial" / "by-id").mkdir(parents=True)
    (dev / "ttyUSB3").touch()
    link = dev / "serial" / "by-id" / "usb-FTDI_USB__-__Serial_Converter-if00-port0"
    link.symlink_to(dev / "ttyUSB3")
    sysfs = tmp_path / "sys" / "bus" / "usb-serial" / "devices"
    (sysfs / "ttyUSB3").mkdir(parents=True)
    if latency is not None:
        (sysfs / "ttyUSB3" / "latency_timer").write_text(f"{latency}\n")
    return str(link), sysfs


def test_a_16_ms_latency_timer_is_a_warning_with_the_fix_and_the_udev_rule(
    tmp_path: Path,
) -> None:
    port, sysfs = usb_port(tmp_path, "16")
    finding = latency_finding(port, sysfs)
    assert finding.level == "warning"
    timer = sysfs / "ttyUSB3" / "latency_timer"
    assert f"echo 1 | sudo tee {timer}" in finding.text
    assert UDEV_RULE in finding.text and "16 ms" in finding.text
    assert adapter_latency_ms(port, sysfs) == 16.0  # the link counts with what sysfs says


def test_a_1_ms_timer_is_ok_and_ports_without_one_are_not_concerned(tmp_path: Path) -> None:
    port, sysfs = usb_port(tmp_path, "1")
    assert latency_finding(port, sysfs).level == "ok"
    other, bare = usb_port(tmp_path / "cp210x", None)  # a ttyUSB adapter that is not FTDI
    assert latency_finding(other, bare).level == "n/a"
    assert "not an FTDI adapter" in latency_finding(other, bare).text
    controller, device = os.openpty()
    try:
        pty = latency_finding(os.ttyname(device), sysfs)
    finally:
        os.close(controller)
        os.close(device)
    assert pty.level == "n/a" and "does not apply" in pty.text
    assert assumed_adapter_ms(other, sysfs=bare) == DEFAULT_LATENCY_MS


def test_a_port_this_user_cannot_open_names_the_group_and_the_fix(tmp_path: Path) -> None:
    port, _ = usb_port(tmp_path, "1")
    refused = access_finding(port, access=lambda path, mode: False)
    assert refused.level == "problem"
    assert port in refused.text and "sudo usermod -aG" in refused.text
    missing = access_finding(str(tmp_path / "ttyUSB9"))
    assert missing.level == "problem" and "does not exist" in missing.text
    assert access_finding(port).level == "ok"
    findings = check_bus(port, 57_600, [axis(1)], access=lambda p, m: False)
    assert [f.level for f in findings] == ["problem", "n/a"]  # no port opened


def test_the_return_delay_budget_follows_the_reply_timeouts() -> None:
    """On a pty at 57 600 baud only the SDK's fixed 2 ms is left (the outbound margin
    takes the rest): 500 µs each for 4 motors, the factory default; an adapter's latency
    counted by the link adds its own once more."""
    assert return_delay_budget_us(4, 57_600, 0.0) == pytest.approx(500.0)
    assert return_delay_budget_us(8, 57_600, 0.0) == pytest.approx(250.0)
    assert return_delay_budget_us(4, 57_600, 1.0) == pytest.approx(750.0)
    assert return_delay_budget_us(4, 57_600, 16.0) > 4 * 254 * 2  # never short


def axis(motor_id: int, **expected: int) -> AxisConfig:
    return AxisConfig(f"axis{motor_id}", motor_id, 1.0, 2.0, **expected)  # type: ignore[arg-type]


def by_motor(findings: list[Finding]) -> dict[int, list[Finding]]:
    out: dict[int, list[Finding]] = {}
    for f in findings:
        if f.text.startswith("motor "):
            out.setdefault(int(f.text.split()[1]), []).append(f)
    return out


def test_each_mismatch_is_one_line_naming_the_motor_and_the_fix(emulator: Emulator) -> None:
    """Wrong model, wrong firmware, Status Return Level 1 and 0, a return delay beyond
    the budget, a motor missing: each one problem line naming ID and axis; the right
    motor one ok line. Through the real link over the emulator's pty."""
    emu = emulator(ids=(1, 2, 3, 4, 5, 6))
    for motor in emu.motors.values():
        motor.set("return_delay_time", 0)
    emu.motors[2].set("model_number", 1060)  # an XL430-W250
    emu.motors[3].set("firmware_version", 44)
    emu.motors[4].set("status_return_level", 1)
    emu.motors[5].set("status_return_level", 0)
    emu.motors[6].set("return_delay_time", 254)
    expected = {"model": 1020, "firmware": 46}
    axes = [axis(i, **expected) for i in (1, 2, 3, 4, 5, 6, 7)]
    findings = check_bus(emu.path, 57_600, axes, latency_ms=0.0)
    assert [f.level for f in findings[:2]] == ["ok", "n/a"]  # the pty
    motors = by_motor(findings)
    assert [f.level for f in motors[1]] == ["ok"]
    assert "XM430-W350, firmware 46, return delay 0 µs" in motors[1][0].text
    for motor_id in (2, 3, 4, 5, 6, 7):
        (line,) = motors[motor_id]
        assert line.level == "problem"
        assert f"motor {motor_id} (axis 'axis{motor_id}')" in line.text
    assert "XL430-W250 (model number 1060)" in motors[2][0].text
    assert "axes.axis2.motor_model" in motors[2][0].text
    assert "firmware 44; the rig file expects 46" in motors[3][0].text
    assert "Status Return Level 1" in motors[4][0].text
    assert "gonio motors reboot" in motors[4][0].text
    assert "answers PING but not READ" in motors[5][0].text
    assert "does not answer" in motors[7][0].text
    # 7 motors on a pty at 57 600 baud: 2 ms / 7 = 285 µs each, so not 254 (508 µs)
    assert "Return Delay Time 254" in motors[6][0].text
    assert "at most 142" in motors[6][0].text and "address 9" in motors[6][0].text
    assert len(blocking(findings)) == sum(len(v) for k, v in motors.items() if k != 1)
    assert emu.stats.instructions.keys() <= {"PING", "READ"}  # nothing written


def test_a_read_reply_lost_once_is_no_status_return_level_0(emulator: Emulator) -> None:
    """A motor whose first READ reply is lost (a host too busy to take it in time), with
    no retry left, answers the next round: ok, not taken for Status Return Level 0."""
    emu = emulator(ids=(1,))
    emu.motors[1].set("return_delay_time", 0)
    emu.inject(Fault.LATE, 1, count=1, delay_ms=0.01)  # the PING's reply, answered
    emu.inject(Fault.NO_REPLY, 1, count=1)  # the first READ's, lost
    findings = check_bus(emu.path, 57_600, [axis(1)], retries=0, latency_ms=0.0)
    (line,) = by_motor(findings)[1]
    assert line.level == "ok", line.text
    assert emu.stats.instructions["PING"] == 2  # the second round PINGs again


def test_without_expectations_any_known_model_passes(emulator: Emulator) -> None:
    emu = emulator(ids=(1, 2))
    emu.motors[2].set("model_number", 1234)
    findings = check_bus(emu.path, 57_600, [axis(1), axis(2)])
    motors = by_motor(findings)
    assert [f.level for f in motors[1]] == ["ok"]
    assert [f.level for f in motors[2]] == ["warning"]
    assert "axes.axis2.motor_model: 1234" in motors[2][0].text
    assert not blocking(findings)


def test_reads_answered_only_past_their_timeouts_are_not_status_return_level_0(
    emulator: Emulator,
) -> None:
    """A motor whose READ statuses come past the attempts' timeouts (as on a loaded
    host) did answer READ: asked again, it is checked as any other, not reported as
    Status Return Level 0 (whose READs never come back, as the test above shows)."""
    emu = emulator(ids=(1,))
    emu.motors[1].set("return_delay_time", 0)

    class LateAfterPing(DynamixelLink):
        """The real link; the motor's next two statuses (a READ's and its sync's) are
        sent 80 ms late once its first PING is answered: that READ fails both attempts."""

        pinged = False

        def ping(self, motor_id: int) -> int:
            model = super().ping(motor_id)
            if not self.pinged:
                emu.inject(Fault.LATE, motor_id=motor_id, count=2, delay_ms=80.0)
                self.pinged = True
            return model

    with LateAfterPing(emu.path, 57_600, retries=1, latency_ms=0.0) as link:
        findings = motor_findings(link, [Expected(1, "axis1", 1020, 46)], 0.0)
        assert link.late_counts.discarded >= 1  # the late READ status did come
    assert [f.level for f in findings] == ["ok"], findings
    assert emu.stats.late == 2
