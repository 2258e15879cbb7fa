"""Recorder-based experiments as the dashboard shows them: a trace capture, the current step test
(Fig. 13, with the model's predicted response) and the speed-model identification (Fig. 16).

The experiments themselves are drive_link's (:mod:`drive_link.workflows.steps`: recording,
commutation retries, the model prediction with the measured back-EMF, metrics, the least-squares
fit); this module runs them as a long action of the bench (deadline, progress, cancel, the drive put
back as found on failure) and turns their results into captures for the plots and downloads. Times
in s, currents in A, speed in rpm; the loop period Ts is 20 µs (fs = 50 kHz).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from dashboard._actions import LongAction
from dashboard._bench import Bench, Capture, as_dict
from dashboard._models import CurrentStepIn, IdentifyIn, TraceIn
from drive_link import Trigger
from drive_link.link.trace import TS
from drive_link.workflows import metrics, steps

__all__ = ["capture", "current_step", "identify"]

CURRENT_STEP_DEADLINE_S = 30.0  #: a current step test gives up (and restores) after this, s
IDENTIFY_DEADLINE_S = 20.0  #: identification: this plus 4 × (recorded time) / speed factor, s


def _hooks(act: LongAction) -> steps.Hooks:
    """drive_link's waits and progress reports through the bench's long action (cancellable,
    bounded by its deadline)."""
    return steps.Hooks(progress=act.progress, sleep=act.sleep)


def _short(name: str) -> str:
    return name.removeprefix("measurements.")


def _columns(tr: Any) -> dict[str, np.ndarray]:
    cols: dict[str, np.ndarray] = {"t": np.asarray(tr.t, dtype=np.float64)}
    for name, v in tr.signals.items():
        cols[_short(name)] = np.asarray(v, dtype=np.float64)
    return cols


def _speed_factor(bench: Bench) -> float:
    """Simulated seconds per wall-clock second of the virtual drive (1 for a real one)."""
    if not bench.virtual:
        return 1.0
    try:
        f = float(bench.drive.read("sim_info.speed_factor"))
        return f if f > 0 else 1.0
    except Exception:
        return 1.0


def capture(bench: Bench, body: TraceIn) -> Capture:
    """One trace as configured by ``body`` (drive_link.workflows.steps.record); adds ī_p (moving
    average) when i_p is recorded."""
    trig = Trigger(
        mode=body.trigger,
        source=body.channels[0],
        level=body.trigger_level or 0.0,
        edge=body.trigger_edge,
    )
    action = None
    step_to_A = body.step_to_A
    if body.trigger == "setpoint_step" and step_to_A is not None:

        def action() -> None:
            bench.set_current(step_to_A)

    sf = _speed_factor(bench)
    deadline = 10.0 + 4.0 * body.length * body.divider * TS / sf
    with bench.long_action("capture", deadline) as act:
        tr = steps.record(
            bench.drive,
            list(body.channels),
            divider=body.divider,
            length=body.length,
            pre_trigger=body.pre_trigger,
            trigger=trig,
            action=action,
            timeout=3.0 + 3.0 * body.length * body.divider * TS / sf,
            hooks=_hooks(act),
        )
    cols = _columns(tr)
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


def current_step(bench: Bench, body: CurrentStepIn, average_samples: int = 1) -> dict[str, Any]:
    """Current step from_A → to_A in current mode, recorded at 50 kHz (divider 1) for
    ``duration_ms`` after the step (drive_link.workflows.steps.current_step: commutation retries,
    the model's predicted response with the measured e_L, metrics of i_p averaged over
    ``average_samples``); kept as a capture with the model overlaid."""
    if body.from_A == body.to_A:
        raise ValueError("from_A and to_A must differ")
    n_post = max(10, round(body.duration_ms * 1e-3 / TS))
    pre = max(5, n_post // 10)
    with bench.long_action("current step", CURRENT_STEP_DEADLINE_S) as act:
        # drive_link switches to current mode (coasting) and leaves the drive as found
        res = steps.current_step(
            bench.drive,
            body.from_A,
            body.to_A,
            divider=1,
            length=pre + n_post,
            pre_trigger=pre,
            settle_s=0.05 / _speed_factor(bench) + 0.02,
            average_samples=average_samples,
            hooks=_hooks(act),
        )
    tr = res.trace
    cols = _columns(tr)
    i_p = cols.pop("i_p")
    cols = {
        "t": cols.pop("t"),
        "i_p": i_p,
        "i_p_avg": metrics.moving_average(i_p, average_samples),
        "i_p_ref": cols.pop("i_p_ref"),
        "model": res.model_column(),
        **cols,
    }
    controller = res.params["controller"]
    cap = bench.add_capture(
        "current_step",
        cols,
        {
            "controller": controller,
            "from_A": body.from_A,
            "to_A": body.to_A,
            "L_c": res.params["L_c"],
            "R_c": res.params["R_c"],
            "e_L": res.params["e_L"],
            "average_samples": average_samples,
            "commutation_at_s": res.commutation_at_s,
            "attempts": res.attempts,
        },
    )
    md = as_dict(res.metrics)
    return {
        "capture": cap.summary(),
        "controller": controller,
        "metrics": {
            "rise_time_s": md["rise_time"],
            "settling_time_s": md["settling_time"],
            "overshoot_pct": md["overshoot_pct"],
            "steady_state_error_A": md["steady_state_error"],
            "y_final_A": md["y_final"],
        },
        "commutation_at_s": res.commutation_at_s,
        "model_rms_error_A": res.model_rms_error,
        "model_stable": res.params["model_stable"],
        "e_L_V": res.params["e_L"],
    }


def identify(bench: Bench, body: IdentifyIn) -> dict[str, Any]:
    """Current step in current mode, trace of i_p and speed, least-squares fit of
    G(z) = b/(z − a) at the loop rate (drive_link.workflows.steps.identify_speed_model); the fit is
    kept for the IP design and the drive is put back as found."""
    if body.from_A == body.to_A:
        raise ValueError("from_A and to_A must differ")
    sf = _speed_factor(bench)
    deadline = IDENTIFY_DEADLINE_S + 4.0 * (body.duration_s + 0.1) / sf
    with bench.long_action("identification", deadline) as act:
        ident = steps.identify_speed_model(  # leaves the drive as found (workflows.steps)
            bench.drive,
            body.from_A,
            body.to_A,
            duration_s=body.duration_s,
            settle_s=0.1 / sf + 0.02,
            hooks=_hooks(act),
        )
    tr, fit = ident.trace, ident.fit
    cols = _columns(tr)
    bench.identified = {"a": fit.a, "b": fit.b, "Ts": TS, "r2": fit.r2}
    cap = bench.add_capture(
        "identification",
        {"t": cols["t"], "i_p": cols["i_p"], "speed": cols["speed"], "model": ident.model},
        {"a": fit.a, "b": fit.b, "divider": tr.divider, "r2": fit.r2},
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
        "divider": tr.divider,
    }
