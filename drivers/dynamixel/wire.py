"""What a Dynamixel Protocol 2.0 transaction costs on the wire (bytes and seconds).

Each byte is 10 bits on the line (start, 8 data, stop). A motor answers after its
Return Delay Time (factory default 250 × 2 µs = 500 µs). Counts are unstuffed: a poll's
bytes cannot form FF FF FD except in rare position values, which add one byte each.

`step_seconds` is the bus's part of one stop-and-go step of `DynamixelBus` (goal write,
settle polls, read back), the budget the planner adds to each target's predicted time.
Wire time and return delays only: a USB adapter adds its latency timer to each status
it hands on (docs/how-to/bring-up-motors.md), the host its own time.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Bits on the line per byte: start, 8 data, stop.
BITS_PER_BYTE = 10
#: The motors' factory Return Delay Time (250 × 2 µs), in seconds.
DEFAULT_RETURN_DELAY_S = 250 * 2e-6
#: Data bytes of Present Position (one poll of one motor during a sweep).
PRESENT_POSITION_BYTES = 4
#: Data bytes of Moving … Present Position (addresses 122-135 of the X series): what
#: `DynamixelBus.wait_settled` polls and `DynamixelBus.positions` reads back.
STATE_BYTES = 14
#: Data bytes of Goal Position (one motor's part of the SYNC_WRITE of goals).
GOAL_BYTES = 4
#: The pause between two polls of `DynamixelBus.wait_settled` (s, on the motion's clock).
SETTLE_POLL_INTERVAL_S = 0.002


def sync_read_bytes(motors: int) -> int:
    """A SYNC_READ instruction: header 4, ID, LEN 2, INST, address 2, length 2, one byte
    per motor ID, CRC 2."""
    return 4 + 1 + 2 + 1 + 2 + 2 + motors + 2


def status_bytes(data: int) -> int:
    """A status packet: header 4, ID, LEN 2, INST 0x55, ERR, ``data`` bytes, CRC 2."""
    return 4 + 1 + 2 + 1 + 1 + data + 2


def poll_bytes(motors: int, data: int = PRESENT_POSITION_BYTES) -> int:
    """Bytes on the line for one SYNC_READ of ``data`` bytes from each of ``motors``."""
    return sync_read_bytes(motors) + motors * status_bytes(data)


def poll_seconds(
    motors: int,
    baud: int,
    data: int = PRESENT_POSITION_BYTES,
    return_delay_s: float = DEFAULT_RETURN_DELAY_S,
) -> float:
    """The shortest time (s) one such SYNC_READ can take at ``baud``: its bytes on the
    line plus each motor's return delay (no host or adapter latency)."""
    return poll_bytes(motors, data) * BITS_PER_BYTE / baud + motors * return_delay_s


#: Data bytes one streamed set-point writes per motor: Profile Acceleration, Profile
#: Velocity and Goal Position (addresses 108-119 of the X series, contiguous).
SETPOINT_BYTES = 12
#: The shortest set-point period (s) a trajectory asks of any bus: a host's loop.
MIN_SETPOINT_PERIOD_S = 0.01
#: Wire time of one period (a SYNC_WRITE and a SYNC_READ) over the set-point period:
#: the rest is left to the host and the adapter's latency.
SETPOINT_DUTY = 0.5


def sync_write_bytes(motors: int, data: int = SETPOINT_BYTES) -> int:
    """A SYNC_WRITE instruction: header 4, ID, LEN 2, INST, address 2, length 2, then
    per motor its ID and ``data`` bytes, CRC 2 (no status packet comes back)."""
    return 4 + 1 + 2 + 1 + 2 + 2 + motors * (1 + data) + 2


def setpoint_seconds(
    motors: int, baud: int, return_delay_s: float = DEFAULT_RETURN_DELAY_S
) -> float:
    """The shortest time (s) one period of a streamed trajectory takes at ``baud``: the
    SYNC_WRITE of every motor's set-point and the SYNC_READ poll of their positions."""
    write = sync_write_bytes(motors) * BITS_PER_BYTE / baud
    return write + poll_seconds(motors, baud, return_delay_s=return_delay_s)


def setpoint_period(motors: int, baud: int) -> float:
    """The set-point period (s) a trajectory on this bus uses: the wire time of one
    period over `SETPOINT_DUTY`, at least `MIN_SETPOINT_PERIOD_S`, rounded up to 1 ms."""
    wire = setpoint_seconds(motors, baud) / SETPOINT_DUTY
    return max(MIN_SETPOINT_PERIOD_S, math.ceil(wire * 1000.0 - 1e-9) / 1000.0)


def step_seconds(
    motors: int,
    baud: int,
    moves: ArrayLike,
    *,
    poll_interval_s: float = SETTLE_POLL_INTERVAL_S,
    return_delay_s: float = DEFAULT_RETURN_DELAY_S,
) -> NDArray[np.float64]:
    """The bus's time (s) in each stop-and-go step of ``motors`` at ``baud`` beyond the
    motion itself, for steps whose moves take ``moves`` s (any shape; 0: no motion).

    The SYNC_WRITE of the goals (the motors start once it has crossed the line), the
    wait of `DynamixelBus.wait_settled` past the motion's end, and the read back (one
    poll of `STATE_BYTES`, ``state``). The settle polls follow one another every
    ``state`` + ``poll_interval_s``; the motion ends anywhere in one of these periods, so
    the poll that finds the axes settled ends on average half a period plus one poll
    after it (one poll alone when nothing moves). Wire time and return delays only.
    """
    goals = sync_write_bytes(motors, GOAL_BYTES) * BITS_PER_BYTE / baud
    state = poll_seconds(motors, baud, STATE_BYTES, return_delay_s)
    moving = np.asarray(moves, dtype=np.float64) > 0.0
    late = np.where(moving, 0.5 * (state + poll_interval_s), 0.0)
    return np.asarray(goals + state + late + state, dtype=np.float64)
