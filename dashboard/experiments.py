"""Recorder-based experiments: a trace capture, the current step test (Fig. 13, with the model's
predicted response) and the speed-model identification (Fig. 16). Times in s, currents in A,
speed in rpm; the loop period Ts is 20 µs (fs = 50 kHz)."""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from dashboard.actions import LongAction, wait_recorder
from dashboard.bench import Bench, Capture, as_dict
from dashboard.models import CurrentStepIn, IdentifyIn, TraceIn
from dashboard.tuning import read_gains
from drive_link import Trigger, design, metrics
from drive_link import identify as ident

TS = 20e-6  #: loop period, s
COMMUTATION_RETRIES = 4  #: current-step records repeated when a commutation disturbs them
CURRENT_STEP_DEADLINE_S = 30.0  #: a current step test gives up (and restores) after this, s
IDENTIFY_DEADLINE_S = 20.0  #: identification: this plus 4 × (recorded time) / speed factor, s


def _column(trace: Any, name: str) -> np.ndarray:
    for key in (name, f"measurements.{name}"):
        if key in trace.signals:
            return np.asarray(trace.signals[key], dtype=np.float64)
    raise KeyError(f"trace has no channel {name} ({', '.join(trace.signals)})")


def _short(name: str) -> str:
    return name.removeprefix("measurements.")


def _record(
    bench: Bench,
    channels: list[str],
    *,
    divider: int,
    length: int,
    pre_trigger: int,
    trigger: Trigger,
    action: Any = None,
    timeout: float | None = None,
    act: LongAction | None = None,
) -> Any:
    """Configure, arm, run ``action`` (e.g. a setpoint step), wait, upload; returns the Trace.
    With ``act`` (a long action) the waits are cancellable and bounded by its deadline."""
    rec = bench.drive.trace
    rec.stop()
    # drive_link writes length before pre_trigger, and the drive requires pre_trigger < length
    # at every write: clear the old pre_trigger first so a shorter record is accepted.
    bench.drive.write("trace_config.pre_trigger", 0)
    rec.configure(channels, divider, length, pre_trigger, trigger)
    rec.arm()
    if pre_trigger:  # let the pre-trigger buffer fill before the step
        pause = min(2.0, pre_trigger * divider * TS / _speed_factor(bench) + 0.02)
        act.sleep(pause) if act is not None else time.sleep(pause)
    if action is not None:
        action()
    if timeout is None:
        timeout = 3.0 + 3.0 * length * divider * TS / _speed_factor(bench)
    if act is None:
        rec.wait(timeout)
        return rec.upload()
    act.progress(0.3, "recording")
    wait_recorder(rec, act, timeout)
    act.progress(0.6, "uploading the trace")

    def uploaded(done: int, total: int | None) -> None:
        if total:
            act.fraction = 0.6 + 0.3 * done / total
            act.text = f"uploading the trace ({done}/{total} bytes)"

    return rec.upload(progress=uploaded)


def _speed_factor(bench: Bench) -> float:
    if not bench.virtual:
        return 1.0
    try:
        f = float(bench.drive.read("sim_info.speed_factor"))
        return f if f > 0 else 1.0
    except Exception:
        return 1.0


def capture(bench: Bench, body: TraceIn) -> Capture:
    """One trace as configured by ``body``; adds ī_p (moving average) when i_p is recorded."""
    trig = Trigger(
        mode=body.trigger,
        source=body.channels[0],
        level=body.trigger_level or 0.0,
        edge=body.trigger_edge,
    )
    action = None
    if body.trigger == "setpoint_step" and body.step_to_A is not None:

        def action() -> None:
            bench.set_current(body.step_to_A)

    deadline = 10.0 + 4.0 * body.length * body.divider * TS / _speed_factor(bench)
    with bench.long_action("capture", deadline) as act:
        tr = _record(
            bench,
            list(body.channels),
            divider=body.divider,
            length=body.length,
            pre_trigger=body.pre_trigger,
            trigger=trig,
            action=action,
            act=act,
        )
    cols: dict[str, np.ndarray] = {"t": np.asarray(tr.t, dtype=np.float64)}
    for name, v in tr.signals.items():
        cols[_short(name)] = np.asarray(v, dtype=np.float64)
    if "i_p" in cols:
        cols["i_p_avg"] = metrics.moving_average(cols["i_p"], body.average_samples)
    meta = {
        "divider": tr.divider,
        "dt_s": tr.dt,
        "trigger_index": tr.trigger_index,
        "trigger": body.trigger,
        "average_samples": body.average_samples,
    }
    return bench.add_capture("trace", cols, meta)


