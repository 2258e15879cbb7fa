"""Scenarios of a sweep run and their simulation: current step, speed step, load step, profile.

Every scenario starts settled: the shaft is set to its start speed, the load torque to its start
value, and the drive runs ``settle`` seconds (not recorded) in current mode at the current that
holds that speed (i_p = (B_tot w + T_load) / K_t of the run's own motor and load); a speed
scenario then switches to the IP speed loop, whose integral starts bumplessly at that current.
Then ``duration`` seconds are recorded (t = 0 at the end of the settling) with the event at
``at``. The simulator runs in chunks between events (one C call each, at most 0.1 s; no Python
per sample); a trip (EMCY) ends the run at the chunk where it happened.

Units: currents A, speeds rpm, torques N m, times s (strings with units are accepted in the
spec: ``"2 ms"``, ``"1500 rpm"``).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from virtual_drive.sim import Simulator
from virtual_drive.sim.params import RPM_PER_RAD_S, Ts
from virtual_drive.sweep.units import SpecError, to_si

__all__ = ["KINDS", "Scenario", "Trace", "parse_scenario", "simulate"]

KINDS = ("current_step", "speed_step", "load_step", "speed_profile")
_MAX_CHUNK = 5000  # samples per C call (0.1 s): a trip stops the run within this


@dataclass(frozen=True)
class Scenario:
    """One scenario: ``kind`` in KINDS; ``initial``/``final`` are A (current_step), rpm
    (speed_step) or N m (load_step); ``speed`` the start speed (rpm); ``points`` the
    profile's (t s, rpm) corners; ``update`` (s) how often the profile's reference is set."""

    name: str
    kind: str
    duration: float
    at: float = 0.0
    initial: float = 0.0
    final: float = 0.0
    speed: float = 0.0
    settle: float = 2e-3
    points: tuple[tuple[float, float], ...] = ()
    update: float = 1e-3
    limits: dict[str, Any] = field(default_factory=dict, compare=False, hash=False)

    @property
    def unit(self) -> str:
        """Unit of the controlled variable: "A" (i_p) or "rpm" (speed)."""
        return "A" if self.kind == "current_step" else "rpm"


def parse_scenario(d: dict[str, Any], index: int) -> Scenario:
    """A :class:`Scenario` from its TOML table (``[[scenarios]]`` entry ``index``)."""
    where = f"scenarios[{index}]"
    if not isinstance(d, dict):
        raise SpecError(f"{where}: must be a table")
    kind = d.get("kind")
    if kind not in KINDS:
        raise SpecError(f"{where}.kind must be one of {list(KINDS)}, got {kind!r}")
    known = {"name", "kind", "duration", "at", "from", "to", "speed", "settle", "points",
             "update", "limits"}  # fmt: skip
    extra = sorted(set(d) - known)
    if extra:
        raise SpecError(f"{where}: unknown key(s) {extra} (known: {sorted(known)})")
    unit = {"current_step": "A", "speed_step": "rpm", "load_step": "N*m"}.get(kind, "rpm")
    kw: dict[str, Any] = {"name": str(d.get("name", kind)), "kind": kind}
    if "duration" not in d:
        raise SpecError(f"{where}.duration is required (s)")
    kw["duration"] = to_si(d["duration"], "s", f"{where}.duration")
    kw["settle"] = to_si(d.get("settle", 2e-3), "s", f"{where}.settle")
    if kind != "speed_profile":
        for k in ("from", "to"):
            if k not in d:
                raise SpecError(f"{where}.{k} is required ({unit})")
        kw["initial"] = to_si(d["from"], unit, f"{where}.from")
        kw["final"] = to_si(d["to"], unit, f"{where}.to")
        kw["at"] = to_si(d.get("at", 0.0), "s", f"{where}.at")
        if not 0.0 <= kw["at"] < kw["duration"]:
            raise SpecError(f"{where}.at must be in [0, duration), got {kw['at']}")
        if kind == "speed_step" and "speed" in d:
            raise SpecError(f"{where}: a speed_step starts at its 'from' speed; no 'speed'")
        kw["speed"] = to_si(d.get("speed", 0.0), "rpm", f"{where}.speed")
        if kind == "speed_step":
            kw["speed"] = kw["initial"]
    else:
        pts = d.get("points")
        if not isinstance(pts, list) or len(pts) < 2:
            raise SpecError(f"{where}.points must be a list of >= 2 [t (s), speed (rpm)] pairs")
        try:
            pp = tuple((float(t), float(n)) for t, n in pts)
        except (TypeError, ValueError):
            raise SpecError(f"{where}.points must be [t (s), speed (rpm)] pairs") from None
        if pp[0][0] != 0.0 or any(b[0] <= a[0] for a, b in itertools.pairwise(pp)):
            raise SpecError(f"{where}.points: times must start at 0 and increase")
        kw["points"] = pp
        kw["speed"] = pp[0][1]
        kw["update"] = to_si(d.get("update", 1e-3), "s", f"{where}.update")
        if kw["update"] < Ts:
            raise SpecError(f"{where}.update must be >= Ts = {Ts} s")
        kw["at"] = pp[-2][0] if pp[-1][1] == pp[-2][1] else pp[-1][0]
        if kw["duration"] < pp[-1][0]:
            raise SpecError(f"{where}.duration must cover the profile ({pp[-1][0]} s)")
    if kw["duration"] <= 0.0 or kw["settle"] < 0.0:
        raise SpecError(f"{where}: duration must be > 0 and settle >= 0")
    bound = {"current_step": 1000.0, "speed_step": 20000.0, "load_step": 50.0}.get(kind)
    if bound is not None and max(abs(kw["initial"]), abs(kw["final"])) > bound:
        raise SpecError(f"{where}: from / to must be within +-{bound:g} {unit}")
    if max([abs(kw["speed"]), *(abs(p[1]) for p in kw.get("points", ()))]) > 20000.0:
        raise SpecError(f"{where}: speeds must be within +-20000 rpm")
    lim = d.get("limits", {})
    if not isinstance(lim, dict):
        raise SpecError(f"{where}.limits must be a table")
    kw["limits"] = dict(lim)
    return Scenario(**kw)


@dataclass
class Trace:
    """What a run recorded (arrays of ``n`` samples, t = k Ts from the end of the settling):
    ``y`` the controlled variable (i_p A or speed rpm), ``r`` its reference, ``i_peak`` the
    largest |phase current| per sample (A), ``speed`` (rpm), ``e_i`` the current loop's error
    i_p* - i_p (A); ``k_event`` the sample of the
    (last) event; ``fault`` the EMCY code (0 none) and ``fault_t`` its time (s)."""

    y: np.ndarray
    r: np.ndarray
    i_peak: np.ndarray
    speed: np.ndarray
    e_i: np.ndarray
    k_event: int
    n_planned: int
    fault: int = 0
    fault_t: float = math.nan

    @property
    def n(self) -> int:
        return int(self.y.shape[0])


def _steady_current(inputs: dict[str, Any], rpm: float, T_load: float) -> float:
    """i_p (A) that holds ``rpm`` against the run's load: (B_tot w + T_load) / K_t, with
    B_tot = B + k_gen (60 / 2 pi) (N m s/rad) and K_t = K_rpm (60 / 2 pi) (N m/A)."""
    B: float = inputs["B"]  # (the run's values by name: the spec's variables, checked there)
    k_gen: float = inputs["k_gen"]
    K_rpm: float = inputs["K_rpm"]
    B_tot = B + k_gen * RPM_PER_RAD_S
    return (B_tot * rpm / RPM_PER_RAD_S + T_load) / (K_rpm * RPM_PER_RAD_S)


def _reference(sc: Scenario, n: int) -> np.ndarray:
    """Reference of the controlled variable per recorded sample (the profile as the
    staircase the controller is given, one value per ``update``)."""
    k_at = round(sc.at / Ts)
    if sc.kind == "current_step" or sc.kind == "speed_step":
        r = np.full(n, sc.initial, dtype=np.float64)
        r[k_at:] = sc.final
        return r
    if sc.kind == "load_step":
        return np.full(n, sc.speed, dtype=np.float64)
    step = max(1, round(sc.update / Ts))
    starts = np.arange(0, n, step)
    ts, ns = zip(*sc.points, strict=True)
    vals = np.interp(starts * Ts, ts, ns)
    return np.repeat(vals, step)[:n].astype(np.float64)


_RECORDED = ("i_p", "i_a", "i_b", "i_c", "speed", "i_p_ref")
_BUF: dict[str, np.ndarray] = {}


def _buffers(n: int) -> dict[str, np.ndarray]:
    """This process's record buffers, grown to at least ``n`` samples (views of length n)."""
    if not _BUF or _BUF["i_p"].shape[0] < n:
        for k in _RECORDED:
            _BUF[k] = np.empty(n, dtype=np.float32)
    return {k: v[:n] for k, v in _BUF.items()}


