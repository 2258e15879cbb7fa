"""Bridge between OD objects and the simulation core (``virtual_drive.sim``, contracts §2).

Maps writes of 0x2000 motor, 0x2010 current controller, 0x2020 speed controller, 0x2050
protection, 0x5000 sim_load, 0x5010 sim_fault and 0x5020 sim_inverter onto the simulator's
validated setters, and reports which objects the simulator cannot take (abort 0x06090030).
All calls happen with the node's simulator lock held, i.e. between two simulation chunks.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

__all__ = [
    "CURRENT_KW",
    "GAIN_SET_SPEED_KW",
    "INVERTER_KW",
    "LOAD_KW",
    "MOTOR_KW",
    "PROTECTION_KW",
    "SETTERS",
    "SPEED_KW",
    "PlantError",
    "apply",
]

#: OD record index → (simulator setter, {sub: keyword})
CURRENT_KW = {
    1: "type",
    2: "L_c",
    3: "R_c",
    4: "k_p",
    5: "k_i",
    6: "T_BT",
    7: "T_DD",
    8: "T_SD",
    9: "V_G",
    10: "emf_feedforward",
}
SPEED_KW = {1: "k_p", 2: "k_i", 3: "current_limit"}
MOTOR_KW = {1: "R", 2: "L", 3: "K_rpm", 4: "pole_pairs", 5: "rated_current", 6: "V_dc_nominal"}
PROTECTION_KW = {1: "overcurrent_trip", 2: "overvoltage_trip", 3: "undervoltage_trip"}
LOAD_KW = {1: "T_load", 2: "k_gen", 3: "J", 4: "B"}
INVERTER_KW = {1: "T_BT", 2: "T_DD", 3: "T_SD", 4: "V_G"}
GAIN_SET_SPEED_KW = {11: "k_p", 12: "k_i", 13: "current_limit"}

SETTERS: dict[int, tuple[str, Mapping[int, str]]] = {
    0x2000: ("set_motor", MOTOR_KW),
    0x2010: ("set_current_gains", CURRENT_KW),
    0x2020: ("set_speed_gains", SPEED_KW),
    0x2050: ("set_protection", PROTECTION_KW),
    0x5000: ("set_load", LOAD_KW),
    0x5020: ("set_inverter_nonidealities", INVERTER_KW),
}


class PlantError(ValueError):
    """The simulator refused a value (becomes SDO abort 0x06090030)."""


def apply(sim: Any, index: int, subindex: int, value: float | int) -> bool:
    """Apply one OD write to the simulator. Returns False if the object is not a plant object.

    :raises PlantError: the simulator refused the value (nothing changed).
    """
    spec = SETTERS.get(index)
    if spec is None:
        return False
    name, kw = spec
    key = kw.get(subindex)
    if key is None:
        return False
    setter = getattr(sim, name, None)
    if setter is None:
        raise PlantError(f"the simulator has no {name}()")
    try:
        setter(**{key: value})
    except (ValueError, TypeError) as exc:
        raise PlantError(str(exc)) from exc
    return True
