"""The bench: one drive (through drive_link only), the control lease and the bench's own state.

The REST API and the viser GUI both call this class; it serialises drive commands with one lock so
that two clients never interleave a half-applied gain set or a capture. Units: rpm, A, s, H, Ω.
"""

from __future__ import annotations

import contextlib
import dataclasses
import itertools
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

from dashboard._actions import Found, LongAction
from dashboard._known import STALE_LIMITS_S, DriveWatch, live_ages, state_name
from dashboard._security import ControlLease
from dashboard._setpoints import SetpointLink
from drive_link import jsonable
from firmware_protocol import emcy_codes
from firmware_protocol.od import load_od

__all__ = [
    "EMCY_TEXT",
    "LIVE_NAMES",
    "LIVE_SIGNALS",
    "SEQUENCE_SLACK_S",
    "STATUS_FIELDS",
    "STATUS_PERIOD_S",
    "STORE_PERIOD_S",
    "Bench",
    "Capture",
    "as_dict",
]

#: The staged gain-set names (0x20F0) → the live object each one mirrors (docs/contracts.md §1).
LIVE_NAMES: dict[str, str] = {
    "type": "current_controller.type",
    "L_c": "current_controller.L_c",
    "R_c": "current_controller.R_c",
    "k_p": "current_controller.k_p",
    "k_i": "current_controller.k_i",
    "T_BT": "current_controller.T_BT",
    "T_DD": "current_controller.T_DD",
    "T_SD": "current_controller.T_SD",
    "V_G": "current_controller.V_G",
    "emf_feedforward": "current_controller.emf_feedforward",
    "speed_k_p": "speed_controller.k_p",
    "speed_k_i": "speed_controller.k_i",
    "speed_current_limit": "speed_controller.current_limit",
}

#: Live plot signals in Drive.live.window() (OD names of the TPDO2/TPDO3 objects).
LIVE_SIGNALS = (
    "measurements.speed",
    "measurements.speed_ref",
    "measurements.i_p",
    "measurements.i_p_ref",
)


def as_dict(obj: Any) -> dict[str, Any]:
    """A plain dict of a dataclass / mapping / object with attributes (for JSON)."""
    if obj is None:
        return {}
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return dataclasses.asdict(obj)
    if isinstance(obj, dict):
        return dict(obj)
    return {k: v for k, v in vars(obj).items() if not k.startswith("_")}


#: Drive.status() fields shown by the dashboard (added by drive_link; absent ones are None).
STATUS_FIELDS = (
    "bus_state",
    "bus_error_frames",
    "store_status",
    "boots_seen",
    "supervision_rearmed_at",
)
SEQUENCE_SLACK_S = 5.0  #: a sequence step later than this (busy host) stops the sequence, s
STATUS_PERIOD_S = 2.0  #: (older name, unused) the status is no longer read by SDO in state()
STORE_PERIOD_S = 10.0  #: the parameter store's health (one SDO read) at most this often (s)

EMCY_TEXT = emcy_codes.MEANINGS
"""EMCY error code -> meaning for display (:mod:`firmware_protocol.emcy_codes`)."""


@dataclasses.dataclass
class Capture:
    """One recorded data set kept for download: equally long columns, "t" (s) first."""

    id: int
    kind: str
    columns: dict[str, np.ndarray]
    meta: dict[str, Any]
    created: float = dataclasses.field(default_factory=time.time)

    def summary(self) -> dict[str, Any]:
        n = len(next(iter(self.columns.values()))) if self.columns else 0
        return {
            "id": self.id,
            "kind": self.kind,
            "columns": list(self.columns),
            "samples": n,
            "created": self.created,
            "meta": jsonable(self.meta),
        }


