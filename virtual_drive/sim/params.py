"""Parameter dataclasses of the virtual drive, validated on construction.

Every field is SI unless stated; defaults are the paper's Table 2 motor and its identified
speed model.  A non-finite or non-physical value raises ``ValueError`` naming the field, e.g.
``ValueError: MotorParams.L must be > 0 (H), got -1e-06``.

Mechanics from the identified model (Valle et al. 2020, eq. 26).  With the current loop
ideal, the shaft obeys J dw/dt = K_t i_p - B_tot w (w in rad/s), whose zero-order-hold
discretisation at Ts, with the speed n in rpm, is n[k+1] = a n[k] + b i_p[k] with

    a = exp(-B_tot Ts / J),    b = (1 - a) K_t (60 / 2 pi) / B_tot.

Hence, from a, b and the torque constant K_t = K_rpm (60 / 2 pi) (N m/A, since the
line-to-line back-EMF at the flat tops is K_rpm n and T_e = e_L i_p / w):

    B_tot = (1 - a) K_t (60 / 2 pi) / b,    J = B_tot Ts / (-ln a).

With b = 3.33715e-4 rpm/A per sample and a = 0.9999785 (the value the paper's IP gains imply;
the printed 0.99997 is rounded): K_t = 0.119366 N m/A, B_tot = 0.07345 N m s/rad, J = 0.0683
kg m^2 (mechanical time constant J / B_tot = 0.93 s).  The paper's bench load is a DC
generator, whose torque grows with speed; B_tot is split into shaft friction B (10 %) and the
generator's k_gen (90 %, in N m/rpm: T_gen = k_gen n).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

from firmware_protocol import paper
from firmware_protocol.enums import CONTROLLER_TYPES
from firmware_protocol.od import load_od

__all__ = [
    "A_IDENTIFIED",
    "B_IDENTIFIED",
    "OD_LIMITS",
    "RPM_PER_RAD_S",
    "CurrentControllerParams",
    "InverterParams",
    "LoadParams",
    "MotorParams",
    "ProtectionParams",
    "SpeedControllerParams",
    "Ts",
    "field_names",
    "mechanics_from_identified",
]

Ts: float = paper.TS
"""Sampling period (s): fs = 50 kHz, equal to the PWM period."""

RPM_PER_RAD_S: float = 60.0 / (2.0 * math.pi)

A_IDENTIFIED: float = paper.A_IDENTIFIED
"""Identified speed-model pole a (1), eq. (26), as implied by the paper's IP gains."""
B_IDENTIFIED: float = paper.B_IDENTIFIED
"""Identified speed-model gain b (rpm/A per sample), eq. (26)."""


def _check(
    owner: str,
    name: str,
    value: float,
    *,
    lo: float | None = None,
    hi: float | None = None,
    lo_open: bool = False,
    hi_open: bool = False,
    unit: str = "",
) -> float:
    """Return ``float(value)`` or raise ValueError naming ``owner.name``."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{owner}.{name} must be a number, got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{owner}.{name} must be finite, got {value!r}")
    u = f" ({unit})" if unit else ""
    if lo is not None and (v <= lo if lo_open else v < lo):
        raise ValueError(f"{owner}.{name} must be {'>' if lo_open else '>='} {lo}{u}, got {v}")
    if hi is not None and (v >= hi if hi_open else v > hi):
        raise ValueError(f"{owner}.{name} must be {'<' if hi_open else '<='} {hi}{u}, got {v}")
    return v


OD_LIMITS: dict[str, str] = {
    **{f"MotorParams.{k}": f"motor.{k}" for k in ("R", "L", "K_rpm", "pole_pairs")},
    "MotorParams.rated_current": "motor.rated_current",
    "MotorParams.V_dc_nominal": "motor.V_dc_nominal",
    **{f"LoadParams.{k}": f"sim_load.{k}" for k in ("T_load", "k_gen", "J", "B")},
    **{f"InverterParams.{k}": f"sim_inverter.{k}" for k in ("T_BT", "T_DD", "T_SD", "V_G")},
    **{
        f"CurrentControllerParams.{k}": f"current_controller.{k}"
        for k in ("L_c", "R_c", "k_p", "k_i", "T_BT", "T_DD", "T_SD", "V_G")
    },
    **{f"SpeedControllerParams.{k}": f"speed_controller.{k}" for k in ("k_p", "k_i")},
    "SpeedControllerParams.current_limit": "speed_controller.current_limit",
    **{
        f"ProtectionParams.{k}": f"protection.{k}"
        for k in ("overcurrent_trip", "overvoltage_trip", "undervoltage_trip")
    },
}
"""``Class.field`` -> the OD object whose EDS ``LowLimit``/``HighLimit`` (inclusive) bound it.

