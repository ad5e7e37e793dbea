"""`DynamixelBus` / `DynamixelLink` safety paths end to end: the unmodified SDK over a real
pty against the emulator, on the emulator's virtual clock where motion matters.

Holding every axis after one faults or a settle times out, configuring without
dropping the arms, refusing stale or short replies, byte stuffing, per-port SDK
timeouts, every hardware alert, and reboot."""

from __future__ import annotations

import _thread
import math
import threading
import time
from collections.abc import Callable
from types import SimpleNamespace

import pytest
from dynamixel_sdk import port_handler

from drivers.dynamixel.axis import AxisConfig
from drivers.dynamixel.bus import DynamixelBus
from drivers.dynamixel.control_table import RAD_PER_TICK, item
from drivers.dynamixel.latency import sdk_latency_timer
from drivers.dynamixel.link import DynamixelLink
from drivers.errors import CommError, DriverError, MotionTimeout, MotorFault
from sim.clock import ManualClock
from sim.peers.dynamixel.emulator import DxlEmulator
from sim.peers.dynamixel.faults import Fault
from sim.peers.dynamixel.protocol import Instruction, Packet, PacketReader
from tests.support.dynamixel import axes

Emulator = Callable[..., DxlEmulator]
TORQUE = item("torque_enable").address
SHUTDOWN_ALERTS = {Fault.OVERHEATING, Fault.ELECTRICAL_SHOCK, Fault.OVERLOAD}  # mask 52
ALERTS = [
    Fault.INPUT_VOLTAGE,
    Fault.OVERHEATING,
    Fault.MOTOR_ENCODER,
    Fault.ELECTRICAL_SHOCK,
    Fault.OVERLOAD,
]


def barrier(emu: DxlEmulator) -> None:
    """Wait until the emulator has served every byte sent so far (also by a bus already
    closed): it serves in order, so a PING's answer comes after them."""
    with DynamixelLink(emu.path) as link:
        link.ping(min(emu.motors))


def sent_packets(emu: DxlEmulator, since: int = 0) -> list[Packet]:
    """The host's packets in the emulator's transcript (from entry ``since`` on)."""
    reader = PacketReader()
    for direction, data in emu.transcript[since:]:
        if direction == "rx":
            reader.feed(data)
    out = []
    while (packet := reader.next_packet()) is not None:
        out.append(packet)
    return out


def torque_writes(packets: list[Packet]) -> list[tuple[int, int]]:
    """(motor id, value) of every write of Torque Enable among ``packets``."""
    out = []
    for p in packets:
        address = int.from_bytes(p.params[:2], "little")
        if p.instruction == Instruction.WRITE and address == TORQUE:
            out.append((p.id, p.params[2]))
        elif p.instruction == Instruction.SYNC_WRITE and address == TORQUE:
            size = int.from_bytes(p.params[2:4], "little")
            body = p.params[4:]
            out += [(body[i], body[i + 1]) for i in range(0, len(body), 1 + size)]
    return out


@pytest.fixture
def virtual_bus(
    emulator: Emulator, latency_timer: int
) -> Callable[..., tuple[DxlEmulator, DynamixelBus]]:
    """Factory: an emulator on the test's ManualClock (motion moves only when the test
    advances it) and a bus on it."""

    def make(
        config: list[AxisConfig] | None = None, **emu_kw: object
    ) -> tuple[DxlEmulator, DynamixelBus]:
        config = config or axes()
        emu = emulator(ids=tuple(a.motor_id for a in config), **emu_kw)
        return emu, DynamixelBus(emu.path, config, latency_ms=latency_timer)

    return make


# -- 1. one fault (or a settle timeout) must not leave the other axes moving --------------


