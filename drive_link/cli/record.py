"""``drive-link record FILE [--seconds S]``: :func:`drive_link.link.record.record_bus` until S s
have passed or Ctrl-C (SIGTERM and SIGHUP end it the same way), then the frame counts."""

from __future__ import annotations

import argparse
import signal
import threading
import time
from collections.abc import Callable
from typing import Any

from ..errors import DriveError, InvalidValue
from ..link.record import check_log_path, record_bus
from ._common import _emit
from .tools import bus_settings

__all__ = ["cmd_record"]


def _bus_kwargs(args: argparse.Namespace) -> dict[str, Any]:
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
    restore = _finish_on_signals()  # SIGTERM/SIGHUP (timeout, kill, systemd) end it like Ctrl-C
    try:
        return _wait_and_report(args, th, stop, done, box)
    finally:
        restore()


def _finish_on_signals() -> Callable[[], None]:
    """Make SIGTERM and SIGHUP raise KeyboardInterrupt in the main thread (the recording is then
    finished and its file closed like on Ctrl-C); returns the function that puts the old
    handlers back. Does nothing outside the main thread (e.g. in a GUI's worker)."""
    if threading.current_thread() is not threading.main_thread():
        return lambda: None

    def interrupt(signum: int, _frame: Any) -> None:
        raise KeyboardInterrupt(signal.Signals(signum).name)

    old = {}
    for name in ("SIGTERM", "SIGHUP"):
        sig = getattr(signal, name, None)
        if sig is not None:
            old[sig] = signal.signal(sig, interrupt)

    def restore() -> None:
        for sig, handler in old.items():
            signal.signal(sig, handler)

    return restore


def _wait_and_report(
    args: argparse.Namespace,
    th: threading.Thread,
    stop: threading.Event,
    done: threading.Event,
    box: dict[str, Any],
) -> int:
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
        lines += [f"dropped {n} frames: {why}" for why, n in stats.dropped.items()]
        lines += [f"  0x{cid:03X}: {n}" for cid, n in top]
        return "\n".join(lines)

    _emit(args, out, text)
    return 0
