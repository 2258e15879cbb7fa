"""The gain set (and nominal motor) of a sweep from a CiA 306 DCF (``drive-link config save``).

A DCF is the drive's EDS with a ``ParameterValue=`` in the section of each configured object
(``[2010sub2]`` for 0x2010:02). It is read here with :mod:`configparser` and the names come
from the object dictionary view of :mod:`firmware_protocol` (the EDS is the source of truth);
``virtual_drive`` never imports ``drive_link``.
"""

from __future__ import annotations

import configparser
import re
from pathlib import Path

from firmware_protocol.enums import CONTROLLER_TYPES
from firmware_protocol.od import load_od
from virtual_drive.sweep.units import SpecError

__all__ = ["DCF_KEYS", "read_gain_set"]

#: OD object -> the sweep's input name
DCF_KEYS: dict[str, str] = {
    "motor.R": "R",
    "motor.L": "L",
    "motor.K_rpm": "K_rpm",
    "motor.pole_pairs": "pole_pairs",
    "current_controller.type": "controller",
    "current_controller.L_c": "L_c",
    "current_controller.R_c": "R_c",
    "current_controller.k_p": "k_p",
    "current_controller.k_i": "k_i",
    "current_controller.emf_feedforward": "emf_feedforward",
    "speed_controller.k_p": "speed_k_p",
    "speed_controller.k_i": "speed_k_i",
    "speed_controller.current_limit": "current_limit",
    "protection.overcurrent_trip": "overcurrent_trip",
    "protection.overvoltage_trip": "overvoltage_trip",
    "protection.undervoltage_trip": "undervoltage_trip",
}

_SECTION = re.compile(r"^([0-9A-Fa-f]{4})(?:sub([0-9A-Fa-f]{1,2}))?$")


def _number(text: str, is_float: bool, where: str) -> float | int:
    s = text.strip().split(";")[0].strip()
    try:
        return float(s) if is_float else int(s, 0)
    except ValueError:
        raise SpecError(f"{where}: ParameterValue {text!r} is not a number") from None


def read_gain_set(path: str | Path) -> dict[str, float | int | str]:
    """Sweep inputs (names of :data:`DCF_KEYS`' values) found in the DCF at ``path``: the
    objects that have a ``ParameterValue``; the controller type as its name."""
    p = Path(path)
    cp = configparser.RawConfigParser(strict=False, interpolation=None)
    # (case-kept keys: the configparser idiom, which typeshed's method declaration rejects)
    cp.optionxform = str  # type: ignore[assignment,method-assign]
    try:
        with p.open(encoding="utf-8") as fh:
            cp.read_file(fh)
    except (OSError, configparser.Error, UnicodeDecodeError) as exc:
        raise SpecError(f"gains.dcf: cannot read {str(p)!r}: {exc}") from None
    od = load_od()
    out: dict[str, float | int | str] = {}
    for sec in cp.sections():
        m = _SECTION.match(sec)
        if not m or not cp.has_option(sec, "ParameterValue"):
            continue
        index, sub = int(m.group(1), 16), int(m.group(2) or "0", 16)
        try:
            entry = od.by_index(index, sub)
        except KeyError:
            continue
        key = DCF_KEYS.get(entry.name)
        if key is None:
            continue
        is_float = entry.is_real
        value = _number(cp.get(sec, "ParameterValue"), is_float, f"gains.dcf {entry.name}")
        if key == "controller":
            names = {v: k for k, v in CONTROLLER_TYPES.items()}
            if value not in names:
                raise SpecError(f"gains.dcf current_controller.type: unknown type {value!r}")
            out[key] = names[int(value)]
        else:
            out[key] = value
    if not any(k in out for k in ("L_c", "speed_k_p")):
        raise SpecError(f"gains.dcf: {str(p)!r} has no controller gains (ParameterValue)")
    return out
