"""Bridge between OD objects and the simulation core (``virtual_drive.sim``, contracts §2).

Maps writes of 0x2000 motor, 0x2010 current controller, 0x2020 speed controller, 0x2050
protection, 0x5000 sim_load, 0x5010 sim_fault and 0x5020 sim_inverter onto the simulator's
validated setters, and reports which objects the simulator cannot take (abort 0x06090030).
All calls happen with the node's simulator lock held, i.e. between two simulation chunks.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from firmware_protocol.od import load_od

_OD = load_od()  # where the objects are: the EDS, through firmware_protocol's view
MOTOR_INDEX = _OD.index_of("motor")
CURRENT_CONTROLLER_INDEX = _OD.index_of("current_controller")
SPEED_CONTROLLER_INDEX = _OD.index_of("speed_controller")
PROTECTION_INDEX = _OD.index_of("protection")
SIM_LOAD_INDEX = _OD.index_of("sim_load")
SIM_INVERTER_INDEX = _OD.index_of("sim_inverter")


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

# {sub: keyword} of each record: the EDS names the sub-objects after the simulator's keywords
# (docs/contracts.md §1/§2), so the maps are read from it
CURRENT_KW = _OD.sub_names("current_controller")
SPEED_KW = _OD.sub_names("speed_controller")
MOTOR_KW = _OD.sub_names("motor")
PROTECTION_KW = _OD.sub_names("protection")
LOAD_KW = _OD.sub_names("sim_load")
INVERTER_KW = _OD.sub_names("sim_inverter")
#: staged speed gains: gain_set sub -> set_speed_gains keyword (``speed_k_p`` -> ``k_p``)
GAIN_SET_SPEED_KW = {
    sub: name.removeprefix("speed_")
    for sub, name in _OD.sub_names("gain_set").items()
    if name.startswith("speed_")
}

#: OD record index → (simulator setter, {sub: keyword})
SETTERS: dict[int, tuple[str, Mapping[int, str]]] = {
    MOTOR_INDEX: ("set_motor", MOTOR_KW),
    CURRENT_CONTROLLER_INDEX: ("set_current_gains", CURRENT_KW),
    SPEED_CONTROLLER_INDEX: ("set_speed_gains", SPEED_KW),
    PROTECTION_INDEX: ("set_protection", PROTECTION_KW),
    SIM_LOAD_INDEX: ("set_load", LOAD_KW),
    SIM_INVERTER_INDEX: ("set_inverter_nonidealities", INVERTER_KW),
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