def _events(sc: Scenario, r: np.ndarray) -> list[int]:
    """Sample indices where the loop stops to change a setpoint (sorted, < len(r))."""
    n = r.shape[0]
    if sc.kind == "speed_profile":
        step = max(1, round(sc.update / Ts))
        return [k for k in range(step, n, step) if r[k] != r[k - 1]]
    k_at = round(sc.at / Ts)
    return [k_at] if 0 <= k_at < n else []


def simulate(
    sim: Simulator, sc: Scenario, inputs: dict[str, Any], reuse: bool = False
) -> Trace:
    """Run ``sc`` on ``sim`` (fresh, built from ``inputs``: the run's B, k_gen, K_rpm,
    T_load are read from there) and return the :class:`Trace`. With ``reuse`` the record
    lives in this process's buffers (no page faults of fresh memory per run) and the trace's
    arrays are overwritten by the next ``simulate(..., reuse=True)``."""
    n = max(1, round(sc.duration / Ts))
    k_event = min(round(sc.at / Ts), n - 1)
    r = _reference(sc, n)
    T0 = sc.initial if sc.kind == "load_step" else inputs["T_load"]
    sim.set_speed(sc.speed)
    if T0 != inputs["T_load"]:
        sim.set_load(T_load=T0)
    speed_mode = sc.kind != "current_step"
    i0 = sc.initial if sc.kind == "current_step" else _steady_current(inputs, sc.speed, T0)
    sim.set_mode("current")
    sim.set_current_ref(max(-1000.0, min(1000.0, i0)))
    n_settle = round(sc.settle / Ts)
    if n_settle:
        sim.run(n_settle, record=False)
    if speed_mode and sim.fault is None:
        sim.set_mode("speed")
        sim.set_speed_ref(r[0])
    rec = _buffers(n) if reuse else {k: np.empty(n, dtype=np.float32) for k in _RECORDED}
    done = 0
    fault = sim.fault
    stops = [*_events(sc, r), n]
    for stop in stops:
        while done < stop and fault is None:
            m = min(_MAX_CHUNK, stop - done)
            sim.run_record(m, rec, done)
            done += m
            fault = sim.fault
        if fault is not None or done >= n:
            break
        # the setpoint change at sample `done`
        if sc.kind == "current_step":
            sim.set_current_ref(r[done])
        elif sc.kind == "load_step":
            sim.set_load(T_load=sc.final)
        else:
            sim.set_speed_ref(r[done])
    keep = done
    i_abs = np.maximum(np.maximum(np.abs(rec["i_a"][:keep]), np.abs(rec["i_b"][:keep])),
                       np.abs(rec["i_c"][:keep]))  # fmt: skip
    y = rec["i_p"][:keep] if sc.kind == "current_step" else rec["speed"][:keep]
    return Trace(
        y=y,
        r=r[:keep],
        i_peak=i_abs,
        speed=rec["speed"][:keep],
        e_i=rec["i_p_ref"][:keep] - rec["i_p"][:keep],
        k_event=k_event,
        n_planned=n,
        fault=0 if fault is None else int(fault.code),
        fault_t=math.nan if fault is None else float(fault.t) - n_settle * Ts,
    )
