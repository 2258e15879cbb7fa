"""The gain-set safety check of ``drive-link gains set``: refuse unstable or poorly damped loops.

Current loop: the closed loop with the drive's motor R, L and the proposed L_c, R_c (eq. 16 for
deadbeat; C·P otherwise) must be stable, L_c ≤ 1.5 L, gain margin ≥ 2 dB and sensitivity peak
‖S‖∞ ≤ 5. Speed loop: the IP closed loop (eq. 27) on the speed model must be stable.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from . import design

L_C_MAX_RATIO = 1.5
GAIN_MARGIN_MIN_DB = 2.0
SENSITIVITY_PEAK_MAX = 5.0
CONTROLLERS = {0: "deadbeat", 1: "pi", 2: "predictive"}


@dataclass
class MarginReport:
    """Outcome: ``ok``; ``problems`` (one line each); figures (GM dB, ‖S‖∞, L_c/L, stability)."""

    ok: bool
    problems: list[str] = field(default_factory=list)
    figures: dict[str, float | bool | str] = field(default_factory=dict)


def check_gains(
    gains: dict[str, float | int],
    R: float,
    L: float,
    speed_model: tuple[float, float] | None = None,
) -> MarginReport:
    """Check a full gain set (names of :class:`drive_link.Gains`) for the motor R (Ω), L (H)."""
    problems: list[str] = []
    controller = CONTROLLERS.get(int(gains["type"]), "deadbeat")
    L_c, R_c = float(gains["L_c"]), float(gains["R_c"])
    fig: dict[str, float | bool | str] = {"controller": controller, "L_c/L": L_c / L}
    if controller == "deadbeat":
        stable = design.is_stable(design.closed_loop_mismatch(R, L, L_c, R_c))
    else:
        stable = None
    loop = design.current_loop_tf(
        controller, R=R, L=L, L_c=L_c, R_c=R_c, k_p=float(gains["k_p"]), k_i=float(gains["k_i"])
    )
    if stable is None:
        stable = design.is_stable(design.feedback(loop))
    fig["current_loop_stable"] = bool(stable)
    if not stable:
        problems.append(f"current loop unstable ({controller}, L_c/L = {L_c / L:.3g})")
    else:
        m = design.margins(loop)
        fig["gain_margin_db"] = float(m.gain_margin_db)
        fig["sensitivity_peak"] = float(m.sensitivity_peak)
        if m.gain_margin_db < GAIN_MARGIN_MIN_DB:
            problems.append(f"gain margin {m.gain_margin_db:.2f} dB < {GAIN_MARGIN_MIN_DB} dB")
        if m.sensitivity_peak > SENSITIVITY_PEAK_MAX:
            problems.append(f"sensitivity peak {m.sensitivity_peak:.2f} > {SENSITIVITY_PEAK_MAX}")
    # 1e-6 relative slack: L read back from the drive is float32, so L_c = 1.5·L typed by a user
    # (22.2 µH on 14.8 µH) must not be refused as 1.5000000008 L.
    if controller in ("deadbeat", "predictive") and L_c > L_C_MAX_RATIO * L * (1 + 1e-6):
        problems.append(f"L_c = {L_c / L:.3g} L > {L_C_MAX_RATIO} L")
    if speed_model is not None:
        a, b = speed_model
        sp = design.is_stable(
            design.ip_closed_loop(a, b, float(gains["speed_k_p"]), float(gains["speed_k_i"]))
        )
        fig["speed_loop_stable"] = bool(sp)
        if not sp:
            problems.append("speed loop (IP, eq. 27) unstable on the speed model")
    return MarginReport(not problems, problems, fig)
