"""How the node's OD objects map onto the simulator: measurement sub-indices, modes, windows.

:data:`MEASUREMENTS` is read from the EDS (the ``measurements`` record 0x2040 names its
sub-objects after the simulator's signals, ``docs/contracts.md`` §1), the modes are
:class:`firmware_protocol.enums.ModeOfOperation`: nothing here is a copy of a protocol fact.
"""

from __future__ import annotations

from firmware_protocol.enums import ModeOfOperation
from firmware_protocol.od import ObjectDictionaryView, load_od

__all__ = [
    "CURRENT_WINDOW_A",
    "MEASUREMENTS",
    "MODE_CURRENT",
    "MODE_PROFILE_TORQUE",
    "MODE_PROFILE_VELOCITY",
    "RESET_BRAKE_LIMIT_S",
    "SPEED_ZERO_RPM",
    "SUPPORTED_MODES",
    "int_default",
]

MODE_CURRENT = int(ModeOfOperation.PSEUDO_CURRENT)
"""Manufacturer mode -1: i_p* = setpoints.i_p_ref (A)."""
MODE_PROFILE_VELOCITY = int(ModeOfOperation.PROFILE_VELOCITY)
"""CiA 402 profile velocity (3): the IP speed loop on target_velocity (rpm)."""
MODE_PROFILE_TORQUE = int(ModeOfOperation.PROFILE_TORQUE)
"""CiA 402 profile torque (4): i_p* = target_torque / 1000 * rated current."""
SUPPORTED_MODES: tuple[int, ...] = tuple(int(m) for m in ModeOfOperation)
"""Values 0x6060 accepts (others: abort 0x06090030)."""

MEASUREMENTS: dict[int, str] = {
    e.subindex: e.sub_name
    for e in load_od()
    if e.object_name == "measurements" and e.subindex > 0
}
"""0x2040 sub-index -> simulator signal name (``i_p``, ``i_a``, ..., ``theta_e``)."""

SPEED_ZERO_RPM = 10.0
"""|speed| below this counts as standstill: the end of a stop ramp (rpm)."""
RESET_BRAKE_LIMIT_S = 5.0
"""A deferred reset node completes after this much braking anyway (s, simulated)."""
CURRENT_WINDOW_A = 1.0
"""Target-reached window of the current modes (A)."""


def int_default(view: ObjectDictionaryView, name: str) -> int:
    """The EDS default of the integer object ``name`` (a COB-ID, an identity field; ``$NODEID``
    resolved by the view); TypeError if the EDS gives it no integer default."""
    default = view.entry(name).default
    if isinstance(default, int):
        return default
    raise TypeError(f"{name}: expected an integer default in the EDS, got {default!r}")
