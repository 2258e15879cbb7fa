"""firmware_protocol.can_bits (frame_bits, crc15, stuff_bit_count) against hand-worked CAN 2.0
examples and independent oracles.

Truths used here (none taken from the code under test):
* CAN 2.0 spec (Bosch 1991) part A §3.1.1 frame layout: SOF, 11-bit id, RTR, IDE, r0, DLC, data,
  CRC-15 (x^15+x^14+x^10+x^8+x^7+x^4+x^3+1, register initialised to 0), CRC delimiter, ACK slot,
  ACK delimiter, 7-bit EOF, 3-bit intermission; bit stuffing ("Frame Coding") from SOF to the
  end of the CRC sequence, a complementary bit after 5 equal bits, counted in later runs.
* A frame captured on a car's OBD-II bus, bits and CRC as published by its author
  (github.com/dominic-meads/CAN_2.0 README): id 0x0C1, DLC 8, data 40 01 08 75 00 00 00 00,
  CRC = 101101101000000.
* Worst-case stuffing bound of Davis, Burns, Bril, Lukkien (Real-Time Systems 35, 2007):
  standard frame ≤ 8n + 47 + floor((34 + 8n - 1) / 4),
  extended frame ≤ 8n + 67 + floor((54 + 8n - 1) / 4).
"""

from __future__ import annotations

import random

import pytest

from firmware_protocol.can_bits import crc15, frame_bits, frame_bits_fast, stuff_bit_count

pytestmark = pytest.mark.unit

# --- independent oracles (test-only) ---------------------------------------------------------


def _crc15_long_division(bits: str) -> int:
    """CRC = remainder of M(x)·x^15 divided by G(x) over GF(2), by plain long division."""
    poly = "1100010110011001"  # x^15 + x^14 + x^10 + x^8 + x^7 + x^4 + x^3 + 1 (16 coefficients)
    work = [int(b) for b in bits] + [0] * 15
    for i in range(len(bits)):
        if work[i]:
            for j, p in enumerate(poly):
                work[i + j] ^= int(p)
    return int("".join(map(str, work[-15:])), 2)


def _stuffed_length(bits: str) -> int:
    """Length after stuffing, by transmitting bit by bit with a run counter."""
    out = []
    run_value, run_len = None, 0
    for b in bits:
        out.append(b)
        if b == run_value:
            run_len += 1
        else:
            run_value, run_len = b, 1
        if run_len == 5:
            stuff = "1" if b == "0" else "0"
            out.append(stuff)
            run_value, run_len = stuff, 1
    return len(out)


def _frame_fields(
    can_id: int, data: bytes, extended: bool, remote: bool = False, dlc: int | None = None
) -> str:
    dlc_bits = format(len(data) if dlc is None else dlc, "04b")
    rtr = "1" if remote else "0"
    payload = "".join(format(b, "08b") for b in data)
    if extended:
        head = "0" + format(can_id >> 18, "011b") + "11" + format(can_id & 0x3FFFF, "018b")
        head += rtr + "00" + dlc_bits  # RTR, r1, r0, DLC
    else:
        head = "0" + format(can_id, "011b") + rtr + "00" + dlc_bits  # SOF, id, RTR, IDE, r0, DLC
    return head + payload


def _oracle_bits(
    can_id: int, data: bytes, extended: bool, remote: bool = False, dlc: int | None = None
) -> int:
    fields = _frame_fields(can_id, data, extended, remote, dlc)
    crc = format(_crc15_long_division(fields), "015b")
    return _stuffed_length(fields + crc) + 1 + 2 + 7 + 3


# --- hand-worked examples --------------------------------------------------------------------

CAR_FIELDS = (
    "0"  # SOF
    "00011000001"  # id 0x0C1
    "0"
    "0"
    "0"  # RTR IDE r0
    "1000"  # DLC 8
    "0100000000000001000010000111010100000000000000000000000000000000"  # 40 01 08 75 00 00 00 00
)


def test_crc_of_captured_car_frame_matches_published_crc():
    assert crc15(int(CAR_FIELDS, 2), len(CAR_FIELDS)) == 0b101101101000000
    assert _crc15_long_division(CAR_FIELDS) == 0b101101101000000  # the oracle agrees too


def test_captured_car_frame_length_hand_counted():
    # Hand count of stuff bits over SOF..CRC (98 bits):
    #   SOF+id "0000 11 00000" -> 1 stuff after the five 0s of the id;
    #   data 0x40,0x01: 13 zeros after the 1 of 0x40 -> 2 stuffs;
    #   0x08, 0x75: no run reaches 5;
    #   bytes 5..8: 32 zeros -> 6 stuffs (after zeros 5,10,...,30), 2 zeros left;
    #   CRC 1011011010 00000 -> the final five zeros get 1 stuff.
    # 98 + 10 stuff bits + 13 (CRC delim, ACK slot, ACK delim, EOF 7, IFS 3) = 121.
    assert frame_bits(0x0C1, bytes.fromhex("4001087500000000")) == 121


