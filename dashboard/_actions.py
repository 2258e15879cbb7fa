"""Long drive actions (identification, step tests, captures, sequences): a deadline, visible
progress, a cancel, and on failure, timeout or cancel the drive put back as it was found.

"As found" = the CiA 402 state (enabled or not), the mode of operation and both setpoints
(speed rpm, pseudo-current i_p* A). Restoring: power stage off first if it was off, then the
old i_p*, the old mode, the old speed setpoint; each step is tried even if an earlier one
failed, and the message lists what could not be put back.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field
from typing import Any

__all__ = ["ActionCancelledError", "ActionTimeoutError", "Found", "LongAction"]


class ActionCancelledError(RuntimeError):
    """The user pressed Cancel (or another client stopped the action)."""


class ActionTimeoutError(TimeoutError):
    """The action ran past its deadline."""


@dataclass
class Found:
    """The drive as the action found it."""

    enabled: bool
    mode: str | None
    speed_rpm: float
    current_A: float


@dataclass
class LongAction:
    """One running action: what, until when (time.monotonic()), progress 0..1 and a text."""

    what: str
    deadline: float
    started: float = field(default_factory=time.monotonic)
    fraction: float = 0.0
    text: str = "starting"
    cancel_event: threading.Event = field(default_factory=threading.Event)
    found: Found | None = None  #: the drive as the action found it (set by the bench)
    quick_stopped: bool = False  #: cancelled by a quick stop: the drive is not enabled again

    def progress(self, fraction: float, text: str) -> None:
        """Report progress (0..1) and a short text; raises when cancelled or past the deadline."""
        self.fraction = max(0.0, min(1.0, float(fraction)))
        self.text = text
        self.check()

    def check(self) -> None:
        if self.cancel_event.is_set():
            raise ActionCancelledError(f"{self.what} cancelled")
        if time.monotonic() > self.deadline:
            raise ActionTimeoutError(
                f"{self.what} did not finish within {self.deadline - self.started:.0f} s"
            )

    def sleep(self, seconds: float) -> None:
        """Sleep, waking at once on cancel; raises like :meth:`check`."""
        end = time.monotonic() + max(0.0, seconds)
        while True:
            self.check()
            left = end - time.monotonic()
            if left <= 0:
                return
            self.cancel_event.wait(min(left, 0.05))

    def public(self) -> dict[str, Any]:
        now = time.monotonic()
        return {
            "what": self.what,
            "fraction": round(self.fraction, 3),
            "text": self.text,
            "elapsed_s": round(now - self.started, 2),
            "deadline_in_s": round(self.deadline - now, 2),
        }
