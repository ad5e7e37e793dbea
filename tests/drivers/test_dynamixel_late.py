"""Late status packets never answer a later request: the unmodified SDK over a real pty
against the emulator, replies of chosen packets sent past the SDK's timeout
(`Fault.LATE`: the bus behind them waits, as on hardware bytes keep their order).

Every value read is compared with the emulator's register; the counts compared are
the run's own: the late replies the emulator sent after the host had moved on
(``overtaken``) are exactly the status packets the link's syncs discarded."""

from __future__ import annotations

from collections.abc import Callable

import dynamixel_sdk as sdk
import pytest

from drivers.dynamixel.axis import AxisConfig
from drivers.dynamixel.bus import DynamixelBus
from drivers.dynamixel.control_table import item
from drivers.dynamixel.link import DynamixelLink
from drivers.dynamixel.sdk_boundary import PacketHandler, Port
from drivers.errors import CommError
from sim.peers.dynamixel.emulator import DxlEmulator
from sim.peers.dynamixel.faults import Fault
from tests.support.dynamixel import axes

Emulator = Callable[..., DxlEmulator]
#: Late by this much (ms): well past a pty link's reply timeout (about 19 ms), within
#: a sync's wait (`drivers.dynamixel.owed.SYNC_WAIT_MS` more).
LATE_MS = 80.0
#: Items of one size, so that a late reply of one has the length of the next's answer.
WORDS = ("current_limit", "pwm_limit", "max_voltage_limit", "velocity_i_gain", "position_p_gain")
LONGS = ("velocity_limit", "moving_threshold", "profile_velocity", "goal_position")


def distinct_values(emu: DxlEmulator) -> None:
    """Give every item of `WORDS` and `LONGS` of every motor its own value."""
    for motor_id, motor in emu.motors.items():
        for k, name in enumerate(WORDS + LONGS):
            reg = item(name)
            motor.set(name, min(reg.high or 1000, 100 + 7 * k + 50 * motor_id))


def check_counts(
    emu: DxlEmulator, link: DynamixelLink, late: int, behind: int = 0, statuses: int = 1
) -> None:
    """Every late reply was sent and waited out (a sync at least for each), each one that
    left after the host's next packet was discarded by a sync, with the ``behind``
    statuses of a sync read held behind them, and no sync had to give up.

    On a quiet host that is all there is: one sync per late reply, each overtaken, and
    the syncs discarded exactly those. A loaded host can add syncs the emulator's count
    does not explain (an answer that was not late but missed its timeout; a late reply
    that left just as the host sent its next packet, or before it and was cleared from
    the port): each such sync may discard the statuses of the one attempt before it
    (``statuses``: one for a READ or WRITE, one per motor for a sync read), no more."""
    stats, counts = emu.stats, link.late_counts
    assert stats.late == late
    assert counts.failed == 0
    assert counts.syncs >= late
    explained = stats.overtaken + behind
    unexplained = counts.syncs - stats.overtaken
    assert explained <= counts.discarded <= explained + unexplained * statuses


def test_a_late_read_reply_never_answers_the_next_read(emulator: Emulator) -> None:
    emu = emulator(ids=(1, 2))
    distinct_values(emu)
    chosen = {1, 4, 5, 9, 12}  # reads whose reply comes late
    with DynamixelLink(emu.path, latency_ms=0) as link:
        names = [(m, n) for _ in range(2) for n in WORDS + LONGS for m in (1, 2)]
        for k, (motor_id, name) in enumerate(names):
            if k in chosen:
                emu.inject(Fault.LATE, motor_id=motor_id, delay_ms=LATE_MS)
            assert link.read(motor_id, name) == emu.motors[motor_id].get(name), (k, name)
        check_counts(emu, link, len(chosen))
        assert emu.stats.overtaken >= 1  # the host did move on before some of them
        assert [link.read(2, n) for n in WORDS] == [emu.motors[2].get(n) for n in WORDS]


def test_a_read_given_up_leaves_its_reply_to_the_next_ones_sync(emulator: Emulator) -> None:
    """Without retries the late read fails, and the next read, of another item of the
    same size, still gets its own value (not the late one's bytes: a Current Limit
    read back as another item's value)."""
    emu = emulator(ids=(1,))
    distinct_values(emu)
    with DynamixelLink(emu.path, latency_ms=0, retries=0) as link:
        emu.inject(Fault.LATE, motor_id=1, delay_ms=LATE_MS)
        with pytest.raises(CommError, match="reading pwm_limit"):
            link.read(1, "pwm_limit")
        link.retries = 3  # the next reads may meet a loaded host's timeouts of their own
        assert link.read(1, "current_limit") == emu.motors[1].get("current_limit")
        assert link.read(1, "pwm_limit") == emu.motors[1].get("pwm_limit")
        check_counts(emu, link, 1)
        # the next read's sync went out before the late reply (as it does unless the
        # host stalls for the 60 ms between its timeout and the late reply; then the
        # reply came first and the port's clearing dropped it)
        assert emu.stats.overtaken <= 1


