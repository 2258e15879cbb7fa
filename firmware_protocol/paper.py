"""The paper's numbers: the Table 2 motor, the sampling, the identified speed model and the gains.

Valle et al., "Simple and Effective Digital Control of a Variable-Speed Low Inductance BLDC Motor
Drive", IEEE Access 8 (2020), doi:10.1109/ACCESS.2020.2966437: the design
the drive implements (``docs/contracts.md``, ``overview.md``). This is the one home of these
constants: the EDS defaults of ``motor.*``, ``current_controller.*`` and ``speed_controller.*``
equal them (a test pins it), the simulator, the design maths and the dashboard import them.

Symbols and units follow the paper: R (Ohm), L (H) per phase, K_rpm (V/rpm), Ts (s), the speed
model G(z) = w(z) / I_p(z) = b / (z - a) of eq. (26) with w in rpm, i_p in A, one step per Ts.
"""

from __future__ import annotations

__all__ = [
    "A_IDENTIFIED",
    "B_IDENTIFIED",
    "FS",
    "IP_KI",
    "IP_KP",
    "IP_OMEGA_N",
    "IP_XI",
    "K_RPM",
    "L_TABLE2",
    "MAX_EFFICIENCY",
    "MAX_TORQUE",
    "PI_KI",
    "PI_KP",
    "POLES",
    "POLE_PAIRS",
    "RATED_CURRENT",
    "RATED_POWER",
    "RATED_SPEED",
    "RATED_VOLTAGE",
    "R_TABLE2",
    "SPEED_MODEL",
    "TS",
]

# -- Table 2, BLDC motor characteristics -----------------------------------------------------
RATED_POWER: float = 5e3
"""Rated power (W)."""
RATED_VOLTAGE: float = 48.0
"""Rated (DC-link) voltage (V)."""
RATED_CURRENT: float = 100.0
"""Rated current (A)."""
MAX_EFFICIENCY: float = 0.891
"""Maximum efficiency (1): 89.1 %."""
R_TABLE2: float = 6.2e-3
"""Resistance per phase R (Ohm): 6.2 mOhm."""
L_TABLE2: float = 14.8e-6
"""Inductance per phase L (H): 14.8 uH."""
K_RPM: float = 0.0125
"""Back-EMF constant K_rpm (V/rpm): line-to-line back-EMF at the flat tops per speed."""
POLES: int = 8
"""Number of poles (1)."""
POLE_PAIRS: int = POLES // 2
"""Pole pairs (1)."""
MAX_TORQUE: float = 13.92
"""Maximum torque (N m)."""
RATED_SPEED: float = 3532.0
"""Rated speed (rpm)."""

# -- sampling -------------------------------------------------------------------------------
FS: float = 50e3
"""Sampling frequency f_s (Hz), equal to the PWM frequency of each leg (Sec. IV-B)."""
TS: float = 1.0 / FS
"""Sampling period T_s (s): 20 us."""

# -- identified speed model, eq. (26) ---------------------------------------------------------
A_IDENTIFIED: float = 0.9999785
"""Speed-model pole a (1 per sample). The paper prints 0.99997 (rounded); its IP gains
k_p = 0.2113, k_i = 2.9994e-5 follow from a = 0.9999785 (``overview.md``)."""
B_IDENTIFIED: float = 3.33715e-4
"""Speed-model gain b (rpm/A per sample)."""
SPEED_MODEL: tuple[float, float] = (A_IDENTIFIED, B_IDENTIFIED)
"""(a, b) of G(z) = b / (z - a)."""

# -- gains of the paper ---------------------------------------------------------------------
PI_KP: float = 0.4647
"""Current PI proportional gain k_p,i (V/A), eq. (22): GM 9.14 dB, PM 45.6 deg."""
PI_KI: float = 0.0492
"""Current PI integral gain k_i,i (V/A per sample), eq. (22)."""
IP_XI: float = 1.0
"""IP speed-loop damping ratio xi (1), eqs. (28)-(31)."""
IP_OMEGA_N: float = 2.3
"""IP speed-loop natural frequency omega_n (rad/s)."""
IP_KP: float = 0.2113
"""IP speed proportional gain k_p (A/rpm)."""
IP_KI: float = 2.9994e-5
"""IP speed integral gain k_i (1/sample)."""
