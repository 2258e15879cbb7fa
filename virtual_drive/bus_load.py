"""Bus load the virtual drives' default TPDO streams offer, before any of them runs.

Several drives at the default rates can offer more than a classical CAN bus carries (four at
1 Mbit/s: about 97 % without stuff bits, 101 % with typical ones); the SDO replies (0x580 + N,
the lowest priority) then wait behind the TPDOs. :func:`overload_warning` says so in one line
when ``virtual-drive hub --nodes`` starts such a bench.

Frame length without stuff bits (ISO 11898-1 classical data frame, 11-bit identifier): SOF 1,
identifier 11, RTR 1, IDE 1, r0 1, DLC 4, data 8·n, CRC 15, CRC delimiter 1, ACK slot and
delimiter 2, EOF 7, plus the 3-bit intermission: 47 + 8·n bits, a lower bound of the real length.
"""

from __future__ import annotations

from firmware_protocol import ObjectDictionaryView, load_od

__all__ = ["WARN_LOAD", "default_tpdo_bits_per_s", "offered_load", "overload_warning"]

#: Offered load (fraction of the bit rate) from which :func:`overload_warning` warns.
WARN_LOAD = 0.8

_N_TPDO = 4


def default_tpdo_bits_per_s() -> float:
    """Bits per second one drive's event-driven TPDOs take at their EDS defaults (event timer
    and mapping), counted without stuff bits (bit/s, a lower bound)."""
    view = load_od(node_id=1)
    bits = 0.0
    for k in range(1, _N_TPDO + 1):
        cob_id = _int_default(view, f"tpdo{k}_communication.cob_id")
        timer_ms = _int_default(view, f"tpdo{k}_communication.event_timer")
        if cob_id & 0x8000_0000 or timer_ms <= 0:
            continue  # not valid, or not sent periodically
        count = _int_default(view, f"tpdo{k}_mapping.number_of_mapped_objects")
        data_bits = sum(
            _int_default(view, f"tpdo{k}_mapping.mapped_object_{j}") & 0xFF
            for j in range(1, count + 1)
        )
        bits += (47 + 8 * ((data_bits + 7) // 8)) * 1000.0 / timer_ms
    return bits


def _int_default(view: ObjectDictionaryView, name: str) -> int:
    """The EDS default of ``name`` as an integer (TypeError if the EDS gives none)."""
    value = view.entry(name).default
    if value is None:
        raise TypeError(f"{name} has no EDS default")
    return int(value)


def offered_load(n_nodes: int, bitrate: float) -> float:
    """Fraction of ``bitrate`` (bit/s) that ``n_nodes`` drives at the default TPDO rates offer
    (at least; stuff bits add a few per cent)."""
    return n_nodes * default_tpdo_bits_per_s() / float(bitrate)


def overload_warning(n_nodes: int, bitrate: float) -> str | None:
    """One line when ``n_nodes`` drives at the default rates offer ≥ :data:`WARN_LOAD` of
    ``bitrate``, else None."""
    load = offered_load(n_nodes, bitrate)
    if n_nodes < 1 or load < WARN_LOAD:
        return None
    view = load_od(node_id=1)
    timers = ", ".join(
        f"0x{e.index:04X}:{e.subindex:02X}"
        for e in (view.entry(f"tpdo{k}_communication.event_timer") for k in (2, 3))
    )
    return (
        f"warning: {n_nodes} drives at the default TPDO rates offer at least {load:.0%} of "
        f"{bitrate / 1e6:g} Mbit/s; SDO replies (lowest priority) will wait behind TPDOs. "
        f"Lengthen the TPDO2/TPDO3 event timers ({timers}), e.g. to 2 ms"
    )
