"""What the bench knows about the drive, with the age of each part, read without waiting.

Nothing that shows the drive's state (the GUI's status loop, ``GET /api/state``, the stream)
may wait on an SDO timeout: a silent drive costs 0.3 s × 6 tries per SDO read, and a status
loop that waits on it keeps showing the last good picture as if it were live (issue 24).
So the state is built from what is already known:

- the live TPDO samples (the statusword, 0x6041, is in TPDO1 at 100 Hz; speed, i_p ... in
  TPDO2/3): the newest sample of each signal and its host time stamp;
- the heartbeat monitor (the NMT state of the last heartbeat and its arrival time);
- values that only SDO can read (mode of operation 0x6061, the parameter store 0x2060, the
  statusword when no TPDO carries it), polled by :class:`DriveWatch` in a worker thread of its
  own; its reads may time out, the readers never wait for them.

Each part carries its age (s) and is named in ``stale`` once older than its limit
(:data:`STALE_LIMITS_S`). Units: s.
"""

from __future__ import annotations

import contextlib
import logging
import math
import threading
import time
from collections.abc import Callable
from typing import Any

from drive_link.link import cia402

__all__ = ["POLL_PERIOD_S", "STALE_LIMITS_S", "STORE_POLL_S", "DriveWatch", "live_ages"]

log = logging.getLogger(__name__)

POLL_PERIOD_S = 0.5  #: the worker reads the mode (and a statusword no TPDO carries) this often
STORE_POLL_S = 10.0  #: the parameter store's health (one SDO read) this often
#: a part of the state older than this (s) is named in ``stale``
STALE_LIMITS_S = {
    "live": 0.5,  # newest TPDO sample (TPDO2/3 run at 1 kHz): as _live_plot.STALE_AFTER_S
    "heartbeat": 0.5,  # the drive's heartbeat (100 ms producer time)
    "statusword": 0.5,  # CiA 402 state: TPDO1 at 100 Hz (the worker's SDO read: below)
    "mode": 3.0,  # polled every POLL_PERIOD_S by SDO
    "store_status": 3 * STORE_POLL_S,
}


def live_ages(live: Any, now: float | None = None) -> dict[str, tuple[float, float]]:
    """Newest (value, host time stamp in s) of every live signal (no wait beyond the live
    buffers' own lock); {} before any frame."""
    out: dict[str, tuple[float, float]] = {}
    for name, (t, v) in live.streams(0.0).items():
        if len(t):
            out[name] = (float(v[-1]), float(t[-1]))
    return out


class DriveWatch:
    """A worker thread that reads by SDO what no TPDO carries; :meth:`get` never waits.

    ``drive``: a ``drive_link.Drive``. ``busy``: returns True while a long action owns the drive
    (nothing is read then: the values just grow older). ``on_read``: hooks called in the worker
    after each poll (e.g. the 3D rotor's θ_e read), so they never run in a status loop."""

    def __init__(
        self,
        drive: Any,
        busy: Callable[[], bool] = lambda: False,
        period_s: float = POLL_PERIOD_S,
    ) -> None:
        self.drive = drive
        self.busy = busy
        self.period_s = period_s
        self.hooks: list[Callable[[], None]] = []
        self._values: dict[str, tuple[Any, float]] = {}  # name → (value, time.monotonic())
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._poke = threading.Event()
        self._thread: threading.Thread | None = None
        self._store_t = -math.inf
        self.beat = time.monotonic()  # the worker's last poll start (its own liveness)

    # ---------------------------------------------------------------- readers (no wait)
    def get(self, name: str) -> tuple[Any, float | None]:
        """(value, age in s) of ``name`` as last read; (None, None) before the first read."""
        with self._lock:
            got = self._values.get(name)
        if got is None:
            return None, None
        return got[0], max(0.0, time.monotonic() - got[1])

    def note(self, name: str, value: Any) -> None:
        """Record a value known without reading it (e.g. the mode the bench just set)."""
        with self._lock:
            self._values[name] = (value, time.monotonic())

    def forget(self, name: str) -> None:
        """Drop a value that may no longer hold (e.g. the mode while a long action changes
        it): :meth:`get` says (None, None) until it is read or noted again."""
        with self._lock:
            self._values.pop(name, None)

    def poke(self) -> None:
        """Poll now (after a command changed the drive), not at the next period."""
        self._poke.set()

    # ---------------------------------------------------------------- worker
    def start(self) -> DriveWatch:
        if self._thread is None or not self._thread.is_alive():
            self._stop.clear()
            self._thread = threading.Thread(target=self._run, name="drive-watch", daemon=True)
            self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        self._poke.set()
        th = self._thread
        if th is not None and th is not threading.current_thread():
            th.join(timeout=3.0)

    def _run(self) -> None:
        while not self._stop.is_set():
            self.beat = time.monotonic()
            try:
                self.poll_once()
            except Exception as exc:  # never die: the ages show what is missing
                log.debug("drive watch poll failed: %s", exc)
            for hook in list(self.hooks):
                with contextlib.suppress(Exception):
                    hook()
            self._poke.wait(self.period_s)
            self._poke.clear()

    def poll_once(self) -> None:
        """One round of SDO reads (each may wait for its timeout: only this thread waits)."""
        if self.busy():
            return
        d = self.drive
        self._read("mode", lambda: d.mode)
        if getattr(d.heartbeat, "last_time", None) is None:  # no heartbeat: SDO fallback
            self._read("nmt_state", lambda: d.nmt_state)
        if not self._statusword_in_tpdo():
            self._read("statusword", lambda: int(d.read("statusword")))
        now = time.monotonic()
        if hasattr(d, "store_status") and now - self._store_t >= STORE_POLL_S:
            self._store_t = now
            self._read("store_status", d.store_status)

    def _statusword_in_tpdo(self) -> bool:
        try:
            return "statusword" in self.drive.live.signals
        except Exception:
            return False

    def _read(self, name: str, fn: Callable[[], Any]) -> None:
        try:
            value = fn()
        except Exception as exc:
            log.debug("drive watch: %s not read: %s", name, exc)
            return
        self.note(name, value)


def state_name(statusword: Any) -> str | None:
    """CiA 402 state name of a statusword value (None for None or a non-number)."""
    try:
        return cia402.state_from_statusword(int(statusword))
    except (TypeError, ValueError):
        return None