These limits are read from the EDS (:func:`firmware_protocol.load_od`), never copied, so the
simulator accepts exactly what the drive's object accepts (``MinNonZero`` excepted: the C
controllers must survive any value the OD path could not give them). Physics may narrow a
range further (``T_DD + T_SD < Ts/2``, which the EDS cannot express); that is stated at the
check."""


def _od_check(owner: str, name: str, value: float) -> float:
    """:func:`_check` with the EDS limits and unit of the object ``OD_LIMITS[owner.name]``."""
    entry = load_od().entry(OD_LIMITS[f"{owner}.{name}"])
    lo = None if entry.low is None else float(entry.low)
    hi = None if entry.high is None else float(entry.high)
    unit = entry.unit if entry.unit not in (None, "1") else ""
    return _check(owner, name, value, lo=lo, hi=hi, unit=unit or "")


def mechanics_from_identified(
    a: float, b: float, K_t: float, Ts: float = Ts
) -> tuple[float, float]:
    """(J in kg m^2, B_tot in N m s/rad) reproducing n[k+1] = a n[k] + b i_p[k] (rpm, A)."""
    B_tot = (1.0 - a) * K_t * RPM_PER_RAD_S / b
    J = B_tot * Ts / (-math.log(a))
    return J, B_tot


@dataclass
class MotorParams:
    """BLDC motor, Table 2.  R, L per phase; K_rpm line-to-line back-EMF constant."""

    R: float = paper.R_TABLE2
    """Phase resistance (Ohm), > 0."""
    L: float = paper.L_TABLE2
    """Phase inductance (H), > 0."""
    K_rpm: float = paper.K_RPM
    """Line-to-line back-EMF at the flat tops per speed (V/rpm), > 0."""
    pole_pairs: int = paper.POLE_PAIRS
    """Pole pairs (8 poles)."""
    rated_current: float = paper.RATED_CURRENT
    """Rated current (A)."""
    V_dc_nominal: float = paper.RATED_VOLTAGE
    """Rated DC-link voltage (V)."""
    emf_rounding: float = math.radians(15.0)
    """Width over which each trapezoid corner is rounded (rad electrical), [0, pi/3];
    0 is the ideal trapezoid of Fig. 2 (fringing effect, Sec. IV-B)."""

    def __post_init__(self) -> None:
        o = "MotorParams"
        self.R = _od_check(o, "R", self.R)
        self.L = _od_check(o, "L", self.L)
        self.K_rpm = _od_check(o, "K_rpm", self.K_rpm)
        pp = _od_check(o, "pole_pairs", self.pole_pairs)
        if pp != int(pp):
            raise ValueError(f"{o}.pole_pairs must be an integer, got {self.pole_pairs!r}")
        self.pole_pairs = int(pp)
        self.rated_current = _od_check(o, "rated_current", self.rated_current)
        self.V_dc_nominal = _od_check(o, "V_dc_nominal", self.V_dc_nominal)
        self.emf_rounding = _check(
            o, "emf_rounding", self.emf_rounding, lo=0.0, hi=math.pi / 3.0, unit="rad"
        )

    @property
    def K_t(self) -> float:
        """Torque constant (N m/A) for i_p: K_rpm * 60 / (2 pi)."""
        return self.K_rpm * RPM_PER_RAD_S

    @property
    def k_e(self) -> float:
        """Per-phase back-EMF constant (V s/rad mechanical): K_t / 2."""
        return 0.5 * self.K_t


_J_DEF, _BTOT_DEF = mechanics_from_identified(
    A_IDENTIFIED, B_IDENTIFIED, paper.K_RPM * RPM_PER_RAD_S
)


@dataclass
class LoadParams:
    """Shaft and load: J dw/dt = T_e - B w - k_gen n - T_load (w rad/s, n rpm)."""

    T_load: float = 0.0
    """Constant load torque (N m), positive opposes positive rotation; a change is a load step."""
    k_gen: float = 0.9 * _BTOT_DEF / RPM_PER_RAD_S
    """DC-generator load (N m/rpm): T_gen = k_gen n, >= 0."""
    J: float = _J_DEF
    """Rotor + load inertia (kg m^2), > 0."""
    B: float = 0.1 * _BTOT_DEF
    """Viscous friction (N m s/rad), >= 0."""

    def __post_init__(self) -> None:
        o = "LoadParams"
        self.T_load = _od_check(o, "T_load", self.T_load)
        self.k_gen = _od_check(o, "k_gen", self.k_gen)
        self.J = _od_check(o, "J", self.J)
        self.B = _od_check(o, "B", self.B)

    @property
    def B_tot(self) -> float:
        """Total speed-proportional torque coefficient (N m s/rad): B + k_gen * 60/(2 pi)."""
        return self.B + self.k_gen * RPM_PER_RAD_S


@dataclass
class InverterParams:
    """Two-level bridge: DC supply and the real non-idealities of eq. (25)."""

    V_dc: float = paper.RATED_VOLTAGE
    """DC supply voltage (V), > 0."""
    T_BT: float = 0.0
    """Blanking (dead) time before each switch turn-on (s), [0, Ts/4]."""
    T_DD: float = 0.0
    """Gate-driver delay of the pulse pattern (s), >= 0, T_DD + T_SD < Ts/2."""
    T_SD: float = 0.0
    """Sampling delay relative to the pattern (s), >= 0."""
    V_G: float = 0.0
    """Switch and diode forward drop (V), [0, 5]."""

    def __post_init__(self) -> None:
        o = "InverterParams"
        self.V_dc = _check(o, "V_dc", self.V_dc, lo=0.0, lo_open=True, hi=1000.0, unit="V")
        for n in ("T_BT", "T_DD", "T_SD"):
            setattr(self, n, _od_check(o, n, getattr(self, n)))
        # physics the EDS limits cannot say: the delayed, sampled pattern inside half a period
        # (T_BT <= Ts/4 is the object's HighLimit)
        self.T_DD = _check(o, "T_DD", self.T_DD, hi=Ts / 2.0, hi_open=True, unit="s")
        self.T_SD = _check(o, "T_SD", self.T_SD, hi=Ts / 2.0, hi_open=True, unit="s")
        if self.T_DD + self.T_SD >= Ts / 2.0:
            raise ValueError(
                f"InverterParams.T_SD: T_DD + T_SD must be < {Ts / 2.0} s, "
                f"got {self.T_DD + self.T_SD}"
            )
        self.V_G = _od_check(o, "V_G", self.V_G)


@dataclass
class CurrentControllerParams:
    """Current controller (OD 0x2010): deadbeat eq. (15), PI eq. (22), predictive eq. (23)/(25)."""

    type: str = "deadbeat"
    """"deadbeat" | "pi" | "predictive" (or 0 / 1 / 2)."""
    L_c: float = paper.L_TABLE2
    """Inductance estimate (H), > 0 (the loop is stable for L_c < 2 L)."""
    R_c: float = paper.R_TABLE2
    """Resistance estimate (Ohm), >= 0."""
    k_p: float = paper.PI_KP
    """PI proportional gain k_p,i (V/A)."""
    k_i: float = paper.PI_KI
    """PI integral gain k_i,i (V/A per sample)."""
    T_BT: float = 0.0
    """Blanking-time estimate for eq. (25) (s), >= 0."""
    T_DD: float = 0.0
    """Driver-delay estimate for eq. (25) (s), >= 0."""
    T_SD: float = 0.0
    """Sampling-delay estimate for eq. (25) (s), >= 0."""
    V_G: float = 0.0
    """Switch-drop estimate for eq. (25) (V), >= 0."""
    emf_feedforward: bool = False
    """Add the back-EMF estimate e_L (2 e_L for eq. 23) to the output."""

    def __post_init__(self) -> None:
        o = "CurrentControllerParams"
        t = self.type
        if isinstance(t, bool) or not isinstance(t, (str, int)):
            raise ValueError(f"{o}.type must be one of {list(CONTROLLER_TYPES)}, got {t!r}")
        if isinstance(t, int):
            names = {v: k for k, v in CONTROLLER_TYPES.items()}
            if t not in names:
                raise ValueError(f"{o}.type must be 0, 1 or 2, got {t!r}")
            t = names[t]
        if t not in CONTROLLER_TYPES:
            raise ValueError(f"{o}.type must be one of {list(CONTROLLER_TYPES)}, got {t!r}")
        self.type = t
        for n in ("L_c", "R_c", "k_p", "k_i", "T_BT", "T_DD", "T_SD", "V_G"):
            setattr(self, n, _od_check(o, n, getattr(self, n)))
        if not isinstance(self.emf_feedforward, (bool, int)) or self.emf_feedforward not in (
            0,
            1,
            True,
            False,
        ):
            raise ValueError(f"{o}.emf_feedforward must be a bool, got {self.emf_feedforward!r}")
        self.emf_feedforward = bool(self.emf_feedforward)

    @property
    def type_code(self) -> int:
        """OD code of ``type``: 0 deadbeat, 1 PI, 2 predictive."""
        return CONTROLLER_TYPES[self.type]


@dataclass
class SpeedControllerParams:
    """IP speed controller (OD 0x2020), Fig. 17 / eq. (27)."""

    k_p: float = paper.IP_KP
    """Proportional gain (A/rpm)."""
    k_i: float = paper.IP_KI
    """Integral gain (1/sample)."""
    current_limit: float = 100.0
    """Limit on |i_p*| (A), [0, 200]."""

    def __post_init__(self) -> None:
        o = "SpeedControllerParams"
        for n in ("k_p", "k_i", "current_limit"):
            setattr(self, n, _od_check(o, n, getattr(self, n)))


@dataclass
class ProtectionParams:
    """Trip limits (OD 0x2050)."""

    overcurrent_trip: float = 300.0
    """Instantaneous phase-current trip (A), > 0."""
    overvoltage_trip: float = 60.0
    """DC-link overvoltage trip (V)."""
    undervoltage_trip: float = 36.0
    """DC-link undervoltage trip (V), < overvoltage_trip."""

    def __post_init__(self) -> None:
        o = "ProtectionParams"
        for n in ("overcurrent_trip", "overvoltage_trip", "undervoltage_trip"):
            setattr(self, n, _od_check(o, n, getattr(self, n)))
        if self.undervoltage_trip >= self.overvoltage_trip:
            raise ValueError(
                f"{o}.undervoltage_trip must be < overvoltage_trip ({self.overvoltage_trip} V), "
                f"got {self.undervoltage_trip}"
            )


def field_names(cls: type) -> list[str]:
    """Names of a params dataclass's fields."""
    return [f.name for f in fields(cls)]
