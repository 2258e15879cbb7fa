"""CAN 2.0 bit physics: how many bits a classical frame occupies on the wire, and who wins
arbitration. The one home of these facts: the loopback hub paces its emulated bus with them and
drive_link's bus monitor turns received frames into bus load with them.

Frame layout (CAN 2.0 spec, Bosch 1991, part A/B §3.1.1): SOF, identifier (11 bits; extended:
11 + SRR + IDE + 18), RTR, IDE/r1, r0, DLC (4), data (8·n), CRC-15, CRC delimiter, ACK slot, ACK
delimiter, EOF (7), then the 3-bit intermission. Bit stuffing ("Frame Coding") runs from SOF to
the end of the CRC sequence: after five equal bits the transmitter inserts one complementary bit,
which counts in the next run.

Pure functions, no I/O. Units: bits (divide by the bit rate in bit/s for seconds).
"""

from __future__ import annotations

from functools import reduce
from operator import getitem, xor

__all__ = [
    "CRC15_POLY",
    "TRAILER_BITS",
    "arbitration_key",
    "crc15",
    "frame_bits",
    "frame_bits_fast",
    "stuff_bit_count",
]

#: x^15 + x^14 + x^10 + x^8 + x^7 + x^4 + x^3 + 1 (CAN 2.0 spec §3.1.1.6), without the x^15 term.
CRC15_POLY = 0x4599

#: CRC delimiter 1 + ACK slot 1 + ACK delimiter 1 + EOF 7 + intermission 3 (never stuffed).
TRAILER_BITS = 13


def _crc15_table() -> tuple[int, ...]:
    table = []
    for byte in range(256):
        crc = byte << 7
        for _ in range(8):
            crc = ((crc << 1) ^ CRC15_POLY) if crc & 0x4000 else (crc << 1)
            crc &= 0x7FFF
        table.append(crc)
    return tuple(table)


_CRC15_TABLE = _crc15_table()


def _position_tables(n_tables: int) -> tuple[tuple[int, ...], ...]:
    """tables[k][byte]: CRC-15 of ``byte`` followed by ``k`` zero bytes. The CRC (init 0) is
    linear over GF(2), so a message's CRC is the xor of its bytes' entries by their distance from
    the end: the bytes are looked up independently (in C, by map/reduce)."""
    tables = [_CRC15_TABLE]
    for _ in range(1, n_tables):
        prev = tables[-1]
        tables.append(tuple(((c << 8) & 0x7FFF) ^ _CRC15_TABLE[(c >> 7) & 0xFF] for c in prev))
    return tuple(tables)


_MAX_OCTETS = (39 + 64 + 7) // 8  # longest message under the CRC: extended header + 8 bytes
#: for a message of L bytes: the tables of its bytes in order (first byte farthest from the end)
_TABLES_BY_LENGTH = tuple(
    _position_tables(_MAX_OCTETS)[n - 1 :: -1] if n else () for n in range(_MAX_OCTETS + 1)
)


