"""SIGINT/SIGTERM as a stop request that a signal handler can set without a lock.

A Python signal handler runs in the main thread between two bytecodes, possibly while that
thread holds a lock: ``threading.Event.set()`` in the handler, with the main loop inside
``Event.wait()``, deadlocked a ``virtual-drive run`` for good (the handler waited for the
Condition lock its own thread held; found by a full test run, the orphan still running 30 min
later). The handler here only sets an attribute, and :meth:`StopSignal.wait` sleeps.
"""

from __future__ import annotations

import signal
import time
from collections.abc import Callable
from types import FrameType
from typing import Any

__all__ = ["StopSignal"]


#: a signal disposition as ``signal.signal`` returns and takes it (None: set outside Python)
_Handler = Callable[[int, FrameType | None], Any] | int | signal.Handlers | None


class StopSignal:
    """``with StopSignal() as stop: while not stop.wait(0.2): ...`` runs until SIGINT/SIGTERM.

    :param signals: the signals that request the stop.
    """

    def __init__(self, signals: tuple[signal.Signals, ...] = (signal.SIGINT, signal.SIGTERM)):
        self.signals = signals
        self.requested = False  #: set by the handler (an attribute store takes no lock)
        self._previous: dict[signal.Signals, _Handler] = {}

    def _on_signal(self, signum: int, frame: FrameType | None) -> None:
        self.requested = True

    def wait(self, timeout: float) -> bool:
        """Sleep ``timeout`` s (a signal's handler runs meanwhile); True once stop requested."""
        if not self.requested:
            time.sleep(timeout)
        return self.requested

    def __enter__(self) -> StopSignal:
        self._previous = {s: signal.signal(s, self._on_signal) for s in self.signals}
        return self

    def __exit__(self, *exc: object) -> None:
        for s, handler in self._previous.items():
            signal.signal(s, handler)
        self._previous = {}
