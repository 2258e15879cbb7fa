"""On-drive trace recorder (0x2100 trace_config, 0x2101 trace_channels, 0x2102 trace_data).

Works on the simulator's full-rate chunk arrays (50 kHz, one array per signal) with numpy only:
per chunk it picks the decimated samples (every ``divider``-th loop sample, counted from the
arm instant), keeps a ring of the last ``pre_trigger`` of them while armed, finds the trigger
with vectorised comparisons, and copies the post-trigger part. No Python per sample.

Trigger modes (0x2100:8): 0 immediate (on arm), 1 crossing of ``trigger_level`` by the source
signal (edge 0 rising, 1 falling, 2 either; a crossing is ``prev < level <= cur`` for rising and
``prev > level >= cur`` for falling, evaluated on consecutive decimated samples), 2 setpoint step
(first decimated sample where the active setpoint signal differs from the one before), 3 fault
(first sample at or after the fault instant). Command 2 forces the trigger at the next sample.
A crossing, step or fault trigger is accepted only once the pre-trigger part is full; a forced
trigger takes what the ring holds. ``trigger_position`` is the index of the trigger sample in the
data (= number of samples before it).

Data (0x2102): little-endian REAL32, sample-major (s0c0, s0c1, …), oldest first.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Mapping, Sequence

import numpy as np

from firmware_protocol.enums import TraceCommand, TraceState, TraceTriggerEdge, TraceTriggerMode

__all__ = [
    "ARMED",
    "CAPACITY",
    "CMD_ARM",
    "CMD_FORCE",
    "CMD_STOP",
    "DONE",
    "EDGE_EITHER",
    "EDGE_FALLING",
    "EDGE_RISING",
    "IDLE",
    "MODE_CROSSING",
    "MODE_FAULT",
    "MODE_IMMEDIATE",
    "MODE_STEP",
    "RECORDING",
    "TraceConfigError",
    "TraceRecorder",
]

logger = logging.getLogger(__name__)

IDLE, ARMED, RECORDING, DONE = (int(s) for s in TraceState)
MODE_IMMEDIATE, MODE_CROSSING, MODE_STEP, MODE_FAULT = (int(m) for m in TraceTriggerMode)
EDGE_RISING, EDGE_FALLING, EDGE_EITHER = (int(e) for e in TraceTriggerEdge)
CMD_STOP, CMD_ARM, CMD_FORCE = (int(c) for c in TraceCommand)

#: REAL32 samples for all channels together (64 KiB of external SRAM on the DSP).
CAPACITY = 16384


class TraceConfigError(ValueError):
    """Configuration inconsistent (e.g. length × channels > capacity)."""


class TraceRecorder:
    """Trace recorder state machine fed with chunks of the simulation record.

    Signals are named like the simulator's ``SIGNALS`` (measurements sub names).
    """

    def __init__(self, capacity: int = CAPACITY) -> None:
        self.capacity = capacity
        self._lock = threading.Lock()
        self.channels: list[str] = ["i_p", "i_p_ref"]
        self.divider = 1
        self.length = 1000
        self.pre_trigger = 100
        self.trigger_source = "i_p"
        self.trigger_level = 0.0
        self.trigger_edge = EDGE_RISING
        self.trigger_mode = MODE_IMMEDIATE
        self.state = IDLE
        self.trigger_position = 0
        self._reset_buffers()

    # -- configuration --------------------------------------------------------------------
    def check(self, channels: Sequence[str], length: int, pre_trigger: int, divider: int) -> None:
        """Raise TraceConfigError if the combination does not fit the recorder."""
        if not 1 <= len(channels) <= 8:
            raise TraceConfigError("channel_count must be 1..8")
        if divider < 1:
            raise TraceConfigError("divider must be >= 1")
        if length < 1 or length * len(channels) > self.capacity:
            raise TraceConfigError(
                f"length {length} x {len(channels)} channels exceeds capacity {self.capacity}"
            )
        if not 0 <= pre_trigger < length:
            raise TraceConfigError("pre_trigger must be < length")

    def _reset_buffers(self) -> None:
        c = len(self.channels)
        self._data = np.zeros((self.length, c), dtype=np.float32)
        self._n = 0  # rows filled in _data
        self._ring = np.zeros((max(self.pre_trigger, 1), c), dtype=np.float32)
        self._ring_n = 0  # valid rows in ring (<= pre_trigger), stored oldest first
        self._phase = 0  # loop samples to skip before the next decimated sample
        self._prev_src: float | None = None
        self._prev_sp: float | None = None
        self._force = False
        self._fault_t: float | None = None
        self._data_bytes: bytes | None = None

    def arm(self) -> None:
        """Start a capture with the present configuration."""
        with self._lock:
            self.check(self.channels, self.length, self.pre_trigger, self.divider)
            self._reset_buffers()
            self.trigger_position = 0
            if self.trigger_mode == MODE_IMMEDIATE:
                self.state = RECORDING
            else:
                self.state = ARMED

    @property
    def pre_trigger_filled(self) -> int:
        """Samples held before the trigger (0x2100:13): the ring's fill while armed (0 →
        ``pre_trigger``), the capture's pre-trigger part once triggered, 0 when idle."""
        if self.state == ARMED:
            return self._ring_n if self.pre_trigger else 0
        if self.state in (RECORDING, DONE):
            return self.trigger_position
        return 0

    def stop(self) -> None:
        with self._lock:
            if self.state in (ARMED, RECORDING):
                self.state = IDLE

    def force(self) -> None:
        """Trigger at the next sample (armed) or start at once (idle)."""
        with self._lock:
            if self.state == ARMED:
                self._force = True
        if self.state in (IDLE, DONE):
            self.arm()
            with self._lock:
                if self.state == ARMED:
                    self._force = True

    def note_fault(self, t: float) -> None:
        """Tell the recorder a fault happened at simulation time ``t`` (s)."""
        self._fault_t = t

    # -- data -----------------------------------------------------------------------------
    def data_bytes(self) -> bytes:
        """0x2102 content: the finished capture (empty while none is done)."""
        with self._lock:
            if self.state != DONE:
                return b""
            if self._data_bytes is None:
                self._data_bytes = self._data[: self._n].astype("<f4").tobytes()
            return self._data_bytes

    def data_array(self) -> np.ndarray:
        """Finished capture as (length, channel_count) float32."""
        with self._lock:
            return self._data[: self._n].copy()

    # -- feeding --------------------------------------------------------------------------
    def feed(self, rec: Mapping[str, np.ndarray], setpoint: str = "i_p_ref") -> None:
        """Process one chunk of the simulation record (all arrays the same length).

        :param rec: signal name → array at the loop rate; must hold ``"t"`` and the channels.
        :param setpoint: name of the active setpoint signal for trigger mode 2.
        """
        if self.state not in (ARMED, RECORDING):
            return
        self._setpoint = setpoint if setpoint in rec else "i_p_ref"
        with self._lock:
            if self.state not in (ARMED, RECORDING):
                return
            n = len(rec["t"])
            if n == 0:
                return
            sel = np.arange(self._phase, n, self.divider)
            self._phase = (self._phase - n) % self.divider
            if sel.size == 0:
                return
            block = np.empty((sel.size, len(self.channels)), dtype=np.float32)
            for j, name in enumerate(self.channels):
                block[:, j] = np.asarray(rec[name], dtype=np.float32)[sel]
            if self.state == ARMED:
                k = self._find_trigger(rec, sel)
                if k is None:
                    self._push_ring(block)
                    return
                self._push_ring(block[:k])
                pre = self._ring[: self._ring_n] if self.pre_trigger else self._ring[:0]
                self._data[: len(pre)] = pre
                self._n = len(pre)
                self.trigger_position = len(pre)
                self.state = RECORDING
                block = block[k:]
            take = min(self.length - self._n, len(block))
            self._data[self._n : self._n + take] = block[:take]
            self._n += take
            if self._n >= self.length:
                self.state = DONE
                self._data_bytes = None
                logger.info("trace done: %d samples x %d channels", self._n, len(self.channels))

    def _push_ring(self, block: np.ndarray) -> None:
        p = self.pre_trigger
        if p == 0 or len(block) == 0:
            return
        if len(block) >= p:
            self._ring[:p] = block[-p:]
            self._ring_n = p
            return
        keep = min(self._ring_n, p - len(block))
        self._ring[:keep] = self._ring[self._ring_n - keep : self._ring_n]
        self._ring[keep : keep + len(block)] = block
        self._ring_n = keep + len(block)

    def _find_trigger(self, rec: Mapping[str, np.ndarray], sel: np.ndarray) -> int | None:
        """Index into ``sel`` of the trigger sample, or None."""
        if self._force:
            self._force = False
            return 0
        # earliest index at which the pre-trigger part is full
        first_ok = max(self.pre_trigger - self._ring_n, 0)
        mode = self.trigger_mode
        if mode == MODE_CROSSING:
            x = np.asarray(rec[self.trigger_source], dtype=np.float32)[sel]
            k = self._crossing(x, first_ok)
            self._prev_src = float(x[-1])
            return k
        if mode == MODE_STEP:
            x = np.asarray(rec[self._setpoint], dtype=np.float32)[sel]
            prev = np.empty_like(x)
            prev[0] = x[0] if self._prev_sp is None else self._prev_sp
            prev[1:] = x[:-1]
            self._prev_sp = float(x[-1])
            hits = np.flatnonzero(x != prev)
            hits = hits[hits >= first_ok]
            return int(hits[0]) if hits.size else None
        if mode == MODE_FAULT:
            if self._fault_t is None:
                return None
            t = np.asarray(rec["t"])[sel]
            hits = np.flatnonzero(t >= self._fault_t - 1e-12)
            hits = hits[hits >= first_ok]
            if hits.size:
                self._fault_t = None
                return int(hits[0])
            return None
        return 0

    def _crossing(self, x: np.ndarray, first_ok: int) -> int | None:
        prev = np.empty_like(x)
        prev[0] = x[0] if self._prev_src is None else self._prev_src
        prev[1:] = x[:-1]
        level = np.float32(self.trigger_level)
        rising = (prev < level) & (x >= level)
        falling = (prev > level) & (x <= level)
        if self.trigger_edge == EDGE_RISING:
            hit = rising
        elif self.trigger_edge == EDGE_FALLING:
            hit = falling
        else:
            hit = rising | falling
        if self._prev_src is None:
            hit[0] = False
        hits = np.flatnonzero(hit)
        hits = hits[hits >= first_ok]
        return int(hits[0]) if hits.size else None

    _setpoint = "i_p_ref"
