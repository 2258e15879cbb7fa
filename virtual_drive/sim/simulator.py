"""The virtual drive's simulator: C core (``virtual_drive._core``) behind a small Python API.

One ``run`` call runs a whole chunk of 50 kHz samples in C (plant, unipolar PWM bridge,
controllers, protection) and returns every signal at full rate as numpy arrays.  Parameters
can be changed between chunks (live tuning) without restarting; a change takes effect at the
next sample.  See ``csrc/loop.h`` (timing, PWM, protection), ``csrc/plant.h`` (motor, diodes,
commutation) and ``csrc/controllers.h`` (laws, anti-windup, float32 integrator).
"""

from __future__ import annotations

import dataclasses
import math
import threading
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from firmware_protocol import emcy_codes
from virtual_drive._core import ffi, lib
from virtual_drive.sim.params import (
    RPM_PER_RAD_S,
    CurrentControllerParams,
    InverterParams,
    LoadParams,
    MotorParams,
    ProtectionParams,
    SpeedControllerParams,
    Ts,
)
from virtual_drive.sim.signals import SIGNALS

__all__ = [
    "FAULT_KINDS",
    "FAULT_OVERCURRENT",
    "FAULT_OVERVOLTAGE",
    "FAULT_UNDERVOLTAGE",
    "MAX_POINTS",
    "Fault",
    "Simulator",
]

FAULT_OVERCURRENT = emcy_codes.OVERCURRENT
FAULT_OVERVOLTAGE = emcy_codes.DC_OVERVOLTAGE
FAULT_UNDERVOLTAGE = emcy_codes.DC_UNDERVOLTAGE

FAULT_KINDS: dict[str, int] = {
    "none": 0,
    "overcurrent": FAULT_OVERCURRENT,
    "overvoltage": FAULT_OVERVOLTAGE,
    "undervoltage": FAULT_UNDERVOLTAGE,
}
"""inject_fault kinds; OD 0x5010 sub1 codes 0..3 map to them in this order."""

#: most instants :meth:`Simulator.run_points` copies in one call
MAX_POINTS = 64

_MODES = {"off": 0, "current": 1, "speed": 2}
_MODELS = {"pwm": 0, "averaged": 1}


@dataclass(frozen=True)
class Fault:
    """A drive trip: EMCY ``code`` (0x2310, 0x3210, 0x3220), ``reason``, sim time ``t`` (s)."""

    code: int
    reason: str
    t: float


