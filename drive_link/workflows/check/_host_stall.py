"""Host stalls seen from inside the process: a probe thread that should wake every ``tick_s``.

A timing measurement (heartbeat period, TPDO rates) taken while this machine did not run the
process for tens of ms says more about the host than about the drive (on one host with a
virtual drive, the drive is stalled too). :class:`StallProbe` measures, during a window, how
late its thread woke beyond its sleep: the longest such delay and their sum. A window is
stalled when one wake-up came more than :data:`STALL_S` late, or when the wake-ups were late by
more than :data:`STARVED_SHARE` of the window in total: a host that runs the process's threads
a few ms late every time (a CPU-bound thread holding the interpreter, a machine with many
runnable tasks per core) never stalls 50 ms at once, yet a 1 kHz TPDO stream of a virtual
drive in that process then gets one frame out per interpreter switch (about 200 Hz).
``drive-link check`` repeats a timing item whose window was stalled and says so.
"""

from __future__ import annotations

import threading
import time

__all__ = ["STALL_S", "STARVED_SHARE", "StallProbe"]

#: A wake-up this late (s) is a host stall that spoils a timing window (a 1 kHz TPDO stream
#: loses 5 % of a 1 s window; a 50 ms heartbeat is shifted by a whole period).
STALL_S = 0.05

#: Wake-ups late by this share of the window in total spoil it too. Measured on the 2-core
#: development host (``check pdo_rates`` against an in-process virtual drive): 1.5-2 % idle
#: and with six CPU hogs beside it; 20-23 % with one CPU-bound thread in the process, when
#: TPDO2 reached 154-158 of its 1000 Hz.
STARVED_SHARE = 0.10


class StallProbe:
    """``with StallProbe() as p: ...`` then ``p.worst`` (s): the longest late wake-up,
    ``p.late`` (s) their sum, ``p.elapsed`` (s) the window, ``p.stalled`` the verdict."""

    def __init__(self, tick_s: float = 0.005) -> None:
        self.tick_s = tick_s
        self.worst = 0.0
        self.late = 0.0
        self.elapsed = 0.0
        self._t0 = 0.0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="stall-probe", daemon=True)

    def _run(self) -> None:
        tick = self.tick_s
        while not self._stop.is_set():
            t0 = time.monotonic()
            self._stop.wait(tick)
            if self._stop.is_set():
                break
            late = max(0.0, time.monotonic() - t0 - tick)
            self.late += late
            if late > self.worst:
                self.worst = late

    def __enter__(self) -> StallProbe:
        self._t0 = time.monotonic()
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(1.0)
        self.elapsed = time.monotonic() - self._t0

    @property
    def share(self) -> float:
        """The wake-ups' total lateness as a share of the window (0..1)."""
        return self.late / self.elapsed if self.elapsed > 0 else 0.0

    @property
    def stalled(self) -> bool:
        return self.worst > STALL_S or self.share > STARVED_SHARE

    def describe(self) -> str:
        """One phrase for a verdict: the stall, or how late the host ran the process."""
        if self.worst > STALL_S:
            return f"{self.worst * 1e3:.0f} ms"
        return f"wake-ups late {100 * self.share:.0f} % of {self.elapsed:.1f} s"