def first_commutation(t: np.ndarray, i_abc: np.ndarray) -> float | None:
    """Time (s) of the first change of the non-conducting phase at t ≥ 0, or None.

    ``i_abc``: phase currents (A), shape (n, 3). In six-step operation two phases conduct; the
    third (smallest |i|) changes at every commutation, which disturbs i_p for a few samples.
    """
    idle = np.argmin(np.abs(i_abc), axis=1)
    k0 = int(np.searchsorted(t, 0.0))
    change = np.flatnonzero(idle[k0 + 1 :] != idle[k0:-1])
    return float(t[k0 + 1 + change[0]]) if change.size else None


def current_step(bench: Bench, body: CurrentStepIn, average_samples: int = 1) -> dict[str, Any]:
    """Current step from_A → to_A in current mode, recorded at 50 kHz (divider 1), with its
    metrics and the model's predicted response (drive_link.design.predicted_step) overlaid.

    The phase currents are recorded too: a commutation disturbs i_p for a few samples, so a
    record with one in its first 80 % is repeated (up to COMMUTATION_RETRIES times); one in the
    last 20 % is cut off (5 samples of margin) and ``commutation_at_s`` says where.
    """
    if body.from_A == body.to_A:
        raise ValueError("from_A and to_A must differ")
    g = read_gains(bench)
    n_post = max(10, round(body.duration_ms * 1e-3 / TS))
    pre = max(5, n_post // 10)
    length = pre + n_post
    channels = ["measurements.i_p", "measurements.i_p_ref"] + [
        f"measurements.i_{ph}" for ph in "abc"
    ]
    if len(channels) * length > 16384:
        raise ValueError("duration too long for the recorder at 50 kHz")
    with bench.long_action("current step", CURRENT_STEP_DEADLINE_S) as act:
        for attempt in range(COMMUTATION_RETRIES):
            act.progress(attempt / COMMUTATION_RETRIES * 0.2, f"step {attempt + 1}: settling")
            bench.set_current(body.from_A)
            if str(bench.drive.state).upper() != "OPERATION ENABLED":
                bench.drive.enable(timeout=2.0)
            act.sleep(0.05 / _speed_factor(bench) + 0.02)
            tr = _record(
                bench,
                channels,
                divider=1,
                length=length,
                pre_trigger=pre,
                trigger=Trigger(mode="setpoint_step"),
                action=lambda: bench.set_current(body.to_A),
                act=act,
            )
            t = np.asarray(tr.t, dtype=np.float64)
            i_abc = np.column_stack([_column(tr, f"i_{ph}") for ph in "abc"])
            t_comm = first_commutation(t, i_abc)
            if t_comm is None or t_comm >= 0.8 * t[-1]:
                break
        else:
            raise RuntimeError(
                f"a commutation fell inside the record {COMMUTATION_RETRIES} times: "
                "shorten duration_ms or lower the speed"
            )
    i_p = _column(tr, "i_p")
    i_ref = _column(tr, "i_p_ref")
    n_after = int(np.sum(t >= 0))
    pred = design.predicted_step(
        g["type"],
        n_samples=n_after,
        i_start=body.from_A,
        i_final=body.to_A,
        R=g["motor_R"],
        L=g["motor_L"],
        L_c=g["L_c"],
        R_c=g["R_c"],
        k_p=g["k_p"],
        k_i=g["k_i"],
    )
    model = np.full(t.size, float(body.from_A))
    model[t >= 0] = pred.i_p[:n_after]
    avg = metrics.moving_average(i_p, average_samples)
    use = t < (t_comm - 5 * TS) if t_comm is not None else np.ones(t.size, bool)
    m = metrics.step_metrics(
        t[use], avg[use], reference=body.to_A, t_step=0.0, y_initial=body.from_A
    )
    post = use & (t >= 0)
    rms = float(np.sqrt(np.mean((avg[post] - model[post]) ** 2)))
    cols = {"t": t, "i_p": i_p, "i_p_avg": avg, "i_p_ref": i_ref, "model": model}
    cols.update({f"i_{ph}": i_abc[:, k] for k, ph in enumerate("abc")})
    cap = bench.add_capture(
        "current_step",
        cols,
        {
            "controller": g["type"],
            "from_A": body.from_A,
            "to_A": body.to_A,
            "L_c": g["L_c"],
            "R_c": g["R_c"],
            "average_samples": average_samples,
            "commutation_at_s": t_comm,
        },
    )
    md = as_dict(m)
    return {
        "capture": cap.summary(),
        "controller": g["type"],
        "metrics": {
            "rise_time_s": md["rise_time"],
            "settling_time_s": md["settling_time"],
            "overshoot_pct": md["overshoot_pct"],
            "steady_state_error_A": md["steady_state_error"],
            "y_final_A": md["y_final"],
        },
        "commutation_at_s": t_comm,
        "model_rms_error_A": rms,
        "model_stable": bool(pred.stable),
    }


def identify(bench: Bench, body: IdentifyIn) -> dict[str, Any]:
    """Current step in current mode, trace of i_p and speed, least-squares fit of
    G(z) = b/(z − a) at the loop rate (drive_link.identify); the fit is kept for the IP design."""
    if body.from_A == body.to_A:
        raise ValueError("from_A and to_A must differ")
    divider = max(1, math.ceil(body.duration_s / (8000 * TS)))
    n_post = round(body.duration_s / (divider * TS))
    pre = max(10, n_post // 20)
    length = min(8192, pre + n_post)
    sf = _speed_factor(bench)
    deadline = IDENTIFY_DEADLINE_S + 4.0 * (body.duration_s + 0.1) / sf
    with bench.long_action("identification", deadline) as act:
        act.progress(0.05, f"settling at {body.from_A:g} A")
        bench.set_current(body.from_A)
        if not str(bench.drive.state).upper().startswith("OPERATION ENABLED"):
            bench.drive.enable(timeout=2.0)
        act.sleep(0.1 / sf + 0.02)
        tr = _record(
            bench,
            ["measurements.i_p", "measurements.speed"],
            divider=divider,
            length=length,
            pre_trigger=pre,
            trigger=Trigger(mode="setpoint_step"),
            action=lambda: bench.set_current(body.to_A),
            act=act,
        )
        act.progress(0.95, "fitting")
        # the motor ran up to to_A: take it back to where it was (the fit needs no drive)
        bench.restore(act.found)
    t = np.asarray(tr.t, dtype=np.float64)
    i_p = _column(tr, "i_p")
    speed = _column(tr, "speed")
    fit = ident.fit_first_order(i_p, speed, Ts=tr.dt)
    model = ident.simulate_first_order(fit.a_D, fit.b_D, i_p, speed[0], fit.offset)
    bench.identified = {"a": fit.a, "b": fit.b, "Ts": TS, "r2": fit.r2}
    cap = bench.add_capture(
        "identification",
        {"t": t, "i_p": i_p, "speed": speed, "model": model},
        {"a": fit.a, "b": fit.b, "divider": divider, "r2": fit.r2},
    )
    bench.emit("identified", bench.identified)
    return {
        "capture": cap.summary(),
        "a": fit.a,
        "b": fit.b,
        "r2": fit.r2,
        "rms_error_rpm": fit.rms,
        "time_constant_s": fit.time_constant,
        "dc_gain_rpm_per_A": fit.dc_gain,
        "Ts": TS,
        "divider": divider,
    }
