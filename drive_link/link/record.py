"""``drive-link record FILE``: the bus as a log file other CAN tools open.

python-can's :class:`can.Logger` picks the format by the file's suffix: ``.asc`` (Vector ASCII:
CANalyzer/CANoe, SavvyCAN), ``.blf`` (Vector binary logging format), ``.log`` (can-utils candump
``-l`` format: ``canplayer``, SavvyCAN), ``.csv``, ``.trc`` (PEAK), ``.mf4`` (ASAM MDF 4, needs
the ``asammdf`` package); a further ``.gz`` compresses. The recorder opens its own bus (python-can
allows one reader per bus object; SocketCAN and the loopback hub serve any number of readers),
so it records beside a running ``drive-link``/dashboard session, all frames of every node.
"""

from __future__ import annotations

import collections
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import can

from ..errors import InvalidValue
from .bus import open_bus

__all__ = [
    "CANNOT_HOLD",
    "RecordStats",
    "check_log_path",
    "frame_kind",
    "record_bus",
]

#: Formats python-can writes, by suffix, with the tools that read them (for help and errors).
FORMATS = {
    ".asc": "Vector ASCII (CANalyzer/CANoe, SavvyCAN)",
    ".blf": "Vector binary logging format",
    ".log": "candump -l format (canplayer, SavvyCAN)",
    ".csv": "python-can CSV",
    ".trc": "PEAK trace",
    ".mf4": "ASAM MDF 4 (needs asammdf)",
}


#: What a format cannot hold, by suffix: frame kind → why (python-can 4.6's writers: the TRC
#: writer skips remote, error and CAN FD frames with a log line; the CSV has no FD flag, so an
#: FD frame would read back as a classical frame with up to 64 data bytes).
CANNOT_HOLD: dict[str, dict[str, str]] = {
    ".trc": {
        "remote": ".trc (python-can's TRC writer) holds no remote (RTR) frames",
        "error": ".trc (python-can's TRC writer) holds no error frames",
        "fd": ".trc (python-can's TRC writer) holds no CAN FD frames",
    },
    ".csv": {"fd": ".csv has no CAN FD flag (an FD frame would read back as classical)"},
}


def frame_kind(msg: can.Message) -> str:
    """``"error"``, ``"remote"``, ``"fd"`` or ``"data"`` (a classical data frame)."""
    if msg.is_error_frame:
        return "error"
    if msg.is_remote_frame:
        return "remote"
    return "fd" if msg.is_fd else "data"