def crc15(bits: int, n_bits: int) -> int:
    """CAN CRC-15 of the ``n_bits`` most-significant-first bits held in the integer ``bits``.

    Same result as the bit-serial register of the CAN 2.0 spec (init 0, no final xor). Leading
    zero bits do not change a CRC with init 0, so the bits are padded on the left to whole bytes.
    Raises ValueError if ``bits`` does not fit in ``n_bits`` bits.
    """
    if n_bits < 0 or bits < 0 or bits >> n_bits:
        raise ValueError("bits must be a non-negative integer of at most n_bits bits")
    octets = bits.to_bytes((n_bits + 7) // 8, "big")
    if len(octets) <= _MAX_OCTETS:
        return _crc15(octets)
    crc = 0
    for byte in octets:  # longer than any frame: byte-serial
        crc = ((crc << 8) & 0x7FFF) ^ _CRC15_TABLE[((crc >> 7) ^ byte) & 0xFF]
    return crc


def _crc15(octets: bytes) -> int:
    """CRC-15 of at most ``_MAX_OCTETS`` bytes."""
    return reduce(xor, map(getitem, _TABLES_BY_LENGTH[len(octets)], octets), 0)


# Stuffing as a finite-state machine. State = last bit · 5 + length of its run (0..4; a run of 5
# is stuffed at once, and the stuff bit starts a run of 1 of the other value). The state before
# SOF is "1, run 0" (the idle bus is recessive, but its bits are not stuffed).
_START = 1 * 5 + 0


def _step(state: int, bit: int) -> tuple[int, int]:
    """(stuff bits inserted, new state) after transmitting ``bit`` in ``state``."""
    last, run = divmod(state, 5)
    run = run + 1 if bit == last else 1
    if run == 5:
        return 1, (1 - bit) * 5 + 1
    return 0, bit * 5 + run


def _chunk_tables() -> tuple[tuple[int, ...], ...]:
    """tables[k][state · 256 + byte] = stuff bits · 16 + new state after the ``k`` (1..8) most
    significant bits of ``byte`` (the others are ignored), MSB first."""
    tables: list[tuple[int, ...]] = [()]
    for k in range(1, 9):
        table = []
        for state in range(10):
            for byte in range(256):
                s, stuffs = state, 0
                for j in range(7, 7 - k, -1):
                    inserted, s = _step(s, (byte >> j) & 1)
                    stuffs += inserted
                table.append(stuffs * 16 + s)
        tables.append(tuple(table))
    return tuple(tables)


#: the stuffing tables, built on the first count (about 13 ms: not a cost of every process
#: that imports this module, such as each drive-link command)
_CHUNK_TABLES: tuple[tuple[int, ...], ...] = ()


def stuff_bit_count(bits: int, n_bits: int) -> int:
    """Stuff bits a transmitter inserts into the ``n_bits`` bits of ``bits`` (MSB first, SOF
    first, SOF .. end of the CRC sequence). Raises ValueError if ``bits`` has more bits."""
    if n_bits < 0 or bits < 0 or bits >> n_bits:
        raise ValueError("bits must be a non-negative integer of at most n_bits bits")
    return _stuff_count(bits, n_bits)


def _stuff_count(bits: int, n_bits: int) -> int:
    """Byte by byte through the state machine (the last byte padded on the right)."""
    if not n_bits:
        return 0
    tables = _CHUNK_TABLES or _built_chunk_tables()
    tail = -n_bits & 7
    octets = (bits << tail).to_bytes((n_bits + 7) >> 3, "big")
    state, stuffs = _START, 0
    table = tables[8]
    for byte in octets[:-1]:
        packed = table[state * 256 + byte]
        stuffs += packed >> 4
        state = packed & 15
    return stuffs + (tables[8 - tail][state * 256 + octets[-1]] >> 4)


def _built_chunk_tables() -> tuple[tuple[int, ...], ...]:
    global _CHUNK_TABLES
    _CHUNK_TABLES = _chunk_tables()  # (two threads may both build it: same tables)
    return _CHUNK_TABLES


def frame_bits(
    arbitration_id: int,
    data: bytes,
    is_extended: bool = False,
    *,
    is_remote: bool = False,
    dlc: int | None = None,
) -> int:
    """Bits a classical CAN frame occupies on the bus, with its exact bit stuffing.

    Counts SOF, arbitration and control fields, data, CRC-15 (all stuffed, the stuff bits found on
    the real bit pattern), then CRC delimiter, ACK slot and delimiter, EOF (7) and the 3-bit
    intermission. Data frame: 47 + 8·n bits before stuffing (extended: 67 + 8·n).
    A remote frame (``is_remote``) has RTR = 1, no data field, and the DLC ``dlc`` (0..8).
    Unit: bits.

    Raises ValueError for an identifier out of range, more than 8 data bytes, data in a remote
    frame or a DLC out of 0..8.
    """
    n = len(data)
    if n > 8:
        raise ValueError(f"classical CAN carries at most 8 data bytes, got {n}")
    if is_remote:
        if n:
            raise ValueError("a remote frame carries no data")
        code = n if dlc is None else dlc
        if isinstance(code, bool) or not isinstance(code, int) or not 0 <= code <= 8:
            raise ValueError(f"DLC must be 0..8, got {dlc!r}")
    else:
        if dlc is not None and dlc != n:
            raise ValueError(f"DLC {dlc!r} differs from the {n} data bytes of a data frame")
        code = n
    if is_extended:
        if not 0 <= arbitration_id <= 0x1FFFFFFF:
            raise ValueError(f"extended identifier {arbitration_id:#x} out of 0..0x1FFFFFFF")
    elif not 0 <= arbitration_id <= 0x7FF:
        raise ValueError(f"standard identifier {arbitration_id:#x} out of 0..0x7FF")
    return _frame_bits(arbitration_id, bytes(data), is_extended, is_remote, code)


def _frame_bits(can_id: int, data: bytes, is_extended: bool, is_remote: bool, dlc: int) -> int:
    rtr = 1 if is_remote else 0
    if is_extended:
        # SOF 0 | base 11 | SRR 1 | IDE 1 | ext 18 | RTR | r1 0 | r0 0 | DLC 4  -> 39 bits
        header = ((((can_id >> 18) << 2 | 0b11) << 18 | (can_id & 0x3FFFF)) << 7) | rtr << 6 | dlc
        header_bits = 39
    else:
        # SOF 0 | id 11 | RTR | IDE 0 | r0 0 | DLC 4  -> 19 bits
        header = (can_id << 7) | rtr << 6 | dlc
        header_bits = 19
    n_bits = header_bits + 8 * len(data)
    value = (header << (8 * len(data))) | int.from_bytes(data, "big")
    region = (value << 15) | _crc15(value.to_bytes((n_bits + 7) >> 3, "big"))
    return n_bits + 15 + _stuff_count(region, n_bits + 15) + TRAILER_BITS


_cache: dict[tuple[int, bytes, bool], int] = {}
_CACHE_MAX = 4096


def frame_bits_fast(arbitration_id: int, data: bytes, is_extended: bool = False) -> int:
    """:func:`frame_bits` of a data frame already known to be valid (identifier in range, at most
    8 bytes of ``bytes``), without the checks; repeated frames come from a small cache. For the
    hub and bus monitors, which see thousands of frames per second."""
    key = (arbitration_id, data, is_extended)
    bits = _cache.get(key)
    if bits is None:
        if len(_cache) >= _CACHE_MAX:
            _cache.clear()
        bits = _cache[key] = _frame_bits(arbitration_id, data, is_extended, False, len(data))
    return bits


def arbitration_key(arbitration_id: int, is_extended: bool) -> int:
    """The bits sent during arbitration as one integer: the lower key wins the bus.

    A standard frame's RTR 0 and IDE 0 beat an extended frame's SRR 1 with the same 11-bit base.
    """
    if is_extended:
        return (arbitration_id >> 18) << 20 | 0b11 << 18 | (arbitration_id & 0x3FFFF)
    return arbitration_id << 20
