"""Our Protocol 2.0 codec against the ROBOTIS e-manual's example packets, and properties."""

import pytest
from hypothesis import given
from hypothesis import strategies as st

from sim.peers.dynamixel.protocol import (
    ALERT,
    BROADCAST_ID,
    CRCError,
    Instruction,
    PacketReader,
    StuffingError,
    crc16,
    instruction_packet,
    parse,
    status_packet,
    stuff,
    unstuff,
)

# (what, our builder's output, the e-manual's bytes)
VECTORS = [
    ("PING id 1", instruction_packet(1, Instruction.PING), "FF FF FD 00 01 03 00 01 19 4E"),
    (
        "status of PING: model 1030, firmware 38",
        status_packet(1, 0, bytes([0x06, 0x04, 0x26])),
        "FF FF FD 00 01 07 00 55 00 06 04 26 65 5D",
    ),
    (
        "READ Present Position (132, 4 bytes)",
        instruction_packet(1, Instruction.READ, bytes([0x84, 0x00, 0x04, 0x00])),
        "FF FF FD 00 01 07 00 02 84 00 04 00 1D 15",
    ),
    (
        "status of READ: position 166",
        status_packet(1, 0, (166).to_bytes(4, "little")),
        "FF FF FD 00 01 08 00 55 00 A6 00 00 00 8C C0",
    ),
    (
        "WRITE Goal Position (116) = 512",
        instruction_packet(1, Instruction.WRITE, bytes([0x74, 0x00]) + (512).to_bytes(4, "little")),
        "FF FF FD 00 01 09 00 03 74 00 00 02 00 00 CA 89",
    ),
    ("REBOOT id 1", instruction_packet(1, Instruction.REBOOT), "FF FF FD 00 01 03 00 08 2F 4E"),
]


@pytest.mark.parametrize(("what", "built", "manual"), VECTORS, ids=[v[0] for v in VECTORS])
def test_builder_matches_the_e_manual(what: str, built: bytes, manual: str) -> None:
    assert built == bytes.fromhex(manual)


def test_crc_of_the_manual_ping() -> None:
    assert crc16(bytes.fromhex("FF FF FD 00 01 03 00 01")) == 0x4E19


def test_stuffing_inserts_and_removes_fd() -> None:
    assert stuff(bytes.fromhex("03 FF FF FD 01")) == bytes.fromhex("03 FF FF FD FD 01")
    packet = instruction_packet(1, Instruction.WRITE, bytes.fromhex("FF FF FD 01"))
    assert packet == bytes.fromhex("FF FF FD 00 01 08 00 03 FF FF FD FD 01 C1 0E")
    assert parse(packet).params == bytes.fromhex("FF FF FD 01")


def test_an_unstuffed_header_in_a_body_is_refused() -> None:
    for body in ("03 FF FF FD 01", "03 FF FF FD", "FF FF FD FD FF FF FD 00"):
        with pytest.raises(ValueError, match="not followed by the stuffing FD"):
            unstuff(bytes.fromhex(body))
    head = bytes.fromhex("FF FF FD 00 01 08 00 03 FF FF FD 01 00")  # LEN 8, not stuffed
    crc = crc16(head)
    reader = PacketReader()
    reader.feed(head + bytes([crc & 0xFF, crc >> 8]) + instruction_packet(1, Instruction.PING))
    with pytest.raises(StuffingError) as err:
        reader.next_packet()
    assert err.value.packet_id == 1
    packet = reader.next_packet()  # the next packet is still found
    assert packet is not None
    assert packet.instruction == Instruction.PING


@given(st.binary(max_size=64))
def test_stuffing_round_trips(body: bytes) -> None:
    stuffed = stuff(body)
    assert unstuff(stuffed) == body
    assert b"\xff\xff\xfd" not in stuffed.replace(b"\xff\xff\xfd\xfd", b"")


@given(
    st.integers(0, 252),
    st.sampled_from(list(Instruction)),
    st.binary(max_size=40),
    st.binary(max_size=20),
)
def test_packets_survive_noise_before_them(
    packet_id: int, inst: int, params: bytes, noise: bytes
) -> None:
    reader = PacketReader()
    reader.feed(noise.replace(b"\xff\xff\xfd", b"") + instruction_packet(packet_id, inst, params))
    packet = reader.next_packet()
    assert packet is not None
    assert (packet.id, packet.instruction, packet.params) == (packet_id, inst, params)


def test_packets_arrive_byte_by_byte() -> None:
    stream = status_packet(3, ALERT, b"\x01\x02") + instruction_packet(
        BROADCAST_ID, Instruction.PING
    )
    reader = PacketReader()
    got = []
    for b in stream:
        reader.feed(bytes([b]))
        p = reader.next_packet()
        if p is not None:
            got.append(p)
    assert [(p.id, p.is_status, p.error, p.params) for p in got] == [
        (3, True, ALERT, b"\x01\x02"),
        (BROADCAST_ID, False, None, b""),
    ]


def test_bad_crc_is_reported_and_skipped() -> None:
    good = instruction_packet(1, Instruction.PING)
    bad = good[:-1] + bytes([good[-1] ^ 0xFF])
    reader = PacketReader()
    reader.feed(bad + good)
    with pytest.raises(CRCError) as err:
        reader.next_packet()
    assert err.value.packet_id == 1
    packet = reader.next_packet()
    assert packet is not None
    assert packet.instruction == Instruction.PING


def test_parse_refuses_more_or_less_than_one_packet() -> None:
    ping = instruction_packet(1, Instruction.PING)
    with pytest.raises(ValueError, match="not exactly one"):
        parse(ping + ping)
    with pytest.raises(ValueError, match="not exactly one"):
        parse(ping[:-1])
