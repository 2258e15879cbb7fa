"""Constants of the paper and input checks shared by the design modules (pure Python).

Valle et al., IEEE Access 2020: Table 2's motor R, L, the PI gains of Section IV-B, the 50 kHz
sampling rate; the controller names of the current loop.
"""

from __future__ import annotations

import math
from typing import Literal, get_args

import numpy as np

from firmware_protocol import paper
from firmware_protocol.enums import CONTROLLER_TYPES

__all__ = [
    "CONTROLLERS",
    "FS_DEFAULT",
    "L_TABLE2",
    "PI_KI_PAPER",
    "PI_KP_PAPER",
    "R_TABLE2",
    "ControllerName",
    "controller_name",
]

FS_DEFAULT = paper.FS
"""Default sampling (and PWM) frequency [Hz]; Ts = 20 µs."""

R_TABLE2 = paper.R_TABLE2
"""Motor phase resistance of Table 2 [Ω]."""

L_TABLE2 = paper.L_TABLE2
"""Motor phase inductance of Table 2 [H]."""

PI_KP_PAPER = paper.PI_KP
"""The paper's PI current gain k_p,i [V/A] (Section IV-B)."""

PI_KI_PAPER = paper.PI_KI
"""The paper's PI current gain k_i,i [V/A per sample] (Section IV-B)."""

ControllerName = Literal["deadbeat", "pi", "predictive"]
"""Host name of a current-controller law (0x2010:1 type 0, 1, 2)."""
CONTROLLERS: tuple[ControllerName, ...] = tuple(
    n for n in get_args(ControllerName) if n in CONTROLLER_TYPES
)
"""The names by code (the EDS enumeration's order: ``CONTROLLERS[code]``)."""
if CONTROLLERS != tuple(sorted(CONTROLLER_TYPES, key=CONTROLLER_TYPES.__getitem__)):
    raise ImportError(f"ControllerName {CONTROLLERS} disagrees with the EDS {CONTROLLER_TYPES}")


def controller_name(code: int) -> ControllerName:
    """The law of 0x2010:1 ``code`` (0 deadbeat, 1 PI, 2 predictive); ValueError otherwise."""
    if not 0 <= int(code) < len(CONTROLLERS):
        raise ValueError(f"controller type {code} is not 0..{len(CONTROLLERS) - 1}")
    return CONTROLLERS[int(code)]


# --------------------------------------------------------------------------- input checks
def _positive(name: str, value: float) -> float:
    v = float(value)
    if not math.isfinite(v) or v <= 0.0:
        raise ValueError(f"{name} must be a finite number > 0 (got {value!r})")
    return v


def _non_negative(name: str, value: float) -> float:
    v = float(value)
    if not math.isfinite(v) or v < 0.0:
        raise ValueError(f"{name} must be a finite number >= 0 (got {value!r})")
    return v


def _finite(name: str, value: float) -> float:
    v = float(value)
    if not math.isfinite(v):
        raise ValueError(f"{name} must be a finite number (got {value!r})")
    return v


def _as_f32(x: float) -> float:
    return float(np.float32(x))
