"""``drive-link record FILE``: the bus as a log file other CAN tools open.

python-can's :class:`can.Logger` picks the format by the file's suffix: ``.asc`` (Vector ASCII:
CANalyzer/CANoe, SavvyCAN), ``.blf`` (Vector binary logging format), ``.log`` (can-utils candump
``-l`` format: ``canplayer``, SavvyCAN), ``.csv``, ``.trc`` (PEAK), ``.mf4`` (ASAM MDF 4, needs
the ``asammdf`` package); a further ``.gz`` compresses. The recorder opens its own bus (python-can
allows one reader per bus object; SocketCAN and the loopback hub serve any number of readers),
so it records beside a running ``drive-link``/dashboard session, all frames of every node.
"""

from __future__ import annotations

import argparse
import collections
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import can

from .bus import open_bus
from .errors import DriveError, InvalidValue

__all__ = ["RecordStats", "check_log_path", "cmd_record", "record_bus"]

#: Formats python-can writes, by suffix, with the tools that read them (for help and errors).
FORMATS = {
    ".asc": "Vector ASCII (CANalyzer/CANoe, SavvyCAN)",
    ".blf": "Vector binary logging format",
    ".log": "candump -l format (canplayer, SavvyCAN)",
    ".csv": "python-can CSV",
    ".trc": "PEAK trace",
    ".mf4": "ASAM MDF 4 (needs asammdf)",
}


@dataclass
class RecordStats:
    """What a recording holds: ``frames`` written, ``seconds`` recorded (s), frames per CAN-ID,
    ``error_frames``, and the file ``path``."""

    path: Path
    frames: int = 0
    error_frames: int = 0
    seconds: float = 0.0
    per_id: dict[int, int] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready summary (CAN-IDs as ``"0x281"`` keys)."""
        return {
            "path": str(self.path),
            "frames": self.frames,
            "error_frames": self.error_frames,
            "seconds": round(self.seconds, 6),
            "frames_per_id": {f"0x{k:03X}": v for k, v in sorted(self.per_id.items())},
        }


class _Counter(can.Listener):
    def __init__(self) -> None:
        self.per_id: collections.Counter[int] = collections.Counter()
        self.error_frames = 0

    def on_message_received(self, msg: can.Message) -> None:
        if msg.is_error_frame:
            self.error_frames += 1
        else:
            self.per_id[msg.arbitration_id] += 1


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
    """Record every frame of the bus opened from ``bus_kwargs`` (:func:`drive_link.bus.open_bus`
    keywords: interface, channel, bitrate, host, port …) to ``path`` until ``stop_event`` is set
    or ``duration`` s have passed; returns what was written.

    Blocks the calling thread (run it in a thread from a GUI and set ``stop_event`` to stop).
    A bad path or format raises :class:`InvalidValue` before the bus is opened; a bus that
    cannot be opened raises :class:`~drive_link.errors.BusError` and leaves no file behind.
    """
    p = check_log_path(path)
    bus = open_bus(**bus_kwargs)  # BusError before any file is written
    counter = _Counter()
    try:
        logger = can.Logger(p)
    except (ValueError, NotImplementedError, OSError) as exc:
        bus.shutdown()
        raise InvalidValue(f"{p}: {exc}") from None
    t0 = time.monotonic()
    notifier = can.Notifier(bus, [logger, counter], timeout=0.1)
    try:
        stop_event.wait(duration)
    finally:
        seconds = time.monotonic() - t0
        try:
            notifier.stop(1.0)  # also stops (flushes and closes) the logger
        finally:
            bus.shutdown()
    return RecordStats(
        p, sum(counter.per_id.values()), counter.error_frames, seconds, dict(counter.per_id)
    )


def _bus_kwargs(args: argparse.Namespace) -> dict[str, Any]:
    from ._cli_tools import bus_settings

    return bus_settings(args)


def _wait_for_ctrl_c(done: threading.Event, stop: threading.Event) -> bool:
    """Wait until the recorder is ``done``; Ctrl-C sets ``stop`` (then it has 15 s to close the
    file). Returns whether Ctrl-C was pressed.

    The main thread only sleeps and reads ``done.is_set()`` (no lock) while a Ctrl-C may come:
    a KeyboardInterrupt raised inside ``Event.wait`` right after its ``with`` took the
    condition's lock leaves that lock held (CPython bpo-29988), and the next wait, or the
    recorder's ``done.set()``, then blocks for ever (a test that interrupted the recording hung
    until its 180 s timeout on a loaded host). A Ctrl-C anywhere in the loop is caught."""
    interrupted = False
    deadline = None  # after the stop: how long the recorder may take to close the file
    while True:
        try:
            while not done.is_set():
                if interrupted and deadline is None:
                    stop.set()
                    deadline = time.monotonic() + 15.0
                if deadline is not None and time.monotonic() > deadline:
                    raise DriveError("the recorder did not close the file within 15 s")
                time.sleep(0.05)
            return interrupted
        except KeyboardInterrupt:  # Ctrl-C ends the recording, not the command
            interrupted = True


def cmd_record(args: argparse.Namespace) -> int:
    """``drive-link record FILE [--seconds S]``: until S s have passed or Ctrl-C."""
    from .cli import _emit

    if args.seconds is not None and not 0 < args.seconds < 1e7:  # also nan and inf
        raise InvalidValue(f"--seconds {args.seconds}: must be a number of seconds > 0")
    stop = threading.Event()
    done = threading.Event()
    box: dict[str, Any] = {}

    def worker() -> None:
        try:
            box["stats"] = record_bus(_bus_kwargs(args), args.file, stop, args.seconds)
        except BaseException as exc:  # handed to the main thread
            box["error"] = exc
        finally:
            done.set()

    check_log_path(args.file)
    th = threading.Thread(target=worker, name="drive-link-record", daemon=True)
    th.start()
    if args.seconds is None and not args.json:
        import sys

        print(f"recording to {args.file} … Ctrl-C to stop", file=sys.stderr, flush=True)
    interrupted = _wait_for_ctrl_c(done, stop)
    if "error" in box:
        raise box["error"]
    stats = box["stats"]
    out = stats.as_dict()
    out["interrupted"] = interrupted
    top = sorted(stats.per_id.items(), key=lambda kv: -kv[1])

    def text() -> str:
        lines = [
            f"recorded {stats.frames} frames in {stats.seconds:.2f} s to {stats.path}"
            + (f" ({stats.error_frames} error frames)" if stats.error_frames else "")
        ]
        lines += [f"  0x{cid:03X}: {n}" for cid, n in top]
        return "\n".join(lines)

    _emit(args, out, text)
    return 0
