"""The inputs of one sweep run: the motor, supply, load and gain set the simulator is built from.

Every input has a name, an SI unit (the object dictionary's) and a nominal value: the paper's
Table 2 motor and gains (``virtual_drive.sim.params`` defaults), replaced by a DCF's values
and by the spec's ``[gains]`` / ``[motor]`` tables. A sweep parameter moves one input (or the
ratios ``L_c/L``, ``R_c/R``, which set L_c, R_c relative to the run's own L, R).

Mechanics: J (kg m^2) and B (N m s/rad) are the shaft's inertia and viscous friction, k_gen
(N m/rpm) the bench's DC-generator load, T_load (N m) a constant load torque. k_e (V s/rad,
per phase) is an alternative to K_rpm (V/rpm line to line): K_rpm = 2 k_e (2 pi / 60).
"""

from __future__ import annotations

from typing import Any

from virtual_drive.sim.params import (
    RPM_PER_RAD_S,
    CurrentControllerParams,
    InverterParams,
    LoadParams,
    MotorParams,
    ProtectionParams,
    SpeedControllerParams,
)

__all__ = ["INPUTS", "RATIOS", "derived_k_e", "nominal_inputs"]

#: input name -> (SI unit for pint, description)
INPUTS: dict[str, tuple[str, str]] = {
    "R": ("ohm", "motor phase resistance"),
    "L": ("H", "motor phase inductance"),
    "K_rpm": ("V/rpm", "line-to-line back-EMF constant"),
    "k_e": ("V*s/rad", "per-phase back-EMF constant (alternative to K_rpm)"),
    "pole_pairs": ("dimensionless", "pole pairs"),
    "J": ("kg*m**2", "rotor + load inertia"),
    "B": ("N*m*s/rad", "viscous friction"),
    "k_gen": ("N*m/rpm", "DC-generator load"),
    "T_load": ("N*m", "constant load torque"),
    "V_dc": ("V", "DC-link voltage"),
    "controller": ("", "current controller type: deadbeat, pi, predictive"),
    "L_c": ("H", "inductance estimate of the current controller"),
    "R_c": ("ohm", "resistance estimate of the current controller"),
    "k_p": ("V/A", "current PI proportional gain"),
    "k_i": ("V/A", "current PI integral gain (per sample)"),
    "emf_feedforward": ("dimensionless", "back-EMF feed-forward 0/1"),
    "speed_k_p": ("A/rpm", "IP speed controller k_p"),
    "speed_k_i": ("dimensionless", "IP speed controller k_i (1/sample)"),
    "current_limit": ("A", "speed controller output limit"),
    "overcurrent_trip": ("A", "protection: phase-current trip"),
    "overvoltage_trip": ("V", "protection: DC-link overvoltage trip"),
    "undervoltage_trip": ("V", "protection: DC-link undervoltage trip"),
}

#: ratio parameter -> (estimate, motor value)
RATIOS: dict[str, tuple[str, str]] = {"L_c/L": ("L_c", "L"), "R_c/R": ("R_c", "R")}


def nominal_inputs() -> dict[str, Any]:
    """The defaults: Table 2 motor at 48 V, the paper's gains, the simulator's load."""
    m, ld, c = MotorParams(), LoadParams(), CurrentControllerParams()
    s, pr, inv = SpeedControllerParams(), ProtectionParams(), InverterParams()
    return {
        "R": m.R,
        "L": m.L,
        "K_rpm": m.K_rpm,
        "pole_pairs": m.pole_pairs,
        "J": ld.J,
        "B": ld.B,
        "k_gen": ld.k_gen,
        "T_load": ld.T_load,
        "V_dc": inv.V_dc,
        "controller": c.type,
        "L_c": c.L_c,
        "R_c": c.R_c,
        "k_p": c.k_p,
        "k_i": c.k_i,
        "emf_feedforward": int(c.emf_feedforward),
        "speed_k_p": s.k_p,
        "speed_k_i": s.k_i,
        "current_limit": s.current_limit,
        "overcurrent_trip": pr.overcurrent_trip,
        "overvoltage_trip": pr.overvoltage_trip,
        "undervoltage_trip": pr.undervoltage_trip,
    }


def derived_k_e(K_rpm: float) -> float:
    """Per-phase k_e (V s/rad) of a line-to-line K_rpm (V/rpm)."""
    return 0.5 * K_rpm * RPM_PER_RAD_S


def k_rpm_of(k_e: float) -> float:
    """K_rpm (V/rpm) of a per-phase k_e (V s/rad)."""
    return 2.0 * k_e / RPM_PER_RAD_S