@dataclass
class RecordStats:
    """What a recording holds: ``frames`` written (error frames included), ``seconds`` of bus
    time recorded (s), frames per CAN-ID, ``error_frames`` written, ``dropped`` (reason → frames
    seen on the bus that the format cannot hold, not written), and the file ``path``."""

    path: Path
    frames: int = 0
    error_frames: int = 0
    seconds: float = 0.0
    per_id: dict[int, int] = field(default_factory=dict)
    dropped: dict[str, int] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready summary (CAN-IDs as ``"0x281"`` keys)."""
        return {
            "path": str(self.path),
            "frames": self.frames,
            "error_frames": self.error_frames,
            "seconds": round(self.seconds, 6),
            "frames_per_id": {f"0x{k:03X}": v for k, v in sorted(self.per_id.items())},
            "dropped": dict(self.dropped),
        }


class _Gate(can.Listener):
    """Passes to ``logger`` the frames the format holds that fall in the bus-time window, and
    counts them; counts the others by reason. The window is ``duration`` s of bus time from the
    start (the bus's clock, whatever its epoch: mapped through the first frame's arrival)."""

    def __init__(
        self, logger: can.Listener, suffix: str, duration: float | None, t0: float
    ) -> None:
        self.logger = logger
        self.cannot = CANNOT_HOLD.get(suffix, {})
        self.duration = duration
        self.t0 = t0  # wall clock (time.time) when the recording started
        self.offset: float | None = None  # bus time - wall time, from the first frame
        self.per_id: collections.Counter[int] = collections.Counter()
        self.error_frames = 0
        self.dropped: collections.Counter[str] = collections.Counter()
        self.first: float | None = None
        self.last: float | None = None
        self.arrived = t0  # wall clock of the latest frame's arrival
        self.done = threading.Event()  # the window's end seen on the bus

    def on_message_received(self, msg: can.Message) -> None:
        if self.done.is_set():
            return
        self.arrived = time.time()
        if self.offset is None:
            self.offset = msg.timestamp - self.arrived
        if self.duration is not None and msg.timestamp >= self.t0 + self.offset + self.duration:
            self.done.set()
            return
        kind = frame_kind(msg)
        why = self.cannot.get(kind)
        if why is not None:
            self.dropped[why] += 1
            return
        self.logger.on_message_received(msg)
        if self.first is None:
            self.first = msg.timestamp
        self.last = msg.timestamp
        if kind == "error":
            self.error_frames += 1
        else:
            self.per_id[msg.arbitration_id] += 1

    def stop(self) -> None:
        self.logger.stop()


def check_log_path(path: str | Path) -> Path:
    """``path`` if python-can can write its format here, else :class:`InvalidValue` (one line)."""
    p = Path(path)
    suffixes = [s.lower() for s in p.suffixes]
    if suffixes and suffixes[-1] == ".gz":
        suffixes.pop()
    suffix = suffixes[-1] if suffixes else ""
    if suffix not in FORMATS:
        known = ", ".join(f"{k} ({v})" for k, v in FORMATS.items())
        raise InvalidValue(f"{p.name}: unknown log format {suffix or '(no suffix)'!r}; use {known}")
    if suffix == ".mf4":
        try:
            import asammdf  # noqa: F401
        except ImportError:
            raise InvalidValue(
                f"{p.name}: .mf4 needs the asammdf package (pip install asammdf); "
                "or record .blf/.asc/.log"
            ) from None
    if not p.parent.is_dir():
        raise InvalidValue(f"{p}: no directory {p.parent}")
    return p


def record_bus(
    bus_kwargs: dict[str, Any],
    path: str | Path,
    stop_event: threading.Event,
    duration: float | None = None,
) -> RecordStats:
    """Record every frame of the bus opened from ``bus_kwargs``
    (:func:`drive_link.link.bus.open_bus` keywords: interface, channel, bitrate, host, port …) to
    ``path`` until ``stop_event`` is set or ``duration`` s have passed; returns what was written.

    Blocks the calling thread (run it in a thread from a GUI and set ``stop_event`` to stop).
    A bad path or format raises :class:`InvalidValue` before the bus is opened; a bus that
    cannot be opened raises :class:`~drive_link.errors.BusError` and leaves no file behind.
    """
    p = check_log_path(path)
    suffixes = [s.lower() for s in p.suffixes if s.lower() != ".gz"]
    bus = open_bus(**bus_kwargs)  # BusError before any file is written
    try:
        logger = can.Logger(p)
    except (ValueError, NotImplementedError, OSError) as exc:
        bus.shutdown()
        raise InvalidValue(f"{p}: {exc}") from None
    t0 = time.time()
    gate = _Gate(logger, suffixes[-1] if suffixes else "", duration, t0)
    notifier = can.Notifier(bus, [gate], timeout=0.1)
    try:
        if duration is None:
            stop_event.wait()
        else:  # the window's end on the bus; a bus gone quiet ends by the wall clock
            end = t0 + duration
            while not (gate.done.is_set() or stop_event.is_set()):
                now = time.time()
                if (now > end + 0.5 and now - gate.arrived > 0.5) or now > end + 10.0:
                    break
                gate.done.wait(0.05)
    finally:
        wall = time.time() - t0
        try:
            notifier.stop(1.0)  # also stops (flushes and closes) the logger
        finally:
            bus.shutdown()
    if duration is not None and gate.done.is_set():
        seconds = duration
    elif gate.offset is not None and gate.last is not None:
        seconds = max(gate.last - (t0 + gate.offset), 0.0)
    else:
        seconds = wall
    return RecordStats(
        p,
        sum(gate.per_id.values()) + gate.error_frames,
        gate.error_frames,
        seconds,
        dict(gate.per_id),
        dict(gate.dropped),
    )
