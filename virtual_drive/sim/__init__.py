"""Simulation core of the virtual drive (contracts.md section 2).

BLDC motor with rounded trapezoidal back-EMF, unipolar-PWM full-bridge inverter with
freewheel diodes, DC-generator load, and the paper's controllers in portable C, run in
chunks by a cffi extension (``virtual_drive._core``).
"""

from virtual_drive.sim.params import (
    CurrentControllerParams,
    InverterParams,
    LoadParams,
    MotorParams,
    ProtectionParams,
    SpeedControllerParams,
)
from virtual_drive.sim.signals import SIGNALS, UNITS
from virtual_drive.sim.simulator import FAULT_KINDS, Fault, Simulator

__all__ = [
    "FAULT_KINDS",
    "SIGNALS",
    "UNITS",
    "CurrentControllerParams",
    "Fault",
    "InverterParams",
    "LoadParams",
    "MotorParams",
    "ProtectionParams",
    "Simulator",
    "SpeedControllerParams",
]