def test_all_zero_standard_frame():
    # id 0, no data: 34 dominant bits SOF..CRC (the CRC of all zeros is 0) -> a stuff bit after
    # every 5th zero: 6 stuff bits; 34 + 6 + 13 = 53.
    assert frame_bits(0x000, b"") == 53


def test_eight_byte_frame_lies_between_111_and_worst_case():
    # 47 + 64 = 111 bits unstuffed (CiA/literature figure); worst case 111 + 24 = 135.
    for data in (bytes(8), b"\xff" * 8, b"\xaa" * 8, bytes(range(8))):
        n = frame_bits(0x7FF, data)
        assert 111 <= n <= 135


@pytest.mark.parametrize("extended", [False, True])
def test_random_frames_match_independent_oracle_and_bounds(extended):
    rng = random.Random(20200101)
    for _ in range(400):
        n = rng.randrange(9)
        data = bytes(rng.randrange(256) for _ in range(n))
        if rng.random() < 0.3:
            data = bytes(rng.choice((0x00, 0xFF)) for _ in range(n))
        can_id = rng.randrange(1 << (29 if extended else 11))
        got = frame_bits(can_id, data, extended)
        assert got == _oracle_bits(can_id, data, extended), (hex(can_id), data.hex())
        assert frame_bits_fast(can_id, data, extended) == got
        base, stuffable = (67, 54) if extended else (47, 34)
        assert 8 * n + base <= got <= 8 * n + base + (stuffable + 8 * n - 1) // 4


@pytest.mark.parametrize("extended", [False, True])
def test_remote_frames_match_independent_oracle(extended):
    # a remote frame: RTR recessive, the DLC of the requested data, no data field
    rng = random.Random(7)
    for _ in range(200):
        can_id, dlc = rng.randrange(1 << (29 if extended else 11)), rng.randrange(9)
        got = frame_bits(can_id, b"", extended, is_remote=True, dlc=dlc)
        assert got == _oracle_bits(can_id, b"", extended, remote=True, dlc=dlc)


def test_stuff_bit_count_matches_bit_by_bit_transmitter():
    rng = random.Random(11)
    for _ in range(500):
        n = rng.randrange(0, 140)
        bits = "".join(rng.choice(("0", "1", "00000", "11111")) for _ in range(n))[:n]
        value = int(bits, 2) if bits else 0
        assert stuff_bit_count(value, len(bits)) == _stuffed_length(bits) - len(bits), bits


def test_stuff_bits_hand_worked():
    assert stuff_bit_count(0b00000, 5) == 1  # five equal bits: one stuff bit
    assert stuff_bit_count(0b0000, 4) == 0
    # 00000 (stuff 1) then 1111: the stuff bit is the first of five 1s -> a second stuff bit
    assert stuff_bit_count(0b000001111, 9) == 2
    assert stuff_bit_count(0b0000000000, 10) == 2  # ten 0s: stuffs after the 5th and 10th


def test_bad_frames_raise():
    with pytest.raises(ValueError):
        frame_bits(0x800, b"")
    with pytest.raises(ValueError):
        frame_bits(-1, b"")
    with pytest.raises(ValueError):
        frame_bits(0x20000000, b"", True)
    with pytest.raises(ValueError):
        frame_bits(0x123, bytes(9))
    with pytest.raises(ValueError):
        frame_bits(0x123, b"\x01", is_remote=True)
    with pytest.raises(ValueError):
        frame_bits(0x123, b"", is_remote=True, dlc=9)
    with pytest.raises(ValueError):
        stuff_bit_count(0b100, 2)


def test_drive_link_bus_monitor_counts_exact_frame_lengths():
    # drive_link's bus load uses the same bit physics (one home): the captured car frame is 121
    # bits, the all-zero frame 53, a remote frame follows the oracle; error frames count nothing
    import can

    from drive_link.link._connection import BusMonitor

    mon = BusMonitor()
    car = bytes.fromhex("4001087500000000")
    mon.on_message_received(can.Message(arbitration_id=0x0C1, data=car, is_extended_id=False))
    mon.on_message_received(can.Message(arbitration_id=0, data=b"", is_extended_id=False))
    mon.on_message_received(
        can.Message(arbitration_id=0x1234567, is_extended_id=True, is_remote_frame=True, dlc=4)
    )
    mon.on_message_received(can.Message(arbitration_id=0x20000008, is_error_frame=True))
    remote = _oracle_bits(0x1234567, b"", True, remote=True, dlc=4)
    assert mon.frames_total == 3
    assert mon.bits_total == 121 + 53 + remote
