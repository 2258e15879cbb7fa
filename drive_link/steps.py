"""Step tests and the speed-model identification, recorded by the drive's trace recorder and
triggered by the step itself (trigger_mode "on setpoint step"), with metrics
(:mod:`drive_link.metrics`), the response the model predicts (:mod:`drive_link.design`) for the
drive's present parameters, and the least-squares fit of ``G(z) = b/(z - a)``
(:mod:`drive_link.identify`). ``drive-link step``/``identify-drive`` and the dashboard both run
these; the dashboard passes :class:`Hooks` to show progress and to cancel.

Current steps record the Hall sector too: a commutation (a sector change) disturbs i_p from
8-25 loop samples before the sector changes (the back-EMF's trapezoid slope; measured at 130-300
rpm on the virtual drive) and the disturbance then decays with the plant's L/R, so a record with a
sector change before the step or in the first ``CLEAN_FRACTION`` after it is repeated
(``commutation_retries`` times, the least disturbed record is kept) and the metrics and the model
error are taken up to ``COMMUTATION_MARGIN`` loop samples before it
(``StepResult.commutation_at_s``). The model prediction uses the back-EMF e_L measured before
the step.
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

from firmware_protocol import enums, paper

from . import design, identify, metrics
from .errors import DriveTimeout, InvalidValue, StateError
from .restore import Snapshot, leave_as_found, snapshot, switch_mode
from .trace import TS, Trace, Trigger

if TYPE_CHECKING:
    from .drive import Drive

__all__ = [
    "CLEAN_FRACTION",
    "COMMUTATION_MARGIN",
    "COMMUTATION_RETRIES",
    "SPEED_MODEL_PAPER",
    "Hooks",
    "Identification",
    "NotSettled",
    "Settle",
    "StepResult",
    "current_step",
    "first_commutation",
    "identification_record",
    "identify_speed_model",
    "record",
    "record_setpoint_step",
    "sector_changes",
    "speed_step",
    "wait_settled",
]

COMMUTATION_RETRIES = 4
"""Current-step records taken at most while a commutation disturbs the early part."""
CLEAN_FRACTION = 0.8
"""A current-step record is clean when no commutation falls in this share after the step."""
COMMUTATION_MARGIN = 30
"""Loop samples before a Hall sector change already disturbed by the commutation (8-25 measured
at 130-300 rpm on the virtual drive: e_L leaves its flat top before the sector changes)."""

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


def _ensure_mode(drive: Drive, mode: str, brake: bool = False) -> None:
    """Select ``mode``; an enabled drive is switched coasting, not braking
    (:func:`drive_link.restore.switch_mode`), and enabled again."""
    switch_mode(drive, mode, brake=brake)


def _require_enabled(drive: Drive, enable: bool) -> None:
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


def _describe_change(kind: str, found: Snapshot, plan: str) -> str:
    return f"{kind}: {plan}; afterwards the drive is put back to {found.describe()}"


def _upload(drive: Drive, hooks: Hooks) -> Trace:
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
        return _upload(drive, h)


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
    its pre-trigger part full (:meth:`~drive_link.trace.Recorder.wait_ready`: in the drive's
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
            return _upload(drive, h)
    raise AssertionError("unreachable")


def first_commutation(t: np.ndarray, i_abc: np.ndarray) -> float | None:
    """Time [s] of the first change of the non-conducting phase at t >= 0, or None.

    ``i_abc``: phase currents [A], shape (n, 3). In six-step operation two phases conduct; the
    third (smallest |i|) changes at every commutation, which disturbs i_p for a few samples.
    (:func:`current_step` uses the recorded Hall sector instead: one channel, no lag.)
    """
    t = np.asarray(t, dtype=float)
    idle = np.argmin(np.abs(np.asarray(i_abc, dtype=float)), axis=1)
    k0 = int(np.searchsorted(t, 0.0))
    change = np.flatnonzero(idle[k0 + 1 :] != idle[k0:-1])
    return float(t[k0 + 1 + change[0]]) if change.size else None


def sector_changes(t: np.ndarray, hall_sector: np.ndarray) -> np.ndarray:
    """Times [s] at which the Hall sector changes (commutations), over the whole record."""
    h = np.asarray(hall_sector)
    return np.asarray(t, dtype=float)[1:][h[1:] != h[:-1]]


def _settled(pre: np.ndarray, tol: float = 0.02) -> bool:
    """True if the pre-step samples show no drift: the means of their halves agree within
    ``tol`` [A] (a decaying disturbance shows as a trend; switching ripple averages out)."""
    if pre.size < 4:
        return True
    h = pre.size // 2
    return bool(abs(float(np.mean(pre[:h])) - float(np.mean(pre[h:]))) <= tol)


def _column(tr: Trace, name: str) -> np.ndarray:
    return np.asarray(tr.signals[f"measurements.{name}"], dtype=float)


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
    *,
    commutation_retries: int = COMMUTATION_RETRIES,
    average_samples: int = 1,
    hooks: Hooks | None = None,
    settle: Settle | None = None,
    brake: bool = False,
    found: Snapshot | None = None,
    restore: bool = True,
) -> StepResult:
    """Pseudo-current step i_from → i_to (A) in "current" mode.

    Sets the mode and i_from, enables (if ``enable``), waits ``settle_s`` s, arms the recorder
    (channels i_p, i_p_ref, v_L, e_L, hall_sector unless ``commutation_retries`` is 0, and
    ``extra``; ``divider`` loop samples per trace sample, ``length`` samples, ``pre_trigger``
    before the step) on "setpoint step", writes i_to and uploads. A record with a Hall sector
    change before the step or in its first :data:`CLEAN_FRACTION` after it is taken again
    (i_from, settle, step), as is one whose i_p still drifts before the step, up to
    ``commutation_retries`` times; the least disturbed one is kept.

    The prediction is :func:`drive_link.design.predicted_step` for the drive's controller type,
    L_c, R_c, k_p, k_i and motor R, L, with the back-EMF e_L measured just before the step. The
    metrics (of i_p averaged over ``average_samples``) and the model's RMS error [A] are taken
    up to :data:`COMMUTATION_MARGIN` loop samples before the first sector change after the step
    when at least 10 samples precede it.

    Leaves the drive as found (``restore``; ``found``: a snapshot the caller took before it
    changed anything itself): state, mode, setpoints, also on error and Ctrl-C; the mode
    switches coast unless ``brake``. Before the step i_p must be settled at i_from
    (:class:`Settle`, default window 50 ms, tolerance max(0.5 A, 5 % of the step); for a law
    without integral action, which settles with an error, steady within that tolerance).
    """
    if i_from == i_to:
        raise InvalidValue("current step needs i_from != i_to")
    h = hooks or Hooks()
    st = settle or Settle(window_s=0.05, timeout_s=5.0)
    tol = st.tol if st.tol is not None else max(0.5, 0.05 * abs(i_to - i_from))
    channels = ["i_p", "i_p_ref", "v_L", "e_L", *extra]
    hall = commutation_retries > 0 or "hall_sector" in extra
    if hall and "hall_sector" not in channels:
        channels.append("hall_sector")
    capacity = drive.trace.capacity
    if len(channels) * length > capacity:
        raise InvalidValue(
            f"{len(channels)} channels x {length} samples exceed the recorder's {capacity} "
            "samples: shorten the record"
        )
    snap = found if found is not None else snapshot(drive)
    h.announce(
        _describe_change(
            "current step", snap, f"current mode, i_p* {i_from:g} A, then {i_to:g} A"
        )
    )
    with _kept(drive, snap, restore, brake):
        _ensure_mode(drive, "current", brake)
        drive.set_current(i_from)
        _require_enabled(drive, enable)
        g0 = drive.read_gains()
        # a law without integral action (predictive; deadbeat with R_c = 0) settles with an
        # error: there the start is settled when steady, not when at i_from
        integral = not (g0.type == 2 or (g0.type == 0 and g0.R_c == 0))
        start = wait_settled(drive, "i_p", i_from if integral else None, tol, st, h, "A")
        tr, t_comm, attempt = _current_records(
            drive, channels, i_from, i_to, divider, length, pre_trigger, settle_s, timeout,
            commutation_retries, hall, h,
        )
        loop = (drive.read_gains(), float(drive.read("motor.R")), float(drive.read("motor.L")))
    return _current_result(
        loop, tr, t_comm, attempt, i_from, i_to, divider, average_samples, start,
        _describe_change("current step", snap, f"i_p* {i_from:g} → {i_to:g} A"), h,
    )


def _kept(drive: Drive, snap: Snapshot, restore: bool, brake: bool) -> Any:
    """:func:`leave_as_found` with ``snap``, or nothing when ``restore`` is False."""
    if not restore:
        return contextlib.nullcontext(snap)
    return leave_as_found(drive, found=snap, brake=brake)


def _current_records(
    drive: Drive,
    channels: list[str],
    i_from: float,
    i_to: float,
    divider: int,
    length: int,
    pre_trigger: int,
    settle_s: float,
    timeout: float | None,
    commutation_retries: int,
    hall: bool,
    h: Hooks,
) -> tuple[Trace, float | None, int]:
    """The current step's records, repeated while a commutation disturbs them (see
    :func:`current_step`): the least disturbed record, its first sector change, attempts."""
    tries = max(1, commutation_retries)
    best: tuple[tuple[bool, float], Trace, float | None] | None = None
    attempt = 0
    for attempt in range(1, tries + 1):
        h.report(0.2 * (attempt - 1) / tries, f"step {attempt}: settling at {i_from:g} A")
        if attempt > 1:
            drive.set_current(i_from)
        h.sleep(settle_s)
        tr = record_setpoint_step(
            drive,
            channels,
            lambda: drive.set_current(i_from),
            lambda: drive.set_current(i_to),
            divider,
            length,
            pre_trigger,
            timeout,
            hooks=h,
        )
        changes = sector_changes(tr.t, _column(tr, "hall_sector")) if hall else np.zeros(0)
        # a sector change before the step (or before the record: i_p still drifting back to
        # i_from) leaves a disturbance decaying over L/R into the step
        settled = not np.any(changes <= 0.0) and _settled(_column(tr, "i_p")[: tr.trigger_index])
        after = changes[changes > 0.0]
        t_comm = float(after[0]) if after.size else None
        score = (settled, math.inf if t_comm is None else t_comm)
        if best is None or score > best[0]:
            best = (score, tr, t_comm)
        if commutation_retries <= 0 or (settled and score[1] >= CLEAN_FRACTION * tr.t[-1]):
            break
    assert best is not None
    _, tr, t_comm = best
    return tr, t_comm, attempt


def _current_result(
    loop: tuple[Any, float, float],
    tr: Trace,
    t_comm: float | None,
    attempt: int,
    i_from: float,
    i_to: float,
    divider: int,
    average_samples: int,
    start: float,
    changes: str,
    h: Hooks,
) -> StepResult:
    """Metrics and the model's prediction of a recorded current step."""
    h.report(0.95, "model and metrics")
    g, R, L = loop
    k0 = tr.trigger_index
    i_p = _column(tr, "i_p")
    e_L = float(np.mean(tr.signals["measurements.e_L"][: max(k0, 1)]))
    controller = design.controller_name(g.type) if g.type in CONTROLLER_NAMES else "deadbeat"
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
    avg = metrics.moving_average(i_p, average_samples)
    use = np.ones(len(tr.t), dtype=bool)
    if t_comm is not None:
        clean = tr.t < t_comm - COMMUTATION_MARGIN * TS
        if np.sum(clean & (tr.t >= 0)) >= 10:
            use = clean
    m = metrics.step_metrics(
        tr.t[use], avg[use], reference=i_to, t_step=0.0, y_initial=float(i_from)
    )
    post = use[k0:]
    rms = float(np.sqrt(np.mean((avg[k0:][post] - y_pred[post]) ** 2)))
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
        "average_samples": average_samples,
        "Ts": TS,
        "model_stable": bool(pred.stable),
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
        commutation_at_s=t_comm,
        model_rms_error=rms,
        attempts=attempt,
        start=start,
        changes=changes,
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

    The prediction is :func:`drive_link.design.predicted_speed_step` with the drive's IP gains
    and the speed model ``model`` = (a, b) (default: the paper's, :data:`SPEED_MODEL_PAPER`;
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
    h.announce(_describe_change("speed step", snap, plan))
    channels = ["speed", "speed_ref", "i_p_ref", "i_p", *extra]
    with _kept(drive, snap, restore, brake):
        _ensure_mode(drive, "speed", brake)
        drive.set_speed(w0)
        _require_enabled(drive, enable)
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
        changes=_describe_change("speed step", snap, f"{w0:g} → {round(w1):g} rpm"),
    )


@dataclass
class Identification:
    """A speed-model identification (Fig. 16): the recorded current step ``trace`` (i_p A,
    speed rpm), the least-squares ``fit`` of ``G(z) = b/(z - a)`` at the loop rate
    (:class:`drive_link.identify.FirstOrderFit`) and ``model``: the identified model's free-run
    speed [rpm] on the trace's time base, driven by the measured i_p."""

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
    h.announce(_describe_change("identification", snap, plan))
    with _kept(drive, snap, restore, brake):
        _ensure_mode(drive, "current", brake)
        drive.set_current(i_from)
        _require_enabled(drive, enable)
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
    i_p = _column(tr, "i_p")
    speed = _column(tr, "speed")
    fit = identify.fit_first_order(i_p, speed, Ts=divider * TS)
    model = identify.simulate_first_order(fit.a_D, fit.b_D, i_p, speed[0], fit.offset)
    ident = Identification(tr, fit, model, float(i_from), float(i_to))
    ident.start_rpm = start
    ident.changes = _describe_change("identification", snap, f"i_p* {i_from:g} → {i_to:g} A")
    return ident
