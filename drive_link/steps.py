"""Step tests: a current step or a speed step recorded by the drive's trace recorder, triggered by
the step itself (trigger_mode "on setpoint step"), with metrics (:mod:`drive_link.metrics`) and
the response the model predicts (:mod:`drive_link.design`) for the drive's present parameters.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from firmware_protocol import enums, paper

from . import design, metrics
from .errors import DriveTimeout, InvalidValue, StateError
from .trace import TS, Trace, Trigger

if TYPE_CHECKING:
    from .drive import Drive

#: Speed model G(z) = b/(z − a) of the paper (eq. 26) at Ts = 20 µs: a (1), b (rpm/A per sample).
SPEED_MODEL_PAPER: tuple[float, float] = paper.SPEED_MODEL

CONTROLLER_NAMES = enums.CONTROLLER_NAMES


@dataclass
class StepResult:
    """One step test.

    ``kind``: "current" or "speed"; ``signal``: the response's trace name; ``trace``: the
    recording (t = 0 at the step); ``metrics``: :class:`drive_link.metrics.StepMetrics` of the
    response after the step; ``predicted``: {"t": s, <signal>: model prediction} on the trace's
    time base from t = 0; ``params``: the drive parameters used for the prediction.
    """

    kind: str
    signal: str
    y_from: float
    y_to: float
    trace: Trace
    metrics: metrics.StepMetrics
    predicted: dict[str, np.ndarray]
    params: dict[str, Any] = field(default_factory=dict)

    def summary(self) -> dict[str, Any]:
        """JSON-friendly summary (metrics, setpoints, parameters)."""
        unit = self.trace.units.get(self.signal, "")
        return {
            "kind": self.kind,
            "signal": self.signal,
            "unit": unit,
            "from": self.y_from,
            "to": self.y_to,
            "metrics": self.metrics.as_dict(),
            "params": self.params,
        }

    def to_csv(self, path: str | Path) -> Path:
        """The trace plus a ``predicted`` column (NaN before the step) as CSV."""
        tr = self.trace
        pred = np.full(len(tr.t), np.nan)
        k0 = tr.trigger_index
        p = self.predicted[self.signal]
        n = min(len(p), len(tr.t) - k0)
        pred[k0 : k0 + n] = p[:n]
        sig = dict(tr.signals)
        sig[f"{self.signal}_predicted"] = pred.astype(np.float32)
        units = dict(tr.units)
        units[f"{self.signal}_predicted"] = tr.units.get(self.signal, "")
        return Trace(tr.t, sig, units, tr.trigger_index, tr.divider).to_csv(path)

    def to_png(self, path: str | Path) -> Path:
        """Plot of the trace with the model prediction dashed."""
        tr = self.trace
        pad = np.full(tr.trigger_index, np.nan)
        over = {f"{self.signal} (model)": np.concatenate([pad, self.predicted[self.signal]])}
        m = self.metrics
        title = (
            f"{self.kind} step {self.y_from:g} → {self.y_to:g}: rise {m.rise_time * 1e3:.3g} ms, "
            f"overshoot {m.overshoot_pct:.3g} %, settling {m.settling_time * 1e3:.3g} ms"
        )
        return tr.to_png(path, title=title, overlay=over)


def _ensure_mode(drive: Drive, mode: str) -> None:
    """Select ``mode``; a drive that refuses mode changes while enabled is disabled first."""
    if drive.mode == mode:
        return
    if drive.state == "OPERATION ENABLED":
        drive.disable()
    drive.set_mode(mode)


def _require_enabled(drive: Drive, enable: bool) -> None:
    state = drive.state
    if state == "OPERATION ENABLED":
        return
    if not enable:
        raise StateError(f"step test needs OPERATION ENABLED (drive is {state}); enable it first")
    drive.enable()


def record_setpoint_step(
    drive: Drive,
    channels: list[str],
    set_before: Callable[[], None],
    set_after: Callable[[], None],
    divider: int,
    length: int,
    pre_trigger: int,
    timeout: float | None,
    attempts: int = 3,
) -> Trace:
    """Record ``channels`` around a setpoint step made by ``set_after``.

    Configures the recorder (``divider`` loop samples per trace sample, ``length`` samples,
    ``pre_trigger`` before the step) on "setpoint step", arms, waits for the pre-trigger part
    to fill, steps, waits (``timeout`` s, default 1 s + 3 × the recording) and uploads, all
    under the trace lock. The recorder ignores a step while its pre-trigger part is still
    filling (state "armed" either way), so the wait is ``3 × pre-trigger time + 20 ms``; if
    the step was still too early ``set_before`` puts the setpoint back and the step is
    repeated (``attempts`` times).
    """
    pre_s = pre_trigger * divider * TS
    record_s = length * divider * TS
    if timeout is None:
        timeout = 1.0 + 3.0 * record_s
    wait_pre = 3.0 * pre_s + 0.02
    with drive.trace.lock:
        drive.trace.configure(channels, divider, length, pre_trigger, Trigger("setpoint_step"))
        for attempt in range(attempts):
            drive.trace.arm()
            time.sleep(wait_pre * (attempt + 1))
            set_after()
            try:
                drive.trace.wait(timeout)
                return drive.trace.upload()
            except DriveTimeout:
                if attempt + 1 == attempts or drive.trace.state != "armed":
                    raise
                drive.trace.stop()
                set_before()
                time.sleep(wait_pre)
    raise AssertionError("unreachable")


def current_step(
    drive: Drive,
    i_from: float = 15.0,
    i_to: float = 20.0,
    divider: int = 1,
    length: int = 400,
    pre_trigger: int = 50,
    settle_s: float = 0.05,
    enable: bool = True,
    timeout: float | None = None,
    extra: tuple[str, ...] = (),
) -> StepResult:
    """Pseudo-current step i_from → i_to (A) in "current" mode.

    Sets the mode and i_from, enables (if ``enable``), waits ``settle_s`` s, arms the recorder
    (channels i_p, i_p_ref, v_L, e_L and ``extra``, e.g. "hall_sector"; ``divider`` loop
    samples per trace sample, ``length`` samples, ``pre_trigger`` before the step) on
    "setpoint step", writes i_to and uploads.
    The prediction is :func:`drive_link.design.predicted_step` for the drive's controller type,
    L_c, R_c, k_p, k_i and motor R, L, with the back-EMF e_L measured just before the step.
    """
    if i_from == i_to:
        raise InvalidValue("current step needs i_from != i_to")
    _ensure_mode(drive, "current")
    drive.set_current(i_from)
    _require_enabled(drive, enable)
    time.sleep(settle_s)
    tr = record_setpoint_step(
        drive,
        ["i_p", "i_p_ref", "v_L", "e_L", *extra],
        lambda: drive.set_current(i_from),
        lambda: drive.set_current(i_to),
        divider,
        length,
        pre_trigger,
        timeout,
    )
    g = drive.read_gains()
    R = float(drive.read("motor.R"))
    L = float(drive.read("motor.L"))
    k0 = tr.trigger_index
    i_p = tr.signals["measurements.i_p"].astype(float)
    e_L = float(np.mean(tr.signals["measurements.e_L"][: max(k0, 1)]))
    controller = CONTROLLER_NAMES.get(int(g.type), "deadbeat")
    n_after = len(tr.t) - k0
    pred = design.predicted_step(
        controller,
        n_samples=n_after * divider,
        i_start=i_from,
        i_final=i_to,
        R=R,
        L=L,
        L_c=g.L_c,
        R_c=g.R_c,
        k_p=g.k_p,
        k_i=g.k_i,
        e_L=e_L,
    )
    y_pred = pred.i_p[::divider][:n_after]
    m = metrics.step_metrics(tr.t, i_p, reference=i_to, t_step=0.0, y_initial=float(i_from))
    params = {
        "controller": controller,
        "R": R,
        "L": L,
        "L_c": g.L_c,
        "R_c": g.R_c,
        "k_p": g.k_p,
        "k_i": g.k_i,
        "e_L": e_L,
        "divider": divider,
        "Ts": TS,
    }
    return StepResult(
        "current",
        "measurements.i_p",
        float(i_from),
        float(i_to),
        tr,
        m,
        {"t": tr.t[k0:], "measurements.i_p": y_pred},
        params,
    )


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
) -> StepResult:
    """Speed step of ``delta_rpm`` (rpm) from ``start_rpm`` (default: the present target) in
    "speed" mode, recorded with channels speed, speed_ref, i_p_ref, i_p.

    The prediction is :func:`drive_link.design.predicted_speed_step` with the drive's IP gains
    and the speed model ``model`` = (a, b) (default: the paper's, :data:`SPEED_MODEL_PAPER`;
    pass the result of ``drive-link identify`` for the machine at hand).
    """
    if delta_rpm == 0:
        raise InvalidValue("speed step needs a non-zero delta")
    _ensure_mode(drive, "speed")
    w0 = float(drive.read("target_velocity")) if start_rpm is None else float(start_rpm)
    w1 = w0 + float(delta_rpm)
    drive.set_speed(w0)
    _require_enabled(drive, enable)
    time.sleep(settle_s)
    tr = record_setpoint_step(
        drive,
        ["speed", "speed_ref", "i_p_ref", "i_p"],
        lambda: drive.set_speed(w0),
        lambda: drive.set_speed(w1),
        divider,
        length,
        pre_trigger,
        timeout,
    )
    g = drive.read_gains()
    a, b = model or SPEED_MODEL_PAPER
    k0 = tr.trigger_index
    speed = tr.signals["measurements.speed"].astype(float)
    w_start = float(np.mean(speed[: max(k0, 1)]))
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
    )
