"""Step tests and the speed-model identification, recorded by the drive's trace recorder and
triggered by the step itself (trigger_mode "on setpoint step"), with metrics
(:mod:`drive_link.workflows.metrics`), the response the model predicts
(:mod:`drive_link.workflows.design`) for the drive's present parameters, and the least-squares fit
of ``G(z) = b/(z - a)`` (:mod:`drive_link.workflows.identify`). ``drive-link
step``/``identify-drive`` and the dashboard both run these; the dashboard passes :class:`Hooks` to
show progress and to cancel.

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

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from firmware_protocol import enums

from ..errors import InvalidValue
from ..link.trace import TS, Trace
from . import design, metrics
from ._speed_steps import (
    SPEED_MODEL_PAPER,
    Identification,
    identification_record,
    identify_speed_model,
    speed_step,
)
from ._step_record import (
    Hooks,
    NotSettled,
    Settle,
    StepResult,
    column,
    describe_change,
    ensure_mode,
    kept,
    record,
    record_setpoint_step,
    require_enabled,
    wait_settled,
)
from .restore import Snapshot, snapshot

if TYPE_CHECKING:
    from ..link.drive import Drive

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
    "ensure_mode",
    "first_commutation",
    "identification_record",
    "identify_speed_model",
    "record",
    "record_setpoint_step",
    "require_enabled",
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

CONTROLLER_NAMES = enums.CONTROLLER_NAMES


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
    # (numpy's stubs type an index by an array as Any: the result is a float array)
    times: np.ndarray = np.asarray(t, dtype=float)[1:][h[1:] != h[:-1]]
    return times


def _settled(pre: np.ndarray, tol: float = 0.02) -> bool:
    """True if the pre-step samples show no drift: the means of their halves agree within
    ``tol`` [A] (a decaying disturbance shows as a trend; switching ripple averages out)."""
    if pre.size < 4:
        return True
    h = pre.size // 2
    return bool(abs(float(np.mean(pre[:h])) - float(np.mean(pre[h:]))) <= tol)


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

    The prediction is :func:`drive_link.workflows.design.predicted_step` for the drive's controller
    type, L_c, R_c, k_p, k_i and motor R, L, with the back-EMF e_L measured just before the step.
    The metrics (of i_p averaged over ``average_samples``) and the model's RMS error [A] are taken
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
        describe_change(
            "current step", snap, f"current mode, i_p* {i_from:g} A, then {i_to:g} A"
        )
    )
    with kept(drive, snap, restore, brake):
        ensure_mode(drive, "current", brake)
        drive.set_current(i_from)
        require_enabled(drive, enable)
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
        describe_change("current step", snap, f"i_p* {i_from:g} → {i_to:g} A"), h,
    )


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
        changes = sector_changes(tr.t, column(tr, "hall_sector")) if hall else np.zeros(0)
        # a sector change before the step (or before the record: i_p still drifting back to
        # i_from) leaves a disturbance decaying over L/R into the step
        settled = not np.any(changes <= 0.0) and _settled(column(tr, "i_p")[: tr.trigger_index])
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
    i_p = column(tr, "i_p")
    e_L = float(np.mean(tr.signals["measurements.e_L"][: max(k0, 1)]))
    controller = design.controller_name(g.type) if g.type in CONTROLLER_NAMES else "deadbeat"
    n_after = len(tr.t) - k0
    loop_pars = design.CurrentLoopPars(controller, R, L, g.L_c, g.R_c, g.k_p, g.k_i)
    pred = design.predict_step(
        loop_pars, n_samples=n_after * divider, i_start=i_from, i_final=i_to, e_L=e_L
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