def test_a_late_write_status_is_not_taken_for_the_next_ones(emulator: Emulator) -> None:
    emu = emulator(ids=(1, 2))
    distinct_values(emu)
    with DynamixelLink(emu.path, latency_ms=0) as link:
        for k, value in enumerate((300, 301, 302, 303)):
            if k % 2 == 0:
                emu.inject(Fault.LATE, motor_id=1, delay_ms=LATE_MS)
            link.write(1, "velocity_i_gain", value)
            link.write(2, "velocity_i_gain", value + 10)
            assert emu.motors[1].get("velocity_i_gain") == value
            for motor_id in (1, 2):
                for name in WORDS:
                    assert link.read(motor_id, name) == emu.motors[motor_id].get(name)
        check_counts(emu, link, 2)


def test_a_late_status_in_a_sync_read_is_never_taken_for_data(
    emulator: Emulator,
) -> None:
    emu = emulator(ids=(1, 2, 3))
    distinct_values(emu)
    behind = 0  # statuses held behind a late one that overtook the host's next packet
    with DynamixelLink(emu.path, latency_ms=0) as link:
        for round_ in range(6):
            late = 1 + round_ % 3
            emu.inject(Fault.LATE, motor_id=late, delay_ms=LATE_MS)
            overtaken = emu.stats.overtaken
            first, last = ("current_limit", "current_limit") if round_ % 2 else ("pwm_limit",) * 2
            data = link.sync_read([1, 2, 3], first, last)
            reg = item(first)
            assert {m: reg.decode(d) for m, d in data.items()} == {
                m: emu.motors[m].get(first) for m in (1, 2, 3)
            }
            behind += (3 - late) * (emu.stats.overtaken - overtaken)
            # a single read of the same length right after
            assert link.read(late, "max_voltage_limit") == emu.motors[late].get("max_voltage_limit")
        check_counts(emu, link, 6, behind, statuses=3)


def test_the_bus_holds_and_reads_true_positions_after_late_replies(
    emulator: Emulator,
) -> None:
    config: list[AxisConfig] = axes()
    emu = emulator(ids=tuple(a.motor_id for a in config))
    ids = [a.motor_id for a in config]
    bus = DynamixelBus(emu.path, config, latency_ms=0)
    with bus:
        for motor_id in ids:
            emu.inject(Fault.LATE, motor_id=motor_id, delay_ms=LATE_MS)
            got = bus.positions()
            assert got == {
                a.name: pytest.approx(a.to_rad(emu.motors[a.motor_id].get("present_position")))
                for a in config
            }
        bus.stop()
        assert {m: emu.motors[m].get("goal_position") for m in ids} == {
            m: emu.motors[m].get("present_position") for m in ids
        }


class CountingPort(Port):
    """The link's port, counting the SDK's calls to read it."""

    reads = 0

    def readPort(self, length: int) -> bytes:
        self.reads += 1
        return super().readPort(length)


def test_waiting_for_a_late_reply_does_not_spin(emulator: Emulator) -> None:
    """The SDK's receive loop reads the port until the packet is whole or its time is up;
    `Port.readPort` waits for a byte first, so a reply 1.5 latency timers late (within
    its timeout) costs a few reads, where the SDK's own would spin through thousands."""
    emu = emulator(ids=(1,))
    emu.motors[1].set("current_limit", 1234)
    timer = 20.0
    port = CountingPort(emu.path, timer)
    assert port.openPort() and port.setBaudRate(emu.baud)
    try:
        for late in (False, True):
            if late:
                emu.inject(Fault.LATE, motor_id=1, delay_ms=1.5 * timer)
            port.reads = 0
            value, result, error = PacketHandler().read2ByteTxRx(
                port, 1, item("current_limit").address
            )
            assert (value, result, error) == (1234, sdk.COMM_SUCCESS, 0)
            assert port.reads <= 12, (late, port.reads)
    finally:
        port.closePort()
    assert emu.stats.late == 1