def test_a_fault_on_one_axis_leaves_every_other_axis_holding(
    virtual_bus: Callable[..., tuple[DxlEmulator, DynamixelBus]], clock: ManualClock
) -> None:
    emu, bus = virtual_bus()
    targets = {"axis1": 0.8, "axis2": -0.8, "axis3": 0.5}
    with pytest.raises(MotorFault) as err, bus:  # noqa: PT012 (the fault comes mid-move)
        bus.move_to(targets)
        bus.positions()  # a read: the goals have been served
        clock.advance(0.1)  # mid-move
        emu.inject(Fault.OVERLOAD, motor_id=3)
        bus.wait_settled(5.0)
    assert err.value.axis == "axis3"
    barrier(emu)  # the hold is a SYNC_WRITE: no status says it has arrived
    held = {}
    for motor_id in (1, 2):
        motor = emu.motors[motor_id]
        held[motor_id] = motor.get("goal_position")
        assert held[motor_id] == motor.get("present_position")  # goal := where it was
    clock.advance(5.0)  # long enough to have reached the targets
    for motor_id, name in ((1, "axis1"), (2, "axis2")):
        motor = emu.motors[motor_id]
        assert motor.get("moving") == 0
        assert motor.get("present_position") == held[motor_id]  # braked and came back
        target = axes()[0].to_ticks(targets[name])
        assert abs(held[motor_id] - target) > 100  # well short of the target
    assert emu.motors[3].get("torque_enable") == 0  # overload is in the Shutdown mask


