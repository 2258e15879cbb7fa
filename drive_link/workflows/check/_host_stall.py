"""Host stalls seen from inside the process: a probe thread that should wake every ``tick_s``.

A timing measurement (heartbeat period, TPDO rates) taken while this machine did not run the
process for tens of ms says more about the host than about the drive (on one host with a
virtual drive, the drive is stalled too). :class:`StallProbe` measures the longest such stall
during a window: how late its thread woke (s) beyond its sleep; ``drive-link check`` repeats a
timing item whose window held a stall above :data:`STALL_S` and says so.
"""

from __future__ import annotations

import threading
import time

__all__ = ["STALL_S", "StallProbe"]

#: A wake-up this late (s) is a host stall that spoils a timing window (a 1 kHz TPDO stream
#: loses 5 % of a 1 s window; a 50 ms heartbeat is shifted by a whole period).
STALL_S = 0.05


class StallProbe:
    """``with StallProbe() as p: ...`` then ``p.worst`` (s): the longest late wake-up."""

    def __init__(self, tick_s: float = 0.005) -> None:
        self.tick_s = tick_s
        self.worst = 0.0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="stall-probe", daemon=True)

    def _run(self) -> None:
        tick = self.tick_s
        while not self._stop.is_set():
            t0 = time.monotonic()
            self._stop.wait(tick)
            late = time.monotonic() - t0 - tick
            if late > self.worst and not self._stop.is_set():
                self.worst = late

    def __enter__(self) -> StallProbe:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(1.0)

    @property
    def stalled(self) -> bool:
        return self.worst > STALL_S
