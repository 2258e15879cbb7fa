"""Recording primitives of the step tests (:mod:`drive_link.workflows.steps`): one recording by the
drive's trace recorder, a setpoint step recorded around itself, the settled-start wait, the
cancellable :class:`Hooks`, and the :class:`StepResult` a step test returns.
"""

from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from firmware_protocol.enums import ModeOfOperation

from ..errors import DriveTimeout, InvalidValue, StateError
from ..link.trace import TS, Trace, Trigger
from . import metrics
from .restore import Snapshot, leave_as_found, switch_mode

if TYPE_CHECKING:
    from ..link.drive import Drive

__all__ = [
    "Hooks",
    "NotSettled",
    "Settle",
    "StepResult",
    "column",
    "describe_change",
    "ensure_mode",
    "kept",
    "record",
    "record_setpoint_step",
    "require_enabled",
    "wait_settled",
]


@dataclass
class StepResult:
    """One step test.

    ``kind``: "current" or "speed"; ``signal``: the response's trace name; ``trace``: the
    recording (t = 0 at the step); ``metrics``: :class:`drive_link.workflows.metrics.StepMetrics` of
    the response after the step; ``predicted``: {"t": s, <signal>: model prediction} on the trace's
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
    commutation_at_s: float | None = None
    model_rms_error: float = math.nan
    attempts: int = 1
    start: float = math.nan
    changes: str = ""

    def summary(self) -> dict[str, Any]:
        """JSON-friendly summary (metrics, setpoints, parameters, model error, commutation,
        the settled start value measured before the step, what the test changed)."""
        unit = self.trace.units.get(self.signal, "")
        return {
            "kind": self.kind,
            "signal": self.signal,
            "unit": unit,
            "from": self.y_from,
            "to": self.y_to,
            "start": self.start,
            "changes": self.changes,
            "metrics": self.metrics.as_dict(),
            "params": self.params,
            "model_rms_error": self.model_rms_error,
            "commutation_at_s": self.commutation_at_s,
            "attempts": self.attempts,
        }

    def model_column(self) -> np.ndarray:
        """The model prediction on the whole trace time base (y_from before the step)."""
        tr = self.trace
        out = np.full(len(tr.t), float(self.y_from))
        k0 = tr.trigger_index
        p = np.asarray(self.predicted[self.signal], dtype=float)
        n = min(len(p), len(tr.t) - k0)
        out[k0 : k0 + n] = p[:n]
        return out

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


def ensure_mode(drive: Drive, mode: str | ModeOfOperation, brake: bool = False) -> None:
    """Select ``mode``; an enabled drive is switched coasting, not braking
    (:func:`drive_link.workflows.restore.switch_mode`), and enabled again."""
    switch_mode(drive, mode, brake=brake)


def require_enabled(drive: Drive, enable: bool) -> None:
    state = drive.state
    if state == "OPERATION ENABLED":
        return
    if not enable:
        raise StateError(f"step test needs OPERATION ENABLED (drive is {state}); enable it first")
    drive.enable()


@dataclass
class Hooks:
    """How a long recording reports and waits: ``progress(fraction 0..1, text)`` and
    ``sleep(seconds)``; either may raise to cancel (the dashboard's long actions do, on Cancel
    or past their deadline). Defaults: no report, :func:`time.sleep`."""

    progress: Callable[[float, str], None] | None = None
    sleep: Callable[[float], None] = time.sleep
    say: Callable[[str], None] | None = None
    """Called once before an experiment changes anything, with one line saying what it
    changes and what it puts back (the CLI prints it on stderr, the dashboard shows it)."""

    def announce(self, text: str) -> None:
        if self.say is not None:
            self.say(text)

    def report(self, fraction: float, text: str) -> None:
        if self.progress is not None:
            self.progress(fraction, text)

    def note(self, fraction: float, text: str) -> None:
        """Report without letting a cancel interrupt (used inside an SDO block upload)."""
        try:
            self.report(fraction, text)
        except Exception:  # the next report() raises it again, outside the upload
            pass


class NotSettled(DriveTimeout):
    """The start of a step did not settle: no metrics are computed from it."""


@dataclass(frozen=True)
class Settle:
    """When a start counts as settled: every reading of the signal over the last ``window_s``
    [s] lies within ``tol`` (the signal's unit: rpm or A) of the target, or, with no target,
    within ``tol`` of each other (steady); given up after ``timeout_s`` [s]. ``tol`` None: the
    experiment's default."""

    window_s: float = 0.3
    timeout_s: float = 15.0
    tol: float | None = None

    def __post_init__(self) -> None:
        for name in ("window_s", "timeout_s"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise InvalidValue(f"settle {name} must be a finite time >= 0 s (got {v!r})")
        if self.tol is not None and not (math.isfinite(self.tol) and self.tol > 0):
            raise InvalidValue(f"settle tolerance must be > 0 (got {self.tol!r})")


def wait_settled(
    drive: Drive,
    signal: str,
    target: float | None,
    tol: float,
    settle: Settle,
    hooks: Hooks,
    unit: str = "",
    poll_s: float = 0.02,
) -> float:
    """Wait until ``measurements.<signal>`` is settled (:class:`Settle`); returns its mean over
    the window. :class:`NotSettled` names the last value and the spread when it does not."""
    name = f"measurements.{signal}"
    t0 = time.monotonic()
    samples: list[tuple[float, float]] = []
    while True:
        now = time.monotonic()
        samples.append((now, float(drive.read(name))))
        samples = [(t, v) for t, v in samples if t >= now - settle.window_s - poll_s]
        span = now - samples[0][0]
        vals = [v for _, v in samples]
        if target is None:
            ok = max(vals) - min(vals) <= tol
        else:
            ok = max(abs(v - target) for v in vals) <= tol
        if ok and span >= settle.window_s:
            return float(np.mean(vals))
        if now - t0 >= settle.timeout_s:
            want = f"within {tol:g} {unit} of {target:g} {unit}" if target is not None else (
                f"steady within {tol:g} {unit}"
            )
            raise NotSettled(
                f"start not settled: {signal} {vals[-1]:.4g} {unit} (spread "
                f"{max(vals) - min(vals):.3g} {unit} over {span:.2g} s), not {want} for "
                f"{settle.window_s:g} s within {settle.timeout_s:g} s; no metrics computed "
                "(longer --settle-timeout?)"
            )
        hooks.sleep(poll_s)


def describe_change(kind: str, found: Snapshot, plan: str) -> str:
    return f"{kind}: {plan}; afterwards the drive is put back to {found.describe()}"


def upload_trace(drive: Drive, hooks: Hooks) -> Trace:
    def progress(done: int, total: int | None) -> None:
        if total:
            hooks.note(0.6 + 0.3 * done / total, f"uploading the trace ({done}/{total} bytes)")

    hooks.report(0.6, "uploading the trace")
    return drive.trace.upload(progress=progress if hooks.progress is not None else None)


def record(
    drive: Drive,
    channels: list[str],
    *,
    divider: int = 1,
    length: int | None = None,
    pre_trigger: int = 0,
    trigger: Trigger | str | None = None,
    action: Callable[[], None] | None = None,
    timeout: float | None = None,
    hooks: Hooks | None = None,
) -> Trace:
    """One recording: configure (``divider`` loop samples per trace sample, ``length`` samples,
    ``pre_trigger`` before the trigger), arm, let the pre-trigger part fill, run ``action``
    (e.g. a setpoint step), wait (``timeout`` s, default 1 s + 3 × the recording) and upload,
    under the trace lock. Waits and progress go through ``hooks``."""
    h = hooks or Hooks()
    with drive.trace.lock:
        drive.trace.configure(channels, divider, length, pre_trigger, trigger)
        n = int(drive.read("trace_config.length")) if length is None else int(length)
        if timeout is None:
            timeout = 1.0 + 3.0 * n * divider * TS
        drive.trace.arm()
        if action is not None:
            if pre_trigger:
                drive.trace.wait_ready(10.0 + 20.0 * pre_trigger * divider * TS, sleep=h.sleep)
            action()
        h.report(0.3, "recording")
        drive.trace.wait(timeout, sleep=h.sleep)
        return upload_trace(drive, h)


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
    hooks: Hooks | None = None,
) -> Trace:
    """Record ``channels`` around a setpoint step made by ``set_after``.

    Configures the recorder (``divider`` loop samples per trace sample, ``length`` samples,
    ``pre_trigger`` before the step) on "setpoint step", arms, waits until the drive reports
    its pre-trigger part full (:meth:`~drive_link.link.trace.Recorder.wait_ready`: in the drive's
    own time, which a slow bus or a starved virtual drive stretches), steps, waits
    (``timeout`` s, default 1 s + 3 × the recording) and uploads, all under the trace lock.
    If the recording still does not finish, ``set_before`` puts the setpoint back (and waits
    for the plant to follow, if it does so) and the step is repeated (``attempts`` times).
    Waits and progress go through ``hooks``.
    """
    h = hooks or Hooks()
    pre_s = pre_trigger * divider * TS
    record_s = length * divider * TS
    if timeout is None:
        timeout = 1.0 + 3.0 * record_s
    ready_timeout = 10.0 + 20.0 * pre_s  # the drive's time may run far behind the wall clock
    with drive.trace.lock:
        drive.trace.configure(channels, divider, length, pre_trigger, Trigger("setpoint_step"))
        for attempt in range(attempts):
            drive.trace.arm()
            drive.trace.wait_ready(ready_timeout, sleep=h.sleep)
            set_after()
            h.report(0.3, "recording")
            try:
                drive.trace.wait(timeout, sleep=h.sleep)
            except DriveTimeout:
                if attempt + 1 == attempts or drive.trace.state != "armed":
                    raise
                drive.trace.stop()
                set_before()
                continue
            return upload_trace(drive, h)
    raise AssertionError("unreachable")


def column(tr: Trace, name: str) -> np.ndarray:
    return np.asarray(tr.signals[f"measurements.{name}"], dtype=float)


def kept(drive: Drive, snap: Snapshot, restore: bool, brake: bool) -> Any:
    """:func:`leave_as_found` with ``snap``, or nothing when ``restore`` is False."""
    if not restore:
        return contextlib.nullcontext(snap)
    return leave_as_found(drive, found=snap, brake=brake)