def test_a_settle_timeout_is_raised_even_when_a_motor_faults_as_it_is_held(
    virtual_bus: Callable[..., tuple[DxlEmulator, DynamixelBus]],
    clock: ManualClock,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The bus's clock stands still, so the axes never settle; the overload appears
    between the last poll and the hold (injected by the deadline check itself)."""
    emu, bus = virtual_bus()
    calls = []

    def now() -> float:
        calls.append(1)
        if len(calls) == 2:  # the deadline check after the first poll
            emu.inject(Fault.OVERLOAD, motor_id=2)
            return math.inf
        return 0.0

    with bus:
        bus.move_to({"axis1": 0.5, "axis2": 0.5})
        bus.positions()
        clock.advance(0.05)
        with monkeypatch.context() as patch:
            patch.setattr(bus, "clock", SimpleNamespace(now=now, sleep=lambda s: None))
            with pytest.raises(MotionTimeout, match="holding them"):
                bus.wait_settled(1.0)
        bus.health()  # a read (motor 2's alert does not raise here): the hold was served
        for motor_id in (1, 3):
            motor = emu.motors[motor_id]
            assert motor.get("goal_position") == motor.get("present_position")


def test_stop_clamps_the_hold_to_the_axis_limits(
    virtual_bus: Callable[..., tuple[DxlEmulator, DynamixelBus]],
) -> None:
    """A motor pushed past its axis limit (by hand, with torque off): holding it at its
    present position would be refused by the motor (Data Limit, and a SYNC_WRITE has no
    status), leaving it chasing its old goal."""
    emu, bus = virtual_bus(axes(1))
    low, high = axes(1)[0].tick_limits()
    with bus:
        bus.move_to({"axis1": 0.5})
        emu.motors[1].set("present_position", high + 40)
        bus.stop()
        bus.positions()  # a read: the hold has been served
        assert emu.motors[1].get("goal_position") == high
    assert low < high


# -- 2. configuring must not drop the arms --------------------------------------------------


def test_a_second_open_sends_no_torque_off(
    virtual_bus: Callable[..., tuple[DxlEmulator, DynamixelBus]], latency_timer: int
) -> None:
    emu, bus = virtual_bus(record=True)
    with bus:
        pass
    since = len(emu.transcript)
    with DynamixelBus(emu.path, axes(), latency_ms=latency_timer) as again:
        again.positions()
    assert torque_writes(sent_packets(emu, since)) == [(1, 1), (2, 1), (3, 1)]  # only on
    assert all(m.get("torque_enable") == 1 for m in emu.motors.values())


def test_only_a_motor_needing_an_eeprom_write_gets_torque_off_and_it_is_read_back(
    virtual_bus: Callable[..., tuple[DxlEmulator, DynamixelBus]],
) -> None:
    emu, bus = virtual_bus(record=True)
    low, high = axes()[0].tick_limits()
    for motor in emu.motors.values():  # configured by an earlier run ...
        motor.set("min_position_limit", low)
        motor.set("max_position_limit", high)
        motor.set("torque_enable", 1)  # ... and holding its arm
    emu.motors[2].set("operating_mode", 4)  # but motor 2 was left in extended mode
    with bus:
        bus.positions()
    packets = sent_packets(emu)
    offs = [w for w in torque_writes(packets) if w[1] == 0]
    assert offs == [(2, 0)]
    mode = item("operating_mode").address
    reads = [i for i, p in enumerate(packets) if p.instruction == Instruction.READ]
    read_back = next(
        i for i in reads if packets[i].id == 2 and packets[i].params[:2] == bytes([TORQUE, 0])
    )
    write = next(
        i
        for i, p in enumerate(packets)
        if p.instruction == Instruction.WRITE and p.id == 2 and p.params[0] == mode
    )
    assert read_back < write
    assert emu.motors[2].get("operating_mode") == 3


def test_the_link_refuses_eeprom_writes_while_torque_is_known_on(emulator: Emulator) -> None:
    emu = emulator(ids=(1, 2))
    with DynamixelLink(emu.path) as link:
        link.write(1, "torque_enable", 1)
        link.sync_write("torque_enable", {2: 1})
        link.ping(2)  # a round trip: the broadcast before it has been served
        before = emu.stats.packets_in
        with pytest.raises(DriverError, match=r"motor 1: .*operating_mode = 4 .*torque is on"):
            link.write(1, "operating_mode", 4)
        with pytest.raises(DriverError, match=r"motor 2: .*homing_offset = 5 .*torque is on"):
            link.sync_write("homing_offset", {2: 5})
        assert emu.stats.packets_in == before  # nothing was sent
        link.write(1, "torque_enable", 0)
        link.write(1, "operating_mode", 4)  # known off: allowed
        assert emu.motors[1].get("operating_mode") == 4


# -- 3. short, stale and late replies ---------------------------------------------------------


def test_a_stale_reply_is_never_decoded_as_data(emulator: Emulator) -> None:
    emu = emulator(ids=(1,))
    emu.motors[1].set("present_position", 1234)
    with DynamixelLink(emu.path, latency_ms=16) as link:
        assert link.ping(1) == 1020
        emu.inject(Fault.STALE, motor_id=1)  # the PING status (3 bytes) comes again first
        assert link.read(1, "present_position") == 1234
        emu.inject(Fault.STALE, motor_id=1)  # that READ status (4 bytes) comes again first
        assert link.read(1, "hardware_error_status") == 0
        emu.inject(Fault.STALE, motor_id=1)  # a 1-byte READ status before the PING status
        assert link.ping(1) == 1020


def test_a_stale_reply_in_a_sync_read_is_retried(
    virtual_bus: Callable[..., tuple[DxlEmulator, DynamixelBus]],
) -> None:
    emu, bus = virtual_bus()
    with bus:
        bus.health()  # motor 2's last status: Present Current … Temperature (21 bytes)
        emu.inject(Fault.STALE, motor_id=2)
        assert bus.positions() == pytest.approx(dict.fromkeys(bus.axes, 0.0), abs=1e-12)


def test_reset_after_ctrl_c_drains_the_reply_still_on_its_way(emulator: Emulator) -> None:
    """Ctrl-C while the SDK waits for a status: the status still arrives, later. Without a
    drain it would be read as the answer to the next, identical request (same ID, same
    length: nothing in the packet tells them apart)."""
    emu = emulator(ids=(1,), baud=9_600, wire_time=True)
    whole = ("model_number", "present_temperature")  # 147 bytes: ~180 ms at 9600 baud
    led = item("led").address
    with DynamixelLink(emu.path, 9_600, latency_ms=0, retries=0) as link:
        threading.Timer(0.03, _thread.interrupt_main).start()
        with pytest.raises(KeyboardInterrupt):
            link.sync_read([1], *whole)
        emu.motors[1].set("led", 1)
        link.reset()
        assert link.sync_read([1], *whole)[1][led] == 1


# -- 4. byte stuffing -------------------------------------------------------------------------


def test_values_containing_a_header_are_stuffed_both_ways(emulator: Emulator) -> None:
    """-131073 is FF FF FD FF little endian: the instruction must carry FF FF FD FD FF
    (the SDK sends it unstuffed) and the status the same (the SDK unstuffs it)."""
    emu = emulator(ids=(1,), record=True)
    with DynamixelLink(emu.path) as link:
        link.write(1, "homing_offset", -131073)
        assert emu.motors[1].get("homing_offset") == -131073
        assert link.read(1, "homing_offset") == -131073
        link.write(1, "operating_mode", 4)
        link.write(1, "torque_enable", 1)
        link.sync_write("goal_position", {1: -131073})
        assert link.read(1, "goal_position") == -131073
    sent = b"".join(d for direction, d in emu.transcript if direction == "rx")
    answered = b"".join(d for direction, d in emu.transcript if direction == "tx")
    assert sent.count(b"\xff\xff\xfd\xfd\xff") == 2
    assert answered.count(b"\xff\xff\xfd\xfd\xff") == 2
    assert emu.stats.crc_errors == emu.stats.stuffing_errors == 0


def test_an_extended_axis_reaches_a_goal_whose_bytes_hold_a_header(
    virtual_bus: Callable[..., tuple[DxlEmulator, DynamixelBus]], clock: ManualClock
) -> None:
    config = [AxisConfig("turntable", 1, -210.0, 210.0, mode="extended_position",
                         profile_velocity_rad_s=4.5, profile_acceleration_rad_s2=60.0)]  # fmt: skip
    emu, bus = virtual_bus(config)
    target = -131073 * RAD_PER_TICK
    with bus:
        bus.move_to({"turntable": target})
        bus.positions()
        clock.advance(60.0)
        bus.wait_settled(1.0)
        assert emu.motors[1].get("present_position") == -131073
        assert bus.positions()["turntable"] == pytest.approx(target, abs=1e-9)


# -- 6. the SDK's latency constant is a process global ----------------------------------------


def test_a_second_link_does_not_shrink_the_first_ones_timeouts(
    emulator: Emulator, latency_timer: int
) -> None:
    slow, fast = emulator(ids=(1,)), emulator(ids=(1,), baud=1_000_000)
    first = DynamixelLink(slow.path, latency_ms=16, retries=0)
    second = DynamixelLink(fast.path, 1_000_000, latency_ms=0)
    with first, second:
        assert second.ping(1) == 1020
        assert latency_timer == port_handler.LATENCY_TIMER  # the global is untouched
        slow.inject(Fault.NO_REPLY, motor_id=1)
        started = time.monotonic()
        with pytest.raises(CommError, match="no status packet"):
            first.ping(1)
        waited = time.monotonic() - started
    assert first.latency_timer_ms == sdk_latency_timer(16, 57_600)
    assert waited >= 2 * first.latency_timer_ms / 1000


# -- 7. every alert end to end, and reboot ---------------------------------------------------


@pytest.mark.parametrize("fault", ALERTS, ids=[f.value for f in ALERTS])
def test_every_alert_is_a_named_fault_and_reboot_clears_it(
    virtual_bus: Callable[..., tuple[DxlEmulator, DynamixelBus]],
    clock: ManualClock,
    fault: Fault,
) -> None:
    emu, bus = virtual_bus()
    with bus:
        bus.move_to({"axis2": 0.5})
        bus.positions()
        clock.advance(0.05)
        emu.inject(fault, motor_id=2)
        with pytest.raises(MotorFault) as err:
            bus.positions()
        assert (err.value.motor_id, err.value.axis, err.value.flags) == (2, "axis2", (fault.value,))
        assert f"motor 2 (axis 'axis2') reports a hardware error: {fault.value}" in str(err.value)
        motor = emu.motors[2]
        assert motor.get("torque_enable") == (0 if fault in SHUTDOWN_ALERTS else 1)

        emu.reset_stats()
        assert bus.reboot() == ("axis2",)
        assert emu.stats.instructions["REBOOT"] == 1  # only the faulted motor
        assert motor.hardware_error == 0
        assert motor.get("torque_enable") == 1
        assert motor.get("goal_position") == motor.get("present_position")
        velocity, acceleration = axes()[1].profile_registers()
        assert (motor.get("profile_velocity"), motor.get("profile_acceleration")) == (
            velocity,
            acceleration,
        )
        bus.move_to({"axis2": 0.2})
        bus.positions()
        clock.advance(5.0)
        bus.wait_settled(1.0)
        assert bus.positions()["axis2"] == pytest.approx(0.2, abs=RAD_PER_TICK)


def test_reboot_of_named_axes_and_of_a_healthy_bus(
    virtual_bus: Callable[..., tuple[DxlEmulator, DynamixelBus]],
) -> None:
    emu, bus = virtual_bus()
    with bus:
        assert bus.reboot() == ()  # nothing faulted: nothing rebooted
        emu.motors[1].set("present_position", 2100)
        assert bus.reboot(["axis1"]) == ("axis1",)
        motor = emu.motors[1]
        assert motor.get("torque_enable") == 1
        assert motor.get("goal_position") == motor.get("present_position") == 2100
        with pytest.raises(DriverError, match="unknown axis 'elbow'"):
            bus.reboot(["elbow"])