class Simulator:
    """Virtual BLDC drive at fs = 50 kHz (Ts = 20 us).

    Parameters are the validated dataclasses of :mod:`virtual_drive.sim.params`;
    ``model`` is ``"pwm"`` (exact per PWM sub-interval) or ``"averaged"``.
    """

    MAX_POINTS = MAX_POINTS  #: most instants :meth:`run_points` copies in one call

    Ts: float = Ts

    def __init__(
        self,
        motor: MotorParams | None = None,
        inverter: InverterParams | None = None,
        load: LoadParams | None = None,
        current: CurrentControllerParams | None = None,
        speed: SpeedControllerParams | None = None,
        model: str = "pwm",
        protection: ProtectionParams | None = None,
    ) -> None:
        self._lock = threading.RLock()
        #: the C sample loop's whole state (csrc/loop.h ``sample_loop_t``), owned here
        self._loop = ffi.new("sample_loop_t *")
        self._os_keep: Any = None
        loop = self._loop
        loop.Ts = Ts
        loop.p.theta_e = math.pi / 3.0  # middle of Hall sector 1
        self._motor = motor if motor is not None else MotorParams()
        self._inverter = inverter if inverter is not None else InverterParams()
        self._load = load if load is not None else LoadParams()
        self._current = current if current is not None else CurrentControllerParams()
        self._speed = speed if speed is not None else SpeedControllerParams()
        self._protection = protection if protection is not None else ProtectionParams()
        self._supply = self._inverter.V_dc
        self._apply_motor()
        self._apply_inverter()
        self._apply_load()
        self._apply_current()
        self._apply_speed()
        self._apply_protection()
        self.set_model(model)
        lib.loop_init(loop)
        self._last: dict[str, float] | None = None
        #: float32 view of the C loop's latest values (SIGNALS order), read without a copy
        self._last_view = np.frombuffer(ffi.buffer(ffi.addressof(loop, "last")), dtype=np.float32)
        # run_points' buffers: sample counts and the rows copied at them (+1: the chunk's end)
        self._points_at = ffi.new("int[]", MAX_POINTS + 1)
        self._points_buf = ffi.new("float[]", (MAX_POINTS + 1) * len(SIGNALS))
        self._points_rows = np.frombuffer(ffi.buffer(self._points_buf), dtype=np.float32).reshape(
            MAX_POINTS + 1, len(SIGNALS)
        )

    @classmethod
    def from_defaults(cls, model: str = "pwm") -> Simulator:
        """Table 2 motor, paper's gains (deadbeat L_c = L, IP k_p = 0.2113, k_i = 2.9994e-5)."""
        return cls(model=model)

    # ------------------------------------------------------------------ parameters
    @property
    def motor(self) -> MotorParams:
        return dataclasses.replace(self._motor)

    @property
    def inverter(self) -> InverterParams:
        return dataclasses.replace(self._inverter)

    @property
    def load(self) -> LoadParams:
        return dataclasses.replace(self._load)

    @property
    def current(self) -> CurrentControllerParams:
        return dataclasses.replace(self._current)

    @property
    def speed(self) -> SpeedControllerParams:
        return dataclasses.replace(self._speed)

    @property
    def protection(self) -> ProtectionParams:
        return dataclasses.replace(self._protection)

    def _apply_motor(self) -> None:
        m, p = self._motor, self._loop.p
        p.R, p.L, p.k_e = m.R, m.L, m.k_e
        p.pole_pairs, p.emf_rounding = m.pole_pairs, m.emf_rounding

    def _apply_inverter(self) -> None:
        v, loop = self._inverter, self._loop
        loop.p.V_dc = self._supply
        loop.p.V_G = v.V_G
        loop.T_BT = v.T_BT
        loop.T_delay = v.T_DD + v.T_SD

    def _apply_load(self) -> None:
        ld, p = self._load, self._loop.p
        p.J, p.B_tot, p.T_load = ld.J, ld.B_tot, ld.T_load
        lib.loop_update_mech(self._loop)

    def _apply_current(self) -> None:
        c = self._current
        rc = lib.cc_current_configure(
            ffi.addressof(self._loop, "cc"),
            c.type_code,
            Ts,
            c.L_c,
            c.R_c,
            c.k_p,
            c.k_i,
            c.T_BT,
            c.T_DD,
            c.T_SD,
            c.V_G,
            int(c.emf_feedforward),
        )
        if rc != 0:  # float32 overflow/underflow of a validated value
            raise ValueError(f"CurrentControllerParams not representable in float32: {c}")

    def _apply_speed(self) -> None:
        s = self._speed
        speed_loop = ffi.addressof(self._loop, "sc")
        if lib.cc_speed_configure(speed_loop, s.k_p, s.k_i, s.current_limit) != 0:
            raise ValueError(f"SpeedControllerParams not representable in float32: {s}")

    def _apply_protection(self) -> None:
        pr, loop = self._protection, self._loop
        loop.oc_trip, loop.ov_trip, loop.uv_trip = (
            pr.overcurrent_trip,
            pr.overvoltage_trip,
            pr.undervoltage_trip,
        )

    @staticmethod
    def _replace(obj: Any, kw: dict[str, Any]) -> Any:
        names = {f.name for f in dataclasses.fields(obj)}
        for k in kw:
            if k not in names:
                raise ValueError(
                    f"{type(obj).__name__}.{k} is not a parameter (known: {sorted(names)})"
                )
        return dataclasses.replace(obj, **kw)

    def set_current_gains(self, **kw: Any) -> CurrentControllerParams:
        """Change current-controller fields (type, L_c, R_c, k_p, k_i, T_BT, T_DD, T_SD, V_G,
        emf_feedforward); validated as a whole, nothing changes on error.  Changing ``type``
        restarts the controller state bumplessly."""
        with self._lock:
            new = self._replace(self._current, kw)
            L_min = float(np.float32(new.L_c))
            if not L_min > 0.0:
                raise ValueError(f"CurrentControllerParams.L_c too small for float32: {new.L_c}")
            old_type = self._current.type
            self._current = new
            self._apply_current()
            if new.type != old_type:
                self._loop.active = 0
            return self.current

    def set_speed_gains(self, **kw: Any) -> SpeedControllerParams:
        """Change k_p (A/rpm), k_i (1/sample), current_limit (A); validated, next sample."""
        with self._lock:
            new = self._replace(self._speed, kw)
            self._speed = new
            self._apply_speed()
            return self.speed

    def set_motor(self, **kw: Any) -> MotorParams:
        """Change the simulated motor (R, L, K_rpm, pole_pairs, emf_rounding, ...)."""
        with self._lock:
            self._motor = self._replace(self._motor, kw)
            self._apply_motor()
            return self.motor

    def set_load(
        self,
        T_load: float | None = None,
        k_gen: float | None = None,
        J: float | None = None,
        B: float | None = None,
    ) -> LoadParams:
        """Load torque T_load (N m; a change is a load step), generator k_gen (N m/rpm),
        inertia J (kg m^2), friction B (N m s/rad)."""
        kw = {
            k: v
            for k, v in (("T_load", T_load), ("k_gen", k_gen), ("J", J), ("B", B))
            if v is not None
        }
        with self._lock:
            self._load = self._replace(self._load, kw)
            self._apply_load()
            return self.load

    def set_inverter_nonidealities(
        self,
        T_BT: float | None = None,
        T_DD: float | None = None,
        T_SD: float | None = None,
        V_G: float | None = None,
    ) -> InverterParams:
        """The virtual inverter's real blanking time, driver delay, sampling delay (s) and
        switch drop (V) -- what eq. (25) compensates with its estimates."""
        kw = {
            k: v
            for k, v in (("T_BT", T_BT), ("T_DD", T_DD), ("T_SD", T_SD), ("V_G", V_G))
            if v is not None
        }
        with self._lock:
            self._inverter = self._replace(self._inverter, kw)
            self._apply_inverter()
            return self.inverter

    def set_protection(self, **kw: Any) -> ProtectionParams:
        """Trip limits: overcurrent_trip (A), overvoltage_trip (V), undervoltage_trip (V)."""
        with self._lock:
            self._protection = self._replace(self._protection, kw)
            self._apply_protection()
            return self.protection

    def set_supply_voltage(self, V: float) -> None:
        """DC supply voltage (V), > 0; outside the protection limits it trips at the next
        sample (0x3210 / 0x3220) and keeps tripping until restored."""
        with self._lock:
            v = float(V)
            if not math.isfinite(v) or v <= 0.0 or v > 1000.0:
                raise ValueError(f"V_dc supply must be in (0, 1000] V, got {V!r}")
            self._supply = v
            self._loop.p.V_dc = v

    @property
    def supply_voltage(self) -> float:
        """DC supply voltage (V)."""
        return self._supply

    def inject_fault(self, kind: str | int) -> None:
        """One-shot trip at the next sample: "overcurrent" (0x2310), "overvoltage" (0x3210),
        "undervoltage" (0x3220), or "none" to cancel a pending one.  Integers 0..3 (OD 0x5010
        sub1) select the same kinds in that order."""
        names = list(FAULT_KINDS)
        if isinstance(kind, bool):
            raise ValueError(f"fault kind must be one of {names} or 0..3, got {kind!r}")
        if isinstance(kind, (int, np.integer)):
            if not 0 <= int(kind) < len(names):
                raise ValueError(f"fault kind must be one of {names} or 0..3, got {kind!r}")
            kind = names[int(kind)]
        if kind not in FAULT_KINDS:
            raise ValueError(f"fault kind must be one of {names} or 0..3, got {kind!r}")
        with self._lock:
            self._loop.inject = FAULT_KINDS[kind]

    def set_model(self, model: str) -> None:
        """ "pwm" (exact per PWM sub-interval) or "averaged" (period-mean leg voltages)."""
        if model not in _MODELS:
            raise ValueError(f"model must be one of {list(_MODELS)}, got {model!r}")
        with self._lock:
            self._model = model
            self._loop.model = _MODELS[model]

    @property
    def model(self) -> str:
        return self._model

    # ------------------------------------------------------------------ commands
    def set_mode(self, mode: str) -> None:
        """ "off" (bridge disabled, all switches open), "current" (i_p loop on set_current_ref)
        or "speed" (IP speed loop on set_speed_ref feeding the current loop)."""
        if mode not in _MODES:
            raise ValueError(f"mode must be one of {list(_MODES)}, got {mode!r}")
        with self._lock:
            new = _MODES[mode]
            if new != self._loop.mode:
                self._loop.active = 0  # controllers restart bumplessly
            self._loop.mode = new

    @property
    def mode(self) -> str:
        return {v: k for k, v in _MODES.items()}[int(self._loop.mode)]

    def set_current_ref(self, i_p_ref: float) -> None:
        """Pseudo-current reference (A), finite, |.| <= 1000 (current mode)."""
        v = float(i_p_ref)
        if v == self._loop.i_ref_set:
            return  # unchanged (the pacing loop sets it every chunk): no lock needed
        if not math.isfinite(v) or abs(v) > 1000.0:
            raise ValueError(f"i_p_ref must be finite and |i_p_ref| <= 1000 A, got {i_p_ref!r}")
        with self._lock:
            self._loop.i_ref_set = v

    def set_speed_ref(self, rpm: float) -> None:
        """Speed reference (rpm), finite, |.| <= 20000 (speed mode)."""
        v = float(rpm)
        if v == self._loop.w_ref_set:
            return  # unchanged (the pacing loop sets it every chunk): no lock needed
        if not math.isfinite(v) or abs(v) > 20000.0:
            raise ValueError(f"speed_ref must be finite and |speed_ref| <= 20000 rpm, got {rpm!r}")
        with self._lock:
            self._loop.w_ref_set = v

    def set_speed(self, rpm: float, theta_e: float | None = None) -> None:
        """Force the shaft speed (rpm) and optionally the electrical angle (rad), e.g. to start
        a test at an operating point or to apply a back-EMF step."""
        v = float(rpm)
        if not math.isfinite(v) or abs(v) > 20000.0:
            raise ValueError(f"speed must be finite and |speed| <= 20000 rpm, got {rpm!r}")
        th = None
        if theta_e is not None:
            th = float(theta_e)
            if not math.isfinite(th):
                raise ValueError(f"theta_e must be finite, got {theta_e!r}")
            th = th % (2.0 * math.pi)
        with self._lock:
            self._loop.p.omega = v / RPM_PER_RAD_S
            if th is not None:
                self._loop.p.theta_e = th

    # ------------------------------------------------------------------ running
    def run(
        self, n_samples: int, *, record: bool = True, oversample: int = 0
    ) -> dict[str, np.ndarray]:
        """Run ``n_samples`` samples (50 kHz).  Returns every name in SIGNALS (float32) and
        "t" (s, float64), each of length n_samples; with ``record=False`` nothing is kept
        (empty dict).  ``oversample=N`` (2..64) adds the exact waveform at N points per
        sample: "os_t", "os_i_a", "os_i_b", "os_i_c", "os_i_p" (float64)."""
        n = int(n_samples)
        if n < 0 or n != n_samples:
            raise ValueError(f"n_samples must be a non-negative integer, got {n_samples!r}")
        os_n = int(oversample)
        if os_n != 0 and not 2 <= os_n <= 64:
            raise ValueError(f"oversample must be 0 or 2..64, got {oversample!r}")
        if not record and not os_n and n <= 1 << 20:
            # the pacing loop's path: one C call, nothing built (state is made when asked)
            with self._lock:
                lib.loop_run(self._loop, n, ffi.NULL, ffi.NULL)
                self._last = None
            return {}
        with self._lock:
            loop = self._loop
            data: np.ndarray | None = None
            t: np.ndarray | None = None
            if record:
                data = np.empty((len(SIGNALS), n), dtype=np.float32)
                t = np.empty(n, dtype=np.float64)
                ptrs = ffi.new(f"float *[{len(SIGNALS)}]")
                for j in range(len(SIGNALS)):
                    ptrs[j] = ffi.cast("float *", data[j].ctypes.data)
                t_ptr = ffi.cast("double *", t.ctypes.data)
            else:
                ptrs = ffi.NULL
                t_ptr = ffi.NULL
            os_buf: np.ndarray | None = None
            if os_n:
                os_buf = np.zeros((n * os_n + 1, 5), dtype=np.float64)
                loop.os_n = os_n
                loop.os_buf = ffi.cast("double *", os_buf.ctypes.data)
                loop.os_cap = os_buf.shape[0]
                loop.os_len = 0
            try:
                chunk = 1 << 20
                done = 0
                while done < n:
                    m = min(chunk, n - done)
                    if record:
                        assert data is not None and t is not None
                        for j in range(len(SIGNALS)):
                            ptrs[j] = ffi.cast("float *", data[j, done:].ctypes.data)
                        t_ptr = ffi.cast("double *", t[done:].ctypes.data)
                    lib.loop_run(loop, m, ptrs, t_ptr)
                    done += m
            finally:
                if os_n:
                    os_len = int(loop.os_len)
                    loop.os_n = 0
                    loop.os_buf = ffi.NULL
                    loop.os_cap = 0
            self._refresh_last()
            if not record:
                return {}
            assert data is not None and t is not None
            out = {name: data[j] for j, name in enumerate(SIGNALS)}
            out["t"] = t
            if os_buf is not None:
                osr = os_buf[:os_len]
                for j, key in enumerate(("os_t", "os_i_a", "os_i_b", "os_i_c", "os_i_p")):
                    out[key] = osr[:, j].copy()
            return out

    def run_seconds(self, T: float, **kw: Any) -> dict[str, np.ndarray]:
        """Run round(T / Ts) samples; T in s, >= 0."""
        v = float(T)
        if not math.isfinite(v) or v < 0.0:
            raise ValueError(f"T must be a finite duration >= 0 s, got {T!r}")
        return self.run(round(v / Ts), **kw)

    def _refresh_last(self) -> None:
        self._last = None  # built by the next ``state``

    @property
    def state(self) -> dict[str, float]:
        """Latest recorded value of every signal (and "t", s)."""
        with self._lock:
            if self._last is None:
                loop = self._loop
                last = dict(zip(SIGNALS, self._last_view.tolist(), strict=True))
                last["hall_sector"] = round(last["hall_sector"])
                last["t"] = float(loop.t) - Ts if loop.k > 0 else 0.0
                self._last = last
            return dict(self._last)

    def run_into(self, n_samples: int, out: dict[str, float]) -> None:
        """Run ``n_samples`` samples (an int >= 0) without recording and write the latest
        value of every signal into ``out`` (as :meth:`update_state`): the pacing loop's chunk,
        one lock and one C call."""
        n = n_samples
        with self._lock:
            while n > 0:
                m = n if n <= 1 << 20 else 1 << 20
                lib.loop_run(self._loop, m, ffi.NULL, ffi.NULL)
                n -= m
            self._last = None
            out.update(zip(SIGNALS, self._last_view.tolist(), strict=True))

    def run_points(self, n_samples: int, at: Sequence[int]) -> list[list[float]]:
        """Run ``n_samples`` samples (an int >= 0) in one C call without recording and return
        the latest value of every signal (a list in SIGNALS order) once ``at[j]`` samples have
        run, for each ``j`` (non-decreasing sample counts, at most 64; a count above
        ``n_samples`` counts as ``n_samples``), then once more at the end: ``len(at) + 1``
        rows. The pacing loop's timed tick: the values of each instant a TPDO is due at."""
        m = len(at)
        if m > MAX_POINTS:
            raise ValueError(f"at most {MAX_POINTS} points per call, got {m}")
        if not 0 <= n_samples <= 1 << 20:
            raise ValueError(f"n_samples must be 0..{1 << 20}, got {n_samples!r}")
        buf = self._points_at
        last = -1
        for j, a in enumerate(at):
            if a < last or a < 0:
                raise ValueError(f"sample counts must be >= 0 and non-decreasing, got {at!r}")
            buf[j] = last = a
        buf[m] = n_samples
        with self._lock:
            lib.loop_run_points(self._loop, n_samples, buf, m + 1, self._points_buf)
            self._last = None
            rows: list[list[float]] = self._points_rows[: m + 1].tolist()
            return rows

    def run_record(self, n_samples: int, out: dict[str, np.ndarray], start: int = 0) -> None:
        """Run ``n_samples`` samples recording only the signals named in ``out`` (SIGNALS
        names -> preallocated C-contiguous float32 arrays of length >= start + n_samples) into
        ``[start, start + n_samples)``: one C call per 2**20 samples and no allocation, the
        path of the robustness sweeps (``virtual_drive.sweep``)."""
        n = int(n_samples)
        if n < 0 or n != n_samples or start < 0:
            raise ValueError(f"n_samples and start must be integers >= 0, got {n_samples!r}")
        ptrs = ffi.new(f"float *[{len(SIGNALS)}]")
        for name, arr in out.items():
            if name not in SIGNALS:
                raise ValueError(f"unknown signal {name!r} (known: {list(SIGNALS)})")
            if arr.dtype != np.float32 or not arr.flags.c_contiguous or arr.shape[0] < start + n:
                raise ValueError(f"out[{name!r}] must be C-contiguous float32 of >= {start + n}")
        with self._lock:
            done = 0
            while done < n:
                m = min(1 << 20, n - done)
                for name, arr in out.items():
                    ptrs[SIGNALS.index(name)] = ffi.cast("float *", arr[start + done :].ctypes.data)
                lib.loop_run(self._loop, m, ptrs, ffi.NULL)
                done += m
            self._last = None

    def update_state(self, out: dict[str, float]) -> None:
        """Write the latest value of every signal (SIGNALS names, float; hall_sector too) into
        ``out``: the per-chunk path of the node, without building or copying a dict."""
        with self._lock:
            out.update(zip(SIGNALS, self._last_view.tolist(), strict=True))

    @property
    def fault(self) -> Fault | None:
        """None, or the active trip."""
        if self._loop.fault_code == 0:  # one int read: no lock needed on the no-fault path
            return None
        with self._lock:
            loop = self._loop
            if loop.fault_code == 0:
                return None
            trip = emcy_codes.TRIP_REASONS.get(int(loop.fault_reason))  # OD_TRIP_*
            return Fault(
                code=int(loop.fault_code),
                reason=trip.text if trip is not None else "?",
                t=float(loop.fault_time),
            )

    def fault_persists(self) -> bool:
        """True while a trip's cause is still there (the DC supply outside the overvoltage /
        undervoltage limits): a fault reset now would trip again at the next sample."""
        with self._lock:
            V = float(self._loop.p.V_dc)
            return V > float(self._loop.ov_trip) or V < float(self._loop.uv_trip)

    def reset_fault(self) -> None:
        """Clear the trip; the drive goes to mode "off" (bridge disabled) and must be enabled
        again with set_mode.  A persisting cause (supply out of limits) trips again."""
        with self._lock:
            lib.loop_reset_fault(self._loop)
            self._loop.mode = 0

    @property
    def time(self) -> float:
        """Simulated time of the next sample (s)."""
        return float(self._loop.t)

    @property
    def sample_index(self) -> int:
        """Index of the next sample."""
        return int(self._loop.k)

    @property
    def speed_rpm(self) -> float:
        """Present shaft speed (rpm)."""
        return float(self._loop.p.omega) * RPM_PER_RAD_S

    @property
    def segments(self) -> int:
        """Circuit segments solved so far (diagnostic: sub-intervals + diode events)."""
        return int(self._loop.segments)
