"""Speed-loop experiments (:mod:`drive_link.workflows.steps`): the speed step (Figs. 18-19) and the
speed-model identification (Fig. 16, eq. 26), recorded by the drive's trace recorder.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from firmware_protocol import paper

from ..errors import InvalidValue
from ..link.trace import TS, Trace
from . import design, identify, metrics
from ._step_record import (
    Hooks,
    NotSettled,
    Settle,
    StepResult,
    column,
    describe_change,
    ensure_mode,
    kept,
    record_setpoint_step,
    require_enabled,
    wait_settled,
)
from .restore import Snapshot, snapshot

if TYPE_CHECKING:
    from ..link.drive import Drive

__all__ = [
    "SPEED_MODEL_PAPER",
    "Identification",
    "identification_record",
    "identify_speed_model",
    "speed_step",
]

#: Speed model G(z) = b/(z − a) of the paper (eq. 26) at Ts = 20 µs: a (1), b (rpm/A per sample).
SPEED_MODEL_PAPER: tuple[float, float] = paper.SPEED_MODEL


def speed_step(
    drive: Drive,
    delta_rpm: float = 500.0,
    start_rpm: float | None = None,
    divider: int = 100,
    length: int = 1500,
    pre_trigger: int = 100,
    settle_s: float = 0.2,
    enable: bool = True,
    model: tuple[float, float] | None = None,
    timeout: float | None = None,
    *,
    hooks: Hooks | None = None,
    settle: Settle | None = None,
    extra: tuple[str, ...] = (),
    brake: bool = False,
    found: Snapshot | None = None,
    restore: bool = True,
) -> StepResult:
    """Speed step of ``delta_rpm`` (rpm) from ``start_rpm`` (default: the present target) in
    "speed" mode, recorded with channels speed, speed_ref, i_p_ref, i_p (and ``extra``, e.g.
    i_a for the paper's Figs. 18-19).

    The start must be settled first: the measured speed within ``settle.tol`` (default
    max(2 rpm, 1 % of the step)) of ``start_rpm`` for ``settle.window_s`` s, within
    ``settle.timeout_s`` s (:class:`Settle`; :class:`NotSettled` otherwise), and the recorded
    speed before the step must agree: a start that drifted raises :class:`NotSettled` with no
    metrics. The measured start is ``StepResult.start`` (also ``y_from``).

    The prediction is :func:`drive_link.workflows.design.predicted_speed_step` with the drive's IP
    gains and the speed model ``model`` = (a, b) (default: the paper's, :data:`SPEED_MODEL_PAPER`;
    pass the result of ``drive-link identify`` for the machine at hand). The drive is left as
    found (see :func:`current_step`).
    """
    if delta_rpm == 0:
        raise InvalidValue("speed step needs a non-zero delta")
    h = hooks or Hooks()
    st = settle or Settle()
    tol = st.tol if st.tol is not None else max(2.0, 0.01 * abs(float(delta_rpm)))
    snap = found if found is not None else snapshot(drive)
    target = snap.setpoints.get("target_velocity", 0)
    w0 = float(target) if start_rpm is None else float(start_rpm)
    w1 = w0 + float(delta_rpm)
    plan = f"speed mode, {w0:g} rpm (settled), then {round(w1):g} rpm"
    h.announce(describe_change("speed step", snap, plan))
    channels = ["speed", "speed_ref", "i_p_ref", "i_p", *extra]
    with kept(drive, snap, restore, brake):
        ensure_mode(drive, "speed", brake)
        drive.set_speed(w0)
        require_enabled(drive, enable)
        h.report(0.02, f"settling at {w0:g} rpm")
        wait_settled(drive, "speed", w0, tol, st, h, "rpm")
        h.sleep(settle_s)

        def back_to_w0() -> None:  # a retried step starts from rest at w0 again
            drive.set_speed(w0)
            wait_settled(drive, "speed", w0, tol, st, h, "rpm")

        tr = record_setpoint_step(
            drive,
            channels,
            back_to_w0,
            lambda: drive.set_speed(w1),
            divider,
            length,
            pre_trigger,
            timeout,
            hooks=h,
        )
        g = drive.read_gains()
    a, b = model or SPEED_MODEL_PAPER
    k0 = tr.trigger_index
    speed = tr.signals["measurements.speed"].astype(float)
    pre = speed[: max(k0, 1)]
    w_start = float(np.mean(pre))
    if float(np.max(np.abs(pre - w0))) > tol:
        raise NotSettled(
            f"start not settled: the recorded speed before the step ran {np.min(pre):.4g}.."
            f"{np.max(pre):.4g} rpm, not within {tol:g} rpm of {w0:g} rpm; no metrics computed"
        )
    n_after = len(tr.t) - k0
    pred = design.predicted_speed_step(
        a,
        b,
        g.speed_k_p,
        g.speed_k_i,
        n_samples=n_after * divider,
        w_start=w_start,
        w_final=round(w1),
        decimate=divider,
    )
    m = metrics.step_metrics(tr.t, speed, reference=round(w1), t_step=0.0, y_initial=w_start)
    params = {
        "a": a,
        "b": b,
        "speed_k_p": g.speed_k_p,
        "speed_k_i": g.speed_k_i,
        "divider": divider,
        "Ts": TS,
        "settle_tol_rpm": tol,
    }
    return StepResult(
        "speed",
        "measurements.speed",
        w_start,
        float(round(w1)),
        tr,
        m,
        {"t": tr.t[k0:], "measurements.speed": pred.speed[:n_after]},
        params,
        start=w_start,
        changes=describe_change("speed step", snap, f"{w0:g} → {round(w1):g} rpm"),
    )


@dataclass
class Identification:
    """A speed-model identification (Fig. 16): the recorded current step ``trace`` (i_p A,
    speed rpm), the least-squares ``fit`` of ``G(z) = b/(z - a)`` at the loop rate
    (:class:`drive_link.workflows.identify.FirstOrderFit`) and ``model``: the identified model's
    free-run speed [rpm] on the trace's time base, driven by the measured i_p."""

    trace: Trace
    fit: identify.FirstOrderFit
    model: np.ndarray
    i_from: float
    i_to: float
    start_rpm: float = math.nan
    changes: str = ""

    def summary(self) -> dict[str, Any]:
        """JSON-friendly: the fit (a, b, R², RMS, time constant, DC gain ...) and the step."""
        return {
            "fit": self.fit.as_dict(),
            "from": self.i_from,
            "to": self.i_to,
            "start_rpm": self.start_rpm,
            "changes": self.changes,
        }


def identification_record(duration_s: float) -> tuple[int, int, int]:
    """(divider, length, pre_trigger) recording ``duration_s`` [s] after the step in at most
    8000 samples per channel, with 5 % (at least 10 samples) before it."""
    if not (math.isfinite(duration_s) and duration_s > 0):
        raise InvalidValue(f"duration must be a finite time > 0 s (got {duration_s!r})")
    divider = max(1, math.ceil(duration_s / (8000 * TS)))
    n_post = round(duration_s / (divider * TS))
    pre = max(10, n_post // 20)
    return divider, min(8192, pre + n_post), pre


def identify_speed_model(
    drive: Drive,
    i_from: float = 15.0,
    i_to: float = 30.0,
    *,
    duration_s: float | None = 1.0,
    divider: int | None = None,
    length: int | None = None,
    pre_trigger: int | None = None,
    settle_s: float = 0.1,
    enable: bool = True,
    timeout: float | None = None,
    hooks: Hooks | None = None,
    settle: Settle | None = None,
    brake: bool = False,
    found: Snapshot | None = None,
    restore: bool = True,
) -> Identification:
    """Current step i_from → i_to (A) in "current" mode with i_p and speed recorded, then the
    fit of ``G(z) = b/(z - a)`` (eq. 26) at the loop rate.

    The record covers ``duration_s`` s after the step (:func:`identification_record`), or is
    given as ``divider``/``length``/``pre_trigger``. Sets the mode (switching coasting, not
    braking, unless ``brake``) and i_from, enables (if ``enable``), waits until the speed is
    steady at i_from (:class:`Settle`: every reading over ``window_s`` within ``tol``, default
    2 rpm, of each other; :class:`NotSettled` after ``timeout_s``), waits ``settle_s`` s, steps,
    and leaves the drive as found afterwards (also on error and Ctrl-C; see
    :func:`current_step`). The settled start speed is ``Identification.start_rpm``.
    """
    if i_from == i_to:
        raise InvalidValue("identification needs i_from != i_to")
    if divider is None or length is None or pre_trigger is None:
        d0, n0, p0 = identification_record(1.0 if duration_s is None else float(duration_s))
        divider = d0 if divider is None else divider
        length = n0 if length is None else length
        pre_trigger = p0 if pre_trigger is None else pre_trigger
    h = hooks or Hooks()
    st = settle or Settle(window_s=0.5, timeout_s=15.0)
    tol = st.tol if st.tol is not None else 2.0
    snap = found if found is not None else snapshot(drive)
    plan = f"current mode, i_p* {i_from:g} A until the speed is steady, then {i_to:g} A"
    h.announce(describe_change("identification", snap, plan))
    with kept(drive, snap, restore, brake):
        ensure_mode(drive, "current", brake)
        drive.set_current(i_from)
        require_enabled(drive, enable)
        h.report(0.05, f"settling at {i_from:g} A")
        start = wait_settled(drive, "speed", None, tol, st, h, "rpm")
        h.sleep(settle_s)
        tr = record_setpoint_step(
            drive,
            ["i_p", "speed"],
            lambda: drive.set_current(i_from),
            lambda: drive.set_current(i_to),
            divider,
            length,
            pre_trigger,
            timeout,
            hooks=h,
        )
    h.report(0.95, "fitting")
    i_p = column(tr, "i_p")
    speed = column(tr, "speed")
    fit = identify.fit_first_order(i_p, speed, Ts=divider * TS)
    model = identify.simulate_first_order(fit.a_D, fit.b_D, i_p, speed[0], fit.offset)
    ident = Identification(tr, fit, model, float(i_from), float(i_to))
    ident.start_rpm = start
    ident.changes = describe_change("identification", snap, f"i_p* {i_from:g} → {i_to:g} A")
    return ident