class Bench:
    """One drive on one bus, shared by every client of the dashboard.

    drive: a connected ``drive_link.Drive``. description: what to show as "bus" (e.g.
    "socketcand 127.0.0.1:29536 (virtual)"). virtual: whether the virtual-drive-only objects
    (sim_load, sim_info) may be used.
    """

    def __init__(self, drive: Any, *, description: str, node_id: int, virtual: bool) -> None:
        self.drive = drive
        self.description = description
        self.node_id = node_id
        self.virtual = virtual
        self.hub_port: int | None = None  # loopback hub this bench started (virtual), if any
        self.lease = ControlLease()
        self.lock = threading.RLock()  # one drive command sequence at a time
        self.speed_setpoint = 0.0  # rpm, last commanded
        self.current_setpoint = 0.0  # A, last commanded
        self.T_load = 0.0
        self.identified: dict[str, float] | None = None  # {"a","b","Ts"} of the last fit
        #: the drive's gain set (with motor_R, motor_L, L_c_over_L) and its motor (R, L,
        #: rated_current, V_dc_nominal) as last read back or applied (:mod:`dashboard._tuning`
        #: keeps them): previews, diffs and an Apply start from them instead of reading again
        self.gains: dict[str, Any] | None = None
        self.motor: dict[str, float] | None = None
        self.captures: dict[int, Capture] = {}
        self._ids = itertools.count(1)
        self._sequence: threading.Thread | None = None
        self._sequence_stop = threading.Event()
        self.last_step_t: float | None = None  # time.monotonic() of the last setpoint step
        self.listeners: list[Callable[[str, dict], None]] = []
        self.busy: str | None = None  # a long operation under way (capture, identify ...)
        from dashboard._models import TraceIn

        #: default for POST /api/trace/capture without a body
        self.trace_config = TraceIn.model_validate({})
        self.sequence_progress: dict[str, Any] | None = None
        self.action: LongAction | None = None  # the long action under way (progress, cancel)
        #: SDO-only values (mode, parameter store) read in a worker of its own: state()
        #: never waits on an SDO timeout
        self.watch = DriveWatch(drive, busy=lambda: self.action is not None).start()
        self.setpoints = SetpointLink(drive)  # by RPDO where mapped, else SDO; no reads

    # ---------------------------------------------------------------- events
    def emit(self, kind: str, data: dict | None = None) -> None:
        """Tell the GUI / streams about something that happened (gains applied, capture ...)."""
        for cb in list(self.listeners):
            try:
                cb(kind, data or {})
            except Exception:  # a broken listener must not break a drive command
                pass

    # ---------------------------------------------------------------- state
    def state(self) -> dict[str, Any]:
        """Connection and drive state for display, built from what is known (never an SDO
        read: see :mod:`dashboard._known`), answered in well under 100 ms whatever the drive
        or the bus do.

        ``ages_s``: the age (s) of each part (``live``: newest TPDO sample; ``heartbeat``;
        ``statusword``: the CiA 402 state; ``mode``; ``store_status``), None before the first;
        ``stale``: the parts older than their limit (:data:`dashboard._known.STALE_LIMITS_S`).
        Also the fields of ``drive_link.Drive.status()`` named in :data:`STATUS_FIELDS`."""
        d = self.drive
        now, wall = time.monotonic(), time.time()
        try:
            stats = as_dict(d.live.stats)
        except Exception as exc:  # pragma: no cover - shown to the user
            stats = {"error": str(exc)}
        newest = _safe(lambda: live_ages(d.live), {}) or {}
        ages: dict[str, float | None] = dict.fromkeys(STALE_LIMITS_S)
        if newest:
            ages["live"] = max(0.0, wall - max(t for _, t in newest.values()))
        hb_t = _safe(lambda: d.heartbeat.last_time)
        ages["heartbeat"] = max(0.0, now - hb_t) if hb_t else None
        sw = None
        if "statusword" in newest:
            sw, sw_t = newest["statusword"]
            ages["statusword"] = max(0.0, wall - sw_t)
        limits = dict(STALE_LIMITS_S)
        if "statusword" not in newest:  # no TPDO carries it: the worker's SDO poll
            sw, ages["statusword"] = self.watch.get("statusword")
            limits["statusword"] = limits["mode"]
        mode, ages["mode"] = self.watch.get("mode")
        store, ages["store_status"] = self.watch.get("store_status")
        stale = [k for k, lim in limits.items() if (age := ages.get(k)) is None or age > lim]
        health = dict.fromkeys(STATUS_FIELDS)
        health.update(_safe(lambda: dict(d.bus_health()), {}) or {})
        sup = _safe(lambda: dict(d.supervisor.status()), {}) or {}
        for k in ("boots_seen", "supervision_rearmed_at"):
            if k in sup:
                health[k] = sup[k]
        health["store_status"] = store
        holder = self.lease.holder
        action = self.action
        # the last heartbeat's state ("OFFLINE" once they stopped); a drive without heartbeats:
        # the worker's answer (drive_link's SDO fallback)
        nmt = _safe(lambda: d.heartbeat.state) if hb_t else self.watch.get("nmt_state")[0]
        out: dict[str, Any] = {
            "bus": self.description,
            "node_id": self.node_id,
            "virtual": self.virtual,
            "nmt_state": nmt,
            "heartbeat_age_s": ages["heartbeat"],
            "state": state_name(sw),
            "statusword": int(sw) if sw is not None else None,
            "mode": mode,
            "ages_s": ages,
            "stale": stale,
            **{k: health.get(k) for k in STATUS_FIELDS},
            "action": action.public() if action is not None else None,
            "speed_setpoint": self.speed_setpoint,
            "current_setpoint": self.current_setpoint,
            "T_load": self.T_load,
            "emcy": [_emcy(e) for e in _safe(lambda: list(d.emcy_history), [])][-20:],
            "live": jsonable(stats),
            "controller": holder.public() if holder else None,
            "busy": self.busy,
            "sequence_running": self._sequence is not None and self._sequence.is_alive(),
            "sequence": self.sequence_progress,
            "identified": self.identified,
        }
        return out

    def live(self, seconds: float) -> dict[str, np.ndarray]:
        """The last ``seconds`` of the plotted signals ("t" in s, host clock, plus the signals)."""
        window: dict[str, np.ndarray] = self.drive.live.window(seconds, list(LIVE_SIGNALS))
        return window

    # ---------------------------------------------------------------- commands
    def command(self, name: str) -> None:
        """enable / disable / quick_stop / fault_reset (CiA 402); quick_stop never waits for
        the bench lock (:meth:`quick_stop`)."""
        if name == "quick_stop":
            self.quick_stop()
            return
        with self.lock:
            if name == "enable":
                self.drive.enable(timeout=2.0)
            elif name == "disable":
                self.stop_sequence()
                self.drive.disable()
            elif name == "fault_reset":
                self.drive.fault_reset()
            else:
                raise ValueError(f"unknown command {name!r}")
        self.watch.poke()
        self.emit("state")

    def quick_stop(self) -> str:
        """CiA 402 quick stop, at once: without the bench lock (a long action holds it for up
        to a minute), cancelling the long action and the sequence under way; they put back
        what they changed but do not enable the drive again (a quick stop wins over "as
        found": :mod:`drive_link.link._stop_guard`). Returns the state reached."""
        act = self.action
        if act is not None:
            act.quick_stopped = True
            act.cancel_event.set()
        self._sequence_stop.set()
        try:
            state: str = self.drive.quick_stop()
            return state
        finally:
            self.stop_sequence()
            self.watch.poke()
            self.emit("state")

    def set_mode(self, mode: str, setpoint: Callable[[], object] | None = None) -> None:
        """Switch to "speed" or "current" mode.

        The drive refuses a mode change while OPERATION ENABLED (SDO abort 0x08000022), so the
        bench disables, switches, applies ``setpoint`` (if given) and enables again; the
        power stage is off for that moment (the motor coasts).
        """
        with self.lock:
            if self._known_mode() == mode:
                if setpoint is not None:
                    setpoint()
                return
            enabled = _safe(lambda: self.drive.state) == "OPERATION ENABLED"
            if enabled:
                self.drive.disable()
            self.drive.set_mode(mode)
            self.watch.note("mode", mode)  # confirmed by drive_link's set_mode
            if setpoint is not None:
                setpoint()
            if enabled:
                self.drive.enable(timeout=2.0)
        self.watch.poke()
        self.emit("state")

    def _known_mode(self) -> Any:
        """The mode as the drive watch last read or the bench set it (read now if unknown or
        older than its stale limit)."""
        mode, age = self.watch.get("mode")
        if mode is None or age is None or age > STALE_LIMITS_S["mode"]:
            return _safe(lambda: self.drive.mode)
        return mode

    def _send(self, name: str, value: float | int) -> str:
        """A setpoint by RPDO or SDO (:class:`dashboard._setpoints.SetpointLink`), from the
        402 and NMT states as known (no read)."""
        s = self.state()
        stale = set(s.get("stale") or ())
        state = s.get("state") if "statusword" not in stale else None
        nmt = s.get("nmt_state") if "heartbeat" not in stale else None
        return self.setpoints.send(name, value, state=state, nmt=nmt)

    def set_speed(self, rpm: float) -> None:
        """Speed setpoint (rpm, rounded to an integer: target_velocity); switches to speed mode
        if needed (see :meth:`set_mode`). No read: the mode as known, the limit as kept."""
        with self.lock:
            self.set_mode("speed", lambda: self._send("target_velocity", round(float(rpm))))
            self.speed_setpoint = float(rpm)
            self.last_step_t = time.monotonic()
        self.emit("setpoint", {"rpm": rpm})

    def step_speed(self, delta_rpm: float, limit: float | None = None) -> float:
        """Add ``delta_rpm`` to the speed setpoint (clamped to ±limit, default the EDS default of
        0x6080 max_motor_speed, rpm); returns the new setpoint."""
        if limit is None:
            limit = float(load_od().entry("max_motor_speed").default or 0)
        target = float(np.clip(self.speed_setpoint + delta_rpm, -limit, limit))
        self.set_speed(target)
        return target

    def set_current(self, amps: float) -> None:
        """Pseudo-current setpoint i_p* (A); switches to current mode if needed."""
        with self.lock:
            self.set_mode("current", lambda: self._send("setpoints.i_p_ref", float(amps)))
            self.current_setpoint = float(amps)
            self.last_step_t = time.monotonic()
        self.emit("setpoint", {"i_p_ref": amps})

    def set_load(self, T_load: float) -> None:
        """Load-torque step on the virtual drive (N·m)."""
        if not self.virtual:
            raise ValueError("load steps exist only on the virtual drive")
        with self.lock:
            self.drive.write("sim_load.T_load", float(T_load))
            self.T_load = float(T_load)
        self.emit("load", {"T_load": T_load})

    # ---------------------------------------------------------------- long actions
    @contextlib.contextmanager
    def long_action(self, what: str, deadline_s: float) -> Iterator[LongAction]:
        """Run a long action under the bench lock with a deadline (s), progress and a cancel;
        on any failure (cancel and timeout included) put the drive back as found, then
        re-raise with what was restored. Refused (RuntimeError) while another runs."""
        running = self.action
        if running is not None or self.busy:
            raise RuntimeError(f"busy: {self.busy or (running.what if running else '')} under way")
        act = LongAction(what, time.monotonic() + deadline_s)
        with self.lock, self._stop_watch():
            if self.action is not None:
                raise RuntimeError(f"busy: {self.action.what} under way")
            found = self._found()
            act.found = found
            self.action, self.busy = act, what
            self.watch.forget("mode")  # the action switches modes as it needs: read it after
            self.emit("busy", {"what": what})
            try:
                yield act
            except BaseException as exc:
                undone = self.restore(found)
                note = "drive put back as found" if not undone else "NOT put back: " + undone
                if act.quick_stopped:
                    note = "quick stop: the drive stays stopped, " + (
                        "settings put back" if not undone else "NOT put back: " + undone
                    )
                self.emit("error", {"message": f"{what}: {exc} ({note})"})
                if isinstance(exc, Exception):
                    try:
                        again = type(exc)(f"{exc} ({note})")
                    except Exception:
                        again = RuntimeError(f"{exc} ({note})")
                    raise again from exc
                raise
            finally:
                self.action, self.busy = None, None
                self.watch.forget("mode")  # read again: the drive_link steps switch it unnoted
                self.emit("busy", {"what": None})

    def _stop_watch(self) -> contextlib.AbstractContextManager:
        """The block in which a quick stop forbids enabling the drive (this thread)."""
        stops = getattr(self.drive, "stops", None)
        return stops.watch() if stops is not None else contextlib.nullcontext()

    def cancel_action(self) -> bool:
        """Cancel the long action under way (True if there was one)."""
        act = self.action
        if act is None:
            return False
        act.cancel_event.set()
        return True

    def _found(self) -> Found:
        return Found(
            enabled=_safe(lambda: self.drive.state) == "OPERATION ENABLED",
            mode=_safe(lambda: self.drive.mode),
            speed_rpm=self.speed_setpoint,
            current_A=self.current_setpoint,
        )

    def restore(self, found: Found) -> str:
        """Put the drive back to ``found``; returns what could not be restored ("" if all)."""
        failed: list[str] = []

        def attempt(name: str, fn: Callable[[], Any]) -> None:
            try:
                fn()
            except Exception as exc:
                failed.append(f"{name} ({exc})")

        d = self.drive
        with self.lock:
            if not found.enabled:
                attempt("power stage off", lambda: d.disable())
            attempt("i_p*", lambda: d.set_current(found.current_A))
            self.current_setpoint = found.current_A
            mode = found.mode
            if mode in ("speed", "current") and _safe(lambda: d.mode) != mode:
                self.watch.forget("mode")  # the drive's, just read, is not the one known
                attempt("mode", lambda: self.set_mode(str(mode)))
            attempt("speed setpoint", lambda: d.set_speed(found.speed_rpm))
            self.speed_setpoint = found.speed_rpm
            if not found.enabled and _safe(lambda: d.state) == "OPERATION ENABLED":
                attempt("power stage off", lambda: d.disable())
        self.emit("state")
        return ", ".join(failed)

    # ---------------------------------------------------------------- sequences
    def start_sequence(self, steps: list[tuple[float, float]]) -> None:
        """Run (at_s, rpm) speed setpoints in the background; a new one replaces a running one.

        Progress is in ``state()["sequence"]``; a sequence that falls more than
        SEQUENCE_SLACK_S s behind its schedule, or whose setpoint is refused, stops and puts
        the drive back as it found it (Stop sequence leaves the last setpoint)."""
        self.stop_sequence()
        self._sequence_stop.clear()
        found = self._found()

        def run() -> None:
            with self._stop_watch():
                steps_run()

        def steps_run() -> None:
            t0 = time.monotonic()
            total = steps[-1][0] if steps else 0.0
            for k, (at_s, rpm) in enumerate(steps):
                self.sequence_progress = {
                    "step": k + 1,
                    "steps": len(steps),
                    "next_at_s": at_s,
                    "total_s": total,
                    "elapsed_s": round(time.monotonic() - t0, 2),
                }
                if self._sequence_stop.wait(max(0.0, t0 + at_s - time.monotonic())):
                    self.sequence_progress = None
                    return
                try:
                    late = time.monotonic() - (t0 + at_s)
                    if late > SEQUENCE_SLACK_S:
                        raise TimeoutError(f"step {k + 1} is {late:.1f} s late")
                    self.set_speed(rpm)
                except Exception as exc:
                    undone = self.restore(found)
                    note = "drive put back as found" if not undone else "NOT put back: " + undone
                    self.emit("error", {"message": f"sequence stopped: {exc} ({note})"})
                    self.sequence_progress = None
                    return
            self.sequence_progress = None
            self.emit("sequence_done")

        self._sequence = threading.Thread(target=run, name="speed-sequence", daemon=True)
        self._sequence.start()

    def stop_sequence(self) -> None:
        self._sequence_stop.set()
        seq = self._sequence
        if seq is not None and seq is not threading.current_thread():
            seq.join(timeout=1.0)
        self._sequence = None

    # ---------------------------------------------------------------- captures
    def add_capture(self, kind: str, columns: dict[str, np.ndarray], meta: dict) -> Capture:
        cap = Capture(next(self._ids), kind, {k: np.asarray(v) for k, v in columns.items()}, meta)
        self.captures[cap.id] = cap
        for old in sorted(self.captures)[:-20]:  # keep the last 20
            del self.captures[old]
        self.emit("capture", cap.summary())
        return cap

    def close(self) -> None:
        self.stop_sequence()
        self.watch.stop()


def _emcy(e: Any) -> dict[str, Any]:
    out = jsonable(as_dict(e))
    out["text"] = emcy_codes.describe(int(out.get("code", -1)))
    return out


def _safe(fn: Callable[[], Any], default: Any = None) -> Any:
    try:
        return fn()
    except Exception:
        return default
