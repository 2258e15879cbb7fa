"""A quick stop wins: once the host sent a quick stop, nothing it runs re-enables the drive.

A long experiment (step test, identification, report) enables the drive, and on its way out
puts it back as found (:mod:`drive_link.workflows.restore`), enabled again if it was found enabled.
A quick stop pressed meanwhile (from another thread: the dashboard's Quick stop button) must win
over both: the experiment must not enable the drive again afterwards, and the restore may put
back settings, gains, setpoints and the mode but never the OPERATION ENABLED state.

:class:`StopGuard` counts the quick stops the host sends (counted before the controlword goes
out) and, for a thread inside :meth:`StopGuard.watch`, refuses to write the enable-operation
controlword once a quick stop was counted after the block began (:class:`StateError`). A quick
stop and an enable's controlword are serialised by one short lock (one SDO write at most), so
an enable cannot slip in after the quick stop. The user's own Enable (outside any block) is
never refused.
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable, Iterator

from ..errors import StateError
from .cia402 import CW_ENABLE_OPERATION

__all__ = ["StopGuard"]


class StopGuard:
    """Quick stops sent by this host, and the blocks in which they forbid enabling."""

    def __init__(self) -> None:
        self.count = 0  #: quick stops sent so far (counted before they are sent)
        self._lock = threading.Lock()  # a quick stop and an enable's controlword: one at a time
        self._local = threading.local()

    def note_quick_stop(self) -> None:
        """Count a quick stop about to be sent (waits for at most one controlword write)."""
        with self._lock:
            self.count += 1

    @contextlib.contextmanager
    def watch(self) -> Iterator[int]:
        """In this block (this thread), a quick stop counted after it began forbids enabling;
        nested blocks keep the outermost beginning. Yields the count at the beginning."""
        outer = getattr(self._local, "since", None)
        if outer is None:
            self._local.since = self.count
        try:
            yield self._local.since
        finally:
            if outer is None:
                self._local.since = None

    def stopped(self) -> bool:
        """Whether a quick stop was sent since this thread's outermost :meth:`watch` began."""
        since = getattr(self._local, "since", None)
        return since is not None and self.count != since

    def write_controlword(self, write: Callable[[int], None], cw: int) -> None:
        """``write(cw)``, refused (:class:`StateError`) for enable operation after a quick stop
        inside a :meth:`watch` block."""
        with self._lock:
            if cw == CW_ENABLE_OPERATION and self.stopped():
                raise StateError(
                    "quick stop pressed: the drive is not enabled again (press Enable yourself)"
                )
            write(cw)
