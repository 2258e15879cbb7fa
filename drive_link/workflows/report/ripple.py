"""The PWM ripple of i_p, measured (paper Sec. IV-B: unipolar PWM, output switched at 100 kHz).

The drive measures i_p at every switching edge of each PWM period (0x2040 ``i_p_min``,
``i_p_max``: the least and largest of those ADC conversions, the ripple's trough and peak;
``i_p_peaks``: the ripple maxima in the period). The experiment records them at the loop rate
at a settled speed and reports:

* ``ripple_freq_Hz``: median ripple maxima per period × f_s; model 2 f_s (unipolar PWM: two
  pulses of v_L per period), paper 100 kHz;
* ``ripple_pp_A``: median of i_p_max − i_p_min; model the unipolar ripple of the conducting
  pair (two phases in series, 2 L): during each active pulse of m T_s / 2 the line voltage is
  V_dc against a mean of m V_dc, so Δi = V_dc m (1 − m) T_s / (4 L), with the m applied in that
  period (recorded one sample before) and motor.L.

Currents A, voltages V, frequencies Hz, L H.
"""

from __future__ import annotations

import numpy as np

from ...link.trace import TS
from .. import steps
from ..restore import leave_as_found
from ._base import Context, ExperimentResult, Metric, figure_png, new_figure

__all__ = ["RIPPLE_SIGNALS", "W_RIPPLE", "pwm_ripple", "unipolar_ripple_pp"]

W_RIPPLE = 1000.0  #: speed of the operating point, rpm (the paper's Figs. 18-19)
N_SAMPLES = 1000  #: loop samples recorded (20 ms: eight commutation sectors at 1000 rpm)
RIPPLE_SIGNALS = ("i_p_min", "i_p_max", "i_p_peaks")  #: 0x2040 objects the experiment needs
PP_TOLERANCE = 0.1  #: allowed |measured − model| / model of the peak-to-peak


def unipolar_ripple_pp(V_dc: np.ndarray, m: np.ndarray, L: float) -> np.ndarray:
    """Peak-to-peak ripple (A) of unipolar PWM on two phases in series (2 L, L in H) with DC
    link ``V_dc`` (V) and modulation index ``m`` (|m| ≤ 1): V_dc |m| (1 − |m|) T_s / (4 L)."""
    a = np.abs(np.asarray(m, dtype=float))
    pp: np.ndarray = np.asarray(V_dc, dtype=float) * a * (1.0 - a) * TS / (4.0 * L)
    return pp


def pwm_ripple(ctx: Context) -> ExperimentResult:
    """Ripple frequency and peak-to-peak of i_p at a settled 1000 rpm (speed mode), measured
    from the drive's edge-sampled i_p_min / i_p_max / i_p_peaks, the unipolar model beside."""
    r = ExperimentResult("pwm_ripple", "PWM ripple of i_p", "Sec. IV-B, unipolar PWM")
    d = ctx.drive
    missing = [s for s in RIPPLE_SIGNALS if f"measurements.{s}" not in d.table]
    if missing:
        r.reason = ("not applicable: the drive does not measure i_p at the PWM edges "
                    f"(no measurements.{', measurements.'.join(missing)} in its EDS)")
        return r
    L = float(d.read("motor.L"))
    h = ctx.step_hooks(0.0, 1.0)
    with leave_as_found(d):
        steps.ensure_mode(d, "speed")
        d.set_speed(W_RIPPLE)
        steps.require_enabled(d, True)
        steps.wait_settled(d, "speed", W_RIPPLE, 5.0, steps.Settle(0.3, 15.0), h, "rpm")
        tr = steps.record(d, ["i_p", *RIPPLE_SIGNALS, "m", "V_dc", "speed"],
                          length=N_SAMPLES, hooks=h)
    sig = {k.removeprefix("measurements."): np.asarray(v, dtype=float)
           for k, v in tr.signals.items()}
    lo, hi, peaks = sig["i_p_min"][1:], sig["i_p_max"][1:], sig["i_p_peaks"][1:]
    pp = hi - lo
    # the period ending at sample k ran with the m computed at sample k − 1
    model_pp = unipolar_ripple_pp(sig["V_dc"][:-1], sig["m"][:-1], L)
    f_meas = float(np.median(peaks)) / TS
    pp_meas, pp_model = float(np.median(pp)), float(np.median(model_pp))
    r.metrics["ripple_freq_Hz"] = Metric(f_meas, 2.0 / TS, 100e3, "Hz", 1.0)
    r.metrics["ripple_pp_A"] = Metric(pp_meas, pp_model, None, "A", PP_TOLERANCE * pp_model)
    r.metrics["ripple_pp_max_A"] = Metric(float(np.max(pp)), None, None, "A", None)
    m_mean = float(np.mean(np.abs(sig["m"])))
    r.conditions = (
        f"speed mode at a settled {np.mean(sig['speed']):.0f} rpm, i_p {np.mean(sig['i_p']):.1f} A,"
        f" modulation index {m_mean:.3f}, V_dc {np.mean(sig['V_dc']):.1f} V, motor.L "
        f"{L * 1e6:.2f} µH; {N_SAMPLES} PWM periods recorded; ripple measured by the drive from "
        "i_p at every switching edge of each period (i_p_min, i_p_max, i_p_peaks)")
    r.notes.append(
        f"Median over the periods, tolerance {PP_TOLERANCE:.0%} of the model. Near a "
        "commutation, and while the open phase's freewheel diode conducts, the peak-to-peak "
        "departs from the two-phase formula (largest seen: "
        f"{float(np.max(pp)):.2f} A).")
    r.figures.append(_plot(tr.t[1:], sig["i_p"][1:], lo, hi, pp, model_pp))
    return r


def _plot(t: np.ndarray, i_p: np.ndarray, lo: np.ndarray, hi: np.ndarray, pp: np.ndarray,
          model_pp: np.ndarray) -> str:
    fig, (ax, ax2) = new_figure(2, 2.6)
    t_ms = t * 1e3
    ax.fill_between(t_ms, lo, hi, step="pre", color="tab:orange", alpha=0.35, lw=0,
                    label="i_p min .. max in each PWM period (A)")
    ax.plot(t_ms, i_p, color="tab:blue", lw=1.0, label="i_p sampled at the period boundary (A)")
    ax.set_ylabel("i_p (A)")
    ax.legend(fontsize=8, loc="lower right")
    ax.grid(alpha=0.3)
    ax.set_title("PWM ripple of i_p (unipolar, 2 pulses per 20 µs period: 100 kHz)", fontsize=9)
    ax2.plot(t_ms, pp, color="tab:blue", lw=1.5, label="measured i_p_max − i_p_min (A)")
    ax2.plot(t_ms, model_pp, color="tab:orange", lw=1.0, ls="--",
             label="model V_dc m (1 − m) T_s / (4 L) (A)")
    ax2.set_ylabel("peak-to-peak (A)")
    ax2.set_xlabel("time (ms)")
    ax2.legend(fontsize=8, loc="upper right")
    ax2.grid(alpha=0.3)
    return figure_png(fig)
