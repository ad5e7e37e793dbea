"""Reply faults at a rate (`FaultBook.strike`, `DxlEmulator.inject_rate`): each status
packet is struck independently with the given probability, queued faults first."""

from __future__ import annotations

import pytest

from sim.peers.dynamixel.faults import Fault, FaultBook
from sim.peers.dynamixel.motor import EmulatedMotor


def test_a_rate_strikes_that_share_of_status_packets_after_the_queued_ones() -> None:
    book, motor = FaultBook(), EmulatedMotor(1)
    book.add(motor, Fault.CORRUPT_CRC, 2)
    book.strike(Fault.NO_REPLY, 0.05, seed=3)
    assert [book.take(motor) for _ in range(2)] == [Fault.CORRUPT_CRC] * 2
    draws = [book.take(motor) for _ in range(20_000)]
    assert set(draws) == {None, Fault.NO_REPLY}
    assert draws.count(Fault.NO_REPLY) / len(draws) == pytest.approx(0.05, abs=0.005)
    book.strike(Fault.NO_REPLY, 0.0)
    assert all(book.take(motor) is None for _ in range(1000))
    book.strike(Fault.NO_REPLY, 1.0)
    book.clear()
    assert book.take(motor) is None


def test_only_reply_faults_at_a_rate_in_0_to_1() -> None:
    book = FaultBook()
    with pytest.raises(ValueError, match="not a reply fault"):
        book.strike(Fault.OVERLOAD, 0.1)
    with pytest.raises(ValueError, match=r"rate must be in \[0, 1\]"):
        book.strike(Fault.NO_REPLY, 1.5)
