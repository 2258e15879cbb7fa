"""Index ranges of the drive's object dictionary (CiA 301 §7.4.1, CiA 402; this drive's layout).

The one home of "which part of the OD is this index in": the OD reference (``OD.md``) groups
its tables by these ranges, the host decides by them what a configuration (DCF) holds and what
a refused write means, the virtual drive which objects only it has.

>>> 0x2010 in MANUFACTURER, 0x5000 in SIMULATION, 0x1A01 in PDO_PARAMETERS
(True, True, True)
>>> hex(TPDO_MAP + 1)
'0x1a01'
"""

from __future__ import annotations

__all__ = [
    "COMMUNICATION",
    "MANUFACTURER",
    "PDO_PARAMETERS",
    "PROFILE",
    "RANGES",
    "RPDO_COMM",
    "RPDO_MAP",
    "SIMULATION",
    "TPDO_COMM",
    "TPDO_MAP",
]

COMMUNICATION = range(0x1000, 0x2000)
"""CiA 301 communication objects (heartbeat, SDO servers, PDOs, EMCY, store/restore)."""
MANUFACTURER = range(0x2000, 0x5000)
"""Manufacturer objects of the real firmware and the virtual drive."""
SIMULATION = range(0x5000, 0x6000)
"""Virtual-drive-only objects (load, fault injection, inverter, sim info): not on the DSP."""
PROFILE = range(0x6000, 0xA000)
"""CiA 402 drive profile objects."""

RPDO_COMM, RPDO_MAP = 0x1400, 0x1600
"""First RPDO communication / mapping parameter (RPDO k at ``+ k - 1``)."""
TPDO_COMM, TPDO_MAP = 0x1800, 0x1A00
"""First TPDO communication / mapping parameter (TPDO k at ``+ k - 1``)."""
PDO_PARAMETERS = range(RPDO_COMM, 0x1C00)
"""Every PDO communication and mapping parameter (0x1400-0x1BFF)."""

#: (range, title) in OD order: the sections of ``OD.md``.
RANGES: tuple[tuple[range, str], ...] = (
    (COMMUNICATION, "CiA 301 communication objects (0x1000-0x1FFF)"),
    (MANUFACTURER, "Manufacturer objects, real firmware and virtual drive (0x2000-0x4FFF)"),
    (SIMULATION, "Virtual-drive-only objects (0x5000-0x5FFF, not on the real firmware)"),
    (PROFILE, "CiA 402 drive profile objects (0x6000-0x9FFF)"),
)
