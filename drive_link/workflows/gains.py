"""One path for a gain change: read once (what the caller does not hold), check, stage, apply,
read back.

``drive-link set-gains`` and the dashboard (REST and GUI) call :func:`apply_gains` and nothing
else, so both follow one policy:

* **refused, always** (even with ``force``): a set the drive's own rule refuses
  (:mod:`firmware_protocol.current_stability`: current-loop poles inside the circle and not too
  slow, the back-EMF feed-forward where a law has no integral action, eq. 25's compensation
  bounded, the speed loop stable around the closed current loop;
  :func:`firmware_protocol.stability.check_ip_speed_gains` on the speed model: an IP pair stable
  and damped), and a closed current or speed loop with a pole on or outside the unit circle
  (:mod:`drive_link.workflows.design`). An unstable set is never applied.
* **refused unless forced** (``force=True`` applies it, with the warnings returned): poor
  margins of a stable current loop — L_c > 1.5 L (deadbeat, predictive), gain margin < 2 dB,
  ‖S‖∞ > 5.

Applying stages the whole set (current loop, speed loop or both: the ones with a changed value)
in gain_set (0x20F0) and applies it with gain_set_apply (0x20F1)
(:func:`drive_link.link._gain_set.stage_and_apply`), so the drive changes all values at once or
none. A caller that holds the present set and the motor (the dashboard) passes them and no read
precedes the write. This is the one public way to change gains: ``Drive.write`` of a gain object
comes here too.

Units: L_c H, R_c Ω, current PI k_p/k_i V/A, T_BT/T_DD/T_SD s, V_G V, speed k_p A/rpm, speed
k_i 1/sample, speed_current_limit A; motor R Ω, L H, rated_current A, V_dc_nominal V.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from firmware_protocol import load_od
from firmware_protocol.current_stability import (
    CURRENT_KEYS,
    MOTOR_KEYS,
    check_cascade,
    check_current_gains,
)
from firmware_protocol.entry import LimitError
from firmware_protocol.stability import A_IDENTIFIED, B_IDENTIFIED, check_ip_speed_gains

from ..errors import InvalidValue
from ..link._gain_set import GAIN_FIELDS, GainSetDrive, stage_and_apply
from . import design

__all__ = [
    "GAIN_MARGIN_MIN_DB",
    "L_C_MAX_RATIO",
    "SENSITIVITY_PEAK_MAX",
    "GainCheck",
    "GainResult",
    "GainsRefused",
    "apply_gains",
    "check_gains",
    "read_motor",
]

L_C_MAX_RATIO = 1.5
"""Largest L_c / L applied without ``force`` (Table 1's last row; deadbeat and predictive)."""
GAIN_MARGIN_MIN_DB = 2.0
"""Smallest current-loop gain margin applied without ``force`` [dB]."""
SENSITIVITY_PEAK_MAX = 5.0
"""Largest current-loop sensitivity peak ‖S‖∞ applied without ``force``."""

_EDS_DEFAULTS = load_od().defaults()
#: Motor values used when a caller gives none: the EDS defaults (Table 2), read from the EDS.
_MOTOR_DEFAULTS = {k: float(_EDS_DEFAULTS[f"motor.{k}"]) for k in ("rated_current", "V_dc_nominal")}
#: Current-set entries a caller may leave out of an offline check: the drive's (EDS) defaults.
_CURRENT_DEFAULTS = {
    k: _EDS_DEFAULTS[f"current_controller.{k}"]
    for k in ("T_BT", "T_DD", "T_SD", "V_G", "emf_feedforward")
}


@dataclass(frozen=True)
class GainCheck:
    """The verdict on one full gain set.

    ``refusals``: reasons the set is never applied (unstable, or the drive's rule refuses it);
    ``warnings``: poor margins, applied only with ``force``; ``figures``: controller, L_c/L,
    current_loop_stable, current_max_pole_radius, gain_margin_db, phase_margin_deg (the
    smallest, a positive angle), crossovers, sensitivity_peak, speed_loop_stable,
    speed_max_pole_radius, speed_model (a, b).
    """

    refusals: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()
    figures: dict[str, Any] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """Nothing to say: no refusal, no warning."""
        return not self.refusals and not self.warnings

    @property
    def problems(self) -> list[str]:
        """Refusals then warnings, one line each."""
        return [*self.refusals, *self.warnings]

    def allowed(self, force: bool = False) -> bool:
        """True if :func:`apply_gains` applies this set (``force`` overrides warnings only)."""
        return not self.refusals and (force or not self.warnings)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (non-finite floats stay floats: the caller's encoder decides)."""
        return {
            "refusals": list(self.refusals),
            "warnings": list(self.warnings),
            "figures": dict(self.figures),
        }


@dataclass(frozen=True)
class GainResult:
    """What :func:`apply_gains` did: ``gains`` read back from the drive after applying,
    ``previous`` the set read before, ``check`` the verdict, ``forced`` True when warnings were
    overridden by ``force``."""

    gains: dict[str, float | int]
    previous: dict[str, float | int]
    check: GainCheck
    forced: bool = False

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: gains, previous, warnings, figures, forced."""
        return {
            "gains": dict(self.gains),
            "previous": dict(self.previous),
            "warnings": list(self.check.warnings),
            "figures": dict(self.check.figures),
            "forced": self.forced,
        }


class GainsRefused(InvalidValue):
    """A gain set refused before anything was sent; ``check`` says why, ``unstable`` whether
    ``force`` could not help (one-line message)."""

    def __init__(self, message: str, check: GainCheck) -> None:
        super().__init__(message)
        self.check = check
        self.unstable = bool(check.refusals)


def _controller(value: Any) -> tuple[int, design.ControllerName]:
    """(code, name) of a controller given as 0..2 or "deadbeat"/"pi"/"predictive"."""
    if isinstance(value, str) and not value.strip().lstrip("-").isdigit():
        name = value.strip().lower()
        if name not in design.CONTROLLERS:
            raise InvalidValue(
                f"type: {value!r} is not a controller ({', '.join(design.CONTROLLERS)} or 0..2)"
            )
        code = design.CONTROLLERS.index(name)
        return code, design.CONTROLLERS[code]
    code = int(value)
    if not 0 <= code < len(design.CONTROLLERS):
        raise InvalidValue(f"type: {code} is not a controller code (0..2)")
    return code, design.CONTROLLERS[code]


def _normalised(gains: Mapping[str, Any]) -> dict[str, float | int]:
    out: dict[str, float | int] = {}
    for k, v in gains.items():
        if k == "type":
            out[k] = _controller(v)[0]
            continue
        if isinstance(v, bool) or not isinstance(v, int | float):
            raise InvalidValue(f"{k}: {v!r} is not a number")
        if not math.isfinite(float(v)):
            raise InvalidValue(f"{k}: {v!r} is not a finite number")
        out[k] = int(v) if k == "emf_feedforward" else float(v)
    return out


def check_gains(
    gains: Mapping[str, Any],
    R: float,
    L: float,
    speed_model: tuple[float, float] | None = None,
    *,
    rated_current: float | None = None,
    V_dc_nominal: float | None = None,
) -> GainCheck:
    """Check a full gain set (names of :class:`drive_link.Gains`) for the motor R [Ω], L [H]
    and the speed model ``(a, b)`` of ``G(z) = b/(z - a)`` (default: the paper's, the one the
    drive's rule uses). No bus. See the module docstring for the policy."""
    g = _normalised(gains)
    for k, v in _CURRENT_DEFAULTS.items():
        g.setdefault(k, v)
    controller = _controller(g["type"])[1]
    R, L = float(R), float(L)
    motor = {
        "R": R,
        "L": L,
        "rated_current": _MOTOR_DEFAULTS["rated_current"]
        if rated_current is None
        else float(rated_current),
        "V_dc_nominal": _MOTOR_DEFAULTS["V_dc_nominal"]
        if V_dc_nominal is None
        else float(V_dc_nominal),
    }
    a, b = speed_model if speed_model is not None else (A_IDENTIFIED, B_IDENTIFIED)
    refusals: list[str] = []
    warnings: list[str] = []
    L_c, R_c = float(g["L_c"]), float(g["R_c"])
    fig: dict[str, Any] = {"controller": controller, "L_c/L": L_c / L, "speed_model": [a, b]}

    # current loop: closed-loop poles (design), then the drive's own rule
    loop = design.loop_tf(
        design.CurrentLoopPars(controller, R, L, L_c, R_c, float(g["k_p"]), float(g["k_i"]))
    )
    closed = design.feedback(loop)
    stable = design.is_stable(closed)
    poles = closed.poles()
    fig["current_loop_stable"] = bool(stable)
    fig["current_max_pole_radius"] = float(max(abs(poles))) if poles.size else 0.0
    if not stable:
        detail = (
            f"k_p = {float(g['k_p']):.4g} V/A, k_i = {float(g['k_i']):.4g} V/A"
            if controller == "pi"
            else f"L_c/L = {L_c / L:.3g}"
        )
        refusals.append(
            f"current loop unstable ({controller}, {detail}, largest |pole| "
            f"{fig['current_max_pole_radius']:.6f})"
        )
    try:
        check_current_gains({k: g[k] for k in CURRENT_KEYS}, motor)
    except LimitError as exc:
        if stable:  # an unstable loop is already reported
            refusals.append(f"the drive refuses this current set: {exc}")
    if stable:
        m = design.margins(loop)
        fig.update(design.margins_summary(m))
        if m.gain_margin_db < GAIN_MARGIN_MIN_DB:
            warnings.append(f"gain margin {m.gain_margin_db:.2f} dB < {GAIN_MARGIN_MIN_DB} dB")
        if m.sensitivity_peak > SENSITIVITY_PEAK_MAX:
            warnings.append(f"sensitivity peak {m.sensitivity_peak:.2f} > {SENSITIVITY_PEAK_MAX}")
    # 1e-6 relative slack: L read back from the drive is float32, so L_c = 1.5·L typed by a user
    # (22.2 µH on 14.8 µH) must not be refused as 1.5000000008 L.
    if controller in ("deadbeat", "predictive") and L_c > L_C_MAX_RATIO * L * (1 + 1e-6):
        warnings.append(f"L_c = {L_c / L:.3g} L > {L_C_MAX_RATIO} L")

    # speed loop: IP on the speed model (eq. 27), the drive's IP rule, the cascade rule
    if "speed_k_p" in g and "speed_k_i" in g:
        kp, ki = float(g["speed_k_p"]), float(g["speed_k_i"])
        sp_closed = design.speed_closed_loop(design.SpeedLoopPars(a, b, kp, ki))
        sp_stable = design.is_stable(sp_closed)
        fig["speed_loop_stable"] = bool(sp_stable)
        fig["speed_max_pole_radius"] = float(max(abs(sp_closed.poles())))
        if not sp_stable:
            refusals.append("speed loop (IP, eq. 27) unstable on the speed model")
        try:
            check_ip_speed_gains(kp, ki, a, b)
            if stable:
                check_cascade({k: g[k] for k in CURRENT_KEYS}, motor, kp, ki)
        except LimitError as exc:
            if sp_stable or "unstable" not in str(exc):
                refusals.append(f"the drive refuses this speed set: {exc}")
    return GainCheck(tuple(refusals), tuple(warnings), fig)


def read_motor(drive: GainSetDrive) -> dict[str, float]:
    """The motor parameters the rule needs, read from the drive (motor.R Ω, motor.L H,
    motor.rated_current A, motor.V_dc_nominal V)."""
    return {k: float(drive.read(f"motor.{k}")) for k in MOTOR_KEYS}


def apply_gains(
    drive: GainSetDrive,
    changes: Mapping[str, Any],
    *,
    force: bool = False,
    speed_model: tuple[float, float] | None = None,
    previous: Mapping[str, Any] | None = None,
    motor: Mapping[str, float] | None = None,
) -> GainResult:
    """Apply ``changes`` (a subset of :data:`drive_link.GAIN_FIELDS`; ``type`` may be a name)
    as one set: check the merged set (:func:`check_gains` on ``speed_model``, default the
    paper's), stage the set(s) it changes in 0x20F0, apply them with 0x20F1 and read back the
    values that changed.

    ``previous`` (the full present set) and ``motor`` (:func:`read_motor`'s values) are what
    the caller already holds; each is read from the drive once when not given. A value equal
    to the present one is no change; a set none of whose values change is not staged, and with
    nothing changed nothing is sent. Bus cost: 13 + 4 reads when nothing is given, then the
    staged set(s) (10 current, 3 speed), one apply and one read per changed REAL32.

    Returns a :class:`GainResult` whose ``gains`` are the set as the drive now holds it (the
    changed values as read back, float32, the others as they were).

    Raises :class:`GainsRefused` (an :class:`InvalidValue`, nothing sent) when the set is
    unstable or the drive's rule refuses it — ``force`` does not change that — or when its
    margins are poor and ``force`` is False; :class:`InvalidValue` for unknown names,
    non-numbers or a value outside its object's limits (nothing sent);
    :class:`drive_link.SdoAbort` if the drive still refuses (it then changed nothing);
    :class:`DriveError` if a value reads back other than applied.
    """
    unknown = [k for k in changes if k not in GAIN_FIELDS]
    if unknown:
        raise InvalidValue(f"unknown gain(s) {', '.join(unknown)}; known: {', '.join(GAIN_FIELDS)}")
    if not changes:
        raise InvalidValue("no gain to change")
    wanted = _normalised(changes)
    before = (
        {k: v for k, v in _normalised(previous).items() if k in GAIN_FIELDS}
        if previous is not None
        else drive.read_gains().to_dict()
    )
    held = dict(motor) if motor is not None else read_motor(drive)
    check = check_gains(
        {**before, **wanted},
        held["R"],
        held["L"],
        speed_model,
        rated_current=held["rated_current"],
        V_dc_nominal=held["V_dc_nominal"],
    )
    if check.refusals:
        raise GainsRefused(
            "refused: " + "; ".join(check.problems) + "; nothing applied (force never applies "
            "an unstable set or one the drive refuses)",
            check,
        )
    if check.warnings and not force:
        raise GainsRefused(
            "refused: " + "; ".join(check.warnings) + " (force to apply anyway); nothing applied",
            check,
        )
    back = stage_and_apply(drive, wanted, present=before, motor=held).to_dict()
    return GainResult(back, before, check, forced=bool(force and check.warnings))
