"""The drive's trace recorder (0x2100 trace_config, 0x2101 trace_channels, 0x2102 trace_data).

Configure, arm, trigger, wait, upload (SDO block upload on the drive's second SDO server so
status reads continue meanwhile) and return a :class:`Trace`: numpy arrays with a time base in s,
units, and the trigger position.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from firmware_protocol import abort_codes, load_od
from firmware_protocol.enums import TraceState, TraceTriggerEdge, TraceTriggerMode

from ..errors import DriveTimeout, InvalidValue, SdoAbort, StateError
from ._objects import ObjectTable
from ._sdo import SdoChannel
from .writers import header_with_units, write_csv, write_png

__all__ = [
    "STATES",
    "TRACE_DATA",
    "TRIGGER_EDGES",
    "TRIGGER_MODES",
    "TS",
    "Recorder",
    "Trace",
    "TraceDrive",
    "Trigger",
    "od_reference",
]



class TraceDrive(Protocol):
    """What the recorder needs of a drive (:class:`drive_link.Drive` is one)."""

    @property
    def table(self) -> ObjectTable: ...

    @property
    def sdo_trace(self) -> SdoChannel: ...

    def read(self, name: str) -> Any: ...

    def write(self, name: str, value: float | int | str | bytes) -> None: ...

#: Control-loop sampling period of the drive, s (fs = 50 kHz; overview "control law").
TS = 20e-6

#: trace_config.trigger_mode / trigger_edge values by host name, trace_config.state names
#: (the EDS enumerations, :mod:`firmware_protocol.enums`).
TRIGGER_MODES: dict[str, int] = {m.name.lower(): int(m) for m in TraceTriggerMode}
TRIGGER_EDGES: dict[str, int] = {e.name.lower(): int(e) for e in TraceTriggerEdge}
STATES: dict[int, str] = {int(s): s.name.lower() for s in TraceState}

_TRACE_DATA_ENTRY = load_od().entry("trace_data")
TRACE_DATA = (_TRACE_DATA_ENTRY.index, _TRACE_DATA_ENTRY.subindex)


@dataclass
class Trigger:
    """Trigger settings: ``mode`` ("immediate", "signal", "setpoint_step", "fault"); for
    "signal": ``source`` (OD name), ``level`` (unit of the source), ``edge``
    ("rising", "falling", "either")."""

    mode: str = "immediate"
    source: str = "measurements.i_p"
    level: float = 0.0
    edge: str = "rising"

    def __post_init__(self) -> None:
        if self.mode not in TRIGGER_MODES:
            raise InvalidValue(f"trigger mode {self.mode!r}: one of {', '.join(TRIGGER_MODES)}")
        if self.edge not in TRIGGER_EDGES:
            raise InvalidValue(f"trigger edge {self.edge!r}: one of {', '.join(TRIGGER_EDGES)}")


@dataclass
class Trace:
    """A recorded trace.

    ``t``: time in s relative to the trigger (0 at ``trigger_index``); ``signals``: name →
    float32 array; ``units``: name → unit; ``divider``: loop samples per trace sample;
    ``Ts``: loop period in s.
    """

    t: np.ndarray
    signals: dict[str, np.ndarray]
    units: dict[str, str]
    trigger_index: int
    divider: int = 1
    Ts: float = TS
    meta: dict[str, Any] = field(default_factory=dict)

    @property
    def dt(self) -> float:
        """Trace sample period in s."""
        return self.divider * self.Ts

    def to_csv(self, path: str | Path) -> Path:
        """Write ``t`` and every signal as CSV with a unit row in the header names."""
        names = list(self.signals)
        header = ["t [s]", *header_with_units(names, self.units)]
        return write_csv(path, header, [self.t, *(self.signals[n] for n in names)])

    def to_png(
        self, path: str | Path, title: str = "", overlay: dict[str, np.ndarray] | None = None
    ) -> Path:
        """Plot every signal (one axis per unit) against t in ms with matplotlib's Agg backend.

        ``overlay``: extra curves on the same time base (e.g. a model prediction), plotted dashed.
        """
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        by_unit: dict[str, list[str]] = {}
        for n in self.signals:
            by_unit.setdefault(self.units.get(n, ""), []).append(n)
        fig, axes = plt.subplots(
            len(by_unit) or 1, 1, sharex=True, figsize=(8, 2.6 * max(1, len(by_unit)))
        )
        axes = np.atleast_1d(axes)
        t_ms = self.t * 1e3
        for ax, (unit, names) in zip(axes, by_unit.items(), strict=False):
            # the measurement on top (zorder) and stronger; overlays (models) thin, dashed
            for n in names:
                ax.plot(t_ms, self.signals[n], label=f"{n} ({unit})" if unit else n, lw=1.4,
                        zorder=3)
            for n, v in (overlay or {}).items():
                if n.split(" ")[0] in names or len(by_unit) == 1:
                    lab = n if not unit else (
                        f"{n[:-1]}, {unit})" if n.endswith(")") else f"{n} ({unit})"
                    )
                    ax.plot(t_ms[: len(v)], v, "--", label=lab, lw=0.9, zorder=2)
            ax.set_ylabel(unit)
            ax.axvline(0.0, color="k", lw=0.5, alpha=0.5)
            ax.grid(True, alpha=0.3)
            ax.legend(loc="best", fontsize=8)
        axes[-1].set_xlabel("t [ms] (0 = trigger)")
        if title:
            axes[0].set_title(title)
        return write_png(path, fig, dpi=110)


def od_reference(index: int, subindex: int, bits: int = 32) -> int:
    """Trace / PDO mapping entry: index<<16 | subindex<<8 | bit length."""
    return (index << 16) | (subindex << 8) | bits


class Recorder:
    """The trace recorder of one drive (use ``drive.trace``)."""

    def __init__(self, drive: TraceDrive):
        self._drive = drive
        self._channels: list[str] = []
        self._divider = 1
        #: held by :meth:`capture` (configure … upload is one operation); take it around your
        #: own configure/arm/wait/upload sequence when several threads use the recorder
        self.lock = threading.RLock()

    @property
    def state(self) -> str:
        """Recorder state: "idle", "armed", "recording" or "done"."""
        v = int(self._drive.read("trace_config.state"))
        return STATES.get(v, f"state {v}")

    @property
    def capacity(self) -> int:
        """REAL32 samples the recorder holds over all channels."""
        return int(self._drive.read("trace_config.capacity"))

    def resolve(self, name: str) -> str:
        """OD name of a channel; bare measurement names ("i_p") are accepted."""
        table = self._drive.table
        if name in table:
            return name
        if f"measurements.{name}" in table:
            return f"measurements.{name}"
        raise InvalidValue(f"unknown trace channel {name!r}")

    def configure(
        self,
        channels: list[str],
        divider: int = 1,
        length: int | None = None,
        pre_trigger: int = 0,
        trigger: Trigger | str | None = None,
    ) -> None:
        """Stop the recorder and write a new configuration (every value checked by the drive).

        ``divider``: loop samples (20 µs) per trace sample; ``length``: samples per channel
        (default: the capacity shared by the channels); ``pre_trigger``: samples before the
        trigger.
        """
        d = self._drive
        if not channels:
            raise InvalidValue("at least one trace channel is needed")
        if len(channels) > 8:
            raise InvalidValue("at most 8 trace channels")
        names = [self.resolve(c) for c in channels]
        trig = Trigger(mode=trigger) if isinstance(trigger, str) else (trigger or Trigger())
        if length is None:
            length = self.capacity // len(names)
        d.write("trace_config.command", 0)
        # shrink first so that every intermediate configuration is valid
        # (pre_trigger < length, length × channel_count ≤ capacity)
        d.write("trace_config.pre_trigger", 0)
        d.write("trace_config.length", 1)
        d.write("trace_config.channel_count", len(names))
        d.write("trace_config.divider", int(divider))
        d.write("trace_config.length", int(length))
        d.write("trace_config.pre_trigger", int(pre_trigger))
        for i, n in enumerate(names, start=1):
            obj = d.table[n]
            d.write(
                f"trace_channels.channel_{i}", od_reference(obj.index, obj.subindex, obj.bits or 32)
            )
        src = d.table[self.resolve(trig.source)]
        d.write(
            "trace_config.trigger_source", od_reference(src.index, src.subindex, src.bits or 32)
        )
        d.write("trace_config.trigger_level", float(trig.level))
        d.write("trace_config.trigger_edge", TRIGGER_EDGES[trig.edge])
        d.write("trace_config.trigger_mode", TRIGGER_MODES[trig.mode])
        self._channels = names
        self._divider = int(divider)

    def arm(self) -> None:
        """Arm (command 1); an "immediate" trigger starts recording at once."""
        self._drive.write("trace_config.command", 1)

    def force_trigger(self) -> None:
        """Trigger now (command 2)."""
        self._drive.write("trace_config.command", 2)

    def stop(self) -> None:
        """Stop (command 0)."""
        self._drive.write("trace_config.command", 0)

    def wait(
        self, timeout: float, poll_s: float = 0.02, sleep: Callable[[float], None] = time.sleep
    ) -> None:
        """Wait until the recorder is "done"; :class:`DriveTimeout` naming the state otherwise,
        :class:`StateError` if it went idle. ``sleep`` waits between polls (s; may raise to
        cancel: the step tests pass their hooks')."""
        deadline = time.monotonic() + timeout
        state = self.state
        while state != "done":
            if state == "idle":
                raise StateError(
                    "trace recorder went idle before it was done (stopped or reconfigured)"
                )
            if time.monotonic() >= deadline:
                raise DriveTimeout(f"trace not done after {timeout:g} s (recorder {state})")
            sleep(poll_s)
            state = self.state

    def wait_ready(
        self, timeout: float, poll_s: float = 0.02, sleep: Callable[[float], None] = time.sleep
    ) -> float:
        """Wait until the armed recorder holds its whole pre-trigger part, so that a setpoint
        step or crossing made now is taken as the trigger; returns the s waited.

        The drive fills that part in its own time (``pre_trigger × divider × 20 µs`` after
        arm, read back as ``trace_config.pre_trigger_filled``): a slow bus, or a virtual drive
        whose simulation lags the wall clock on a busy host, takes longer than a fixed sleep
        assumes. Firmware without that object (SDO abort 0x06090011) gets the fixed sleep:
        3 × the pre-trigger time + 20 ms. ``sleep`` waits between polls (s; may raise to
        cancel).

        :raises DriveTimeout: not full after ``timeout`` s.
        :raises StateError: the recorder is idle (not armed, or stopped meanwhile).
        """
        d = self._drive
        t0 = time.monotonic()
        pre = int(d.read("trace_config.pre_trigger"))
        if pre == 0:
            return time.monotonic() - t0
        deadline = t0 + timeout
        polls = 0
        while True:
            try:
                filled = int(d.read("trace_config.pre_trigger_filled"))
            except SdoAbort as exc:
                if exc.code != abort_codes.NO_SUBINDEX:
                    raise
                divider = int(d.read("trace_config.divider"))
                sleep(3.0 * pre * divider * TS + 0.02)
                return time.monotonic() - t0
            if filled >= pre:
                return time.monotonic() - t0
            polls += 1
            if polls % 5 == 1:  # already triggered (e.g. "immediate"), or not armed at all?
                state = self.state
                if state in ("recording", "done"):
                    return time.monotonic() - t0
                if state == "idle":
                    raise StateError("trace recorder is idle: arm it before waiting for it")
            if time.monotonic() >= deadline:
                raise DriveTimeout(
                    f"trace pre-trigger part {filled}/{pre} samples after {timeout:g} s"
                )
            sleep(poll_s)

    def upload(self, progress: Callable[[int, int | None], None] | None = None) -> Trace:
        """Upload the recorded data by SDO block upload on the second SDO channel."""
        d = self._drive
        count = int(d.read("trace_config.channel_count"))
        length = int(d.read("trace_config.length"))
        divider = int(d.read("trace_config.divider"))
        trig = int(d.read("trace_config.trigger_position"))
        names = []  # the drive's own channel list (it may have been configured elsewhere)
        for i in range(1, count + 1):
            ref = int(d.read(f"trace_channels.channel_{i}"))
            obj = d.table.by_index(ref >> 16, (ref >> 8) & 0xFF)
            names.append(obj.name if obj else f"0x{ref >> 16:04X}:{(ref >> 8) & 0xFF:02X}")
        self._channels = names
        raw = d.sdo_trace.upload_block(*TRACE_DATA, name="trace_data", progress=progress)
        expected = length * count * 4
        if len(raw) != expected:
            raise StateError(f"trace upload returned {len(raw)} bytes, expected {expected}")
        data = np.frombuffer(raw, dtype="<f4").reshape(length, count)
        t = (np.arange(length, dtype=np.float64) - trig) * divider * TS
        signals = {n: data[:, i].copy() for i, n in enumerate(self._channels)}
        units = {n: (d.table[n].unit if n in d.table else "") for n in self._channels}
        return Trace(t=t, signals=signals, units=units, trigger_index=trig, divider=divider)

    def capture(
        self,
        channels: list[str],
        divider: int = 1,
        length: int | None = None,
        pre_trigger: int = 0,
        trigger: Trigger | str | None = None,
        timeout: float | None = None,
        progress: Callable[[int, int | None], None] | None = None,
    ) -> Trace:
        """Configure, arm, wait for the trigger and the recording, upload; returns a :class:`Trace`.

        ``timeout`` (s) defaults to 2 s plus 3 × the recording duration.
        """
        with self.lock:
            self.configure(channels, divider, length, pre_trigger, trigger)
            length = int(self._drive.read("trace_config.length"))
            if timeout is None:
                timeout = 2.0 + 3.0 * length * divider * TS
            self.arm()
            self.wait(timeout)
            return self.upload(progress)
