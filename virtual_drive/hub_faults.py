"""Fault injection of the loopback CAN hub: frame loss and a delivery delay with jitter.

:class:`FaultInjection` owns the settings (``drop_rate``, ``delay_s``, ``jitter_s``) and the two
seeded random generators (one for the drops, one for the jitter, so that the jitter draws do not
change which frames are dropped). The hub (:class:`virtual_drive.hub.Hub`) changes the settings
with :meth:`FaultInjection.set`; its buses (:class:`virtual_drive.hub_bus.Bus`) ask it whether a
frame is lost and when a completed frame is due.
"""

from __future__ import annotations

import math
import random

__all__ = ["FaultInjection"]


class FaultInjection:
    """Frame loss and delivery delay of a hub.

    drop_rate: probability 0..1 that a frame is lost for all receivers (it still uses bus time).
    delay_s: extra delivery delay, s (0..3600), added after the frame completed on the bus.
    jitter_s: ± uniform jitter of that delay per frame, s (0..3600).
    seed: seed of the drop and jitter generators (None: unseeded).
    Out-of-range values raise ValueError.
    """

    __slots__ = ("_jitter_rng", "_rng", "delay_s", "drop_rate", "jitter_s")

    def __init__(
        self,
        drop_rate: float = 0.0,
        delay_s: float = 0.0,
        jitter_s: float = 0.0,
        seed: int | None = 0,
    ) -> None:
        self.check(drop_rate, delay_s, jitter_s)
        #: probability 0..1 that a frame is lost (read it; change it with :meth:`set`)
        self.drop_rate = float(drop_rate)
        #: extra delivery delay, s
        self.delay_s = float(delay_s)
        #: ± jitter of the delivery delay, s
        self.jitter_s = float(jitter_s)
        self._rng = random.Random(seed)
        self._jitter_rng = random.Random(None if seed is None else f"jitter-{seed}")

    @staticmethod
    def check(drop_rate: float, delay_s: float, jitter_s: float = 0.0) -> None:
        """Raise ValueError unless the three settings are finite and in range."""
        for name, v in (("drop_rate", drop_rate), ("delay_s", delay_s), ("jitter_s", jitter_s)):
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ValueError(f"{name} must be a finite number, got {v!r}")
        if not 0.0 <= drop_rate <= 1.0:
            raise ValueError(f"drop_rate must be in 0..1, got {drop_rate}")
        if not 0.0 <= delay_s <= 3600.0:
            raise ValueError(f"delay_s must be in 0..3600 s, got {delay_s}")
        if not 0.0 <= jitter_s <= 3600.0:
            raise ValueError(f"jitter_s must be in 0..3600 s, got {jitter_s}")

    def set(
        self,
        drop_rate: float | None = None,
        delay_s: float | None = None,
        jitter_s: float | None = None,
    ) -> None:
        """Change the settings (None keeps one); ValueError and nothing changed if out of range."""
        new_drop = self.drop_rate if drop_rate is None else drop_rate
        new_delay = self.delay_s if delay_s is None else delay_s
        new_jitter = self.jitter_s if jitter_s is None else jitter_s
        self.check(new_drop, new_delay, new_jitter)
        self.drop_rate = float(new_drop)
        self.delay_s = float(new_delay)
        self.jitter_s = float(new_jitter)

    def drops(self) -> bool:
        """True if the next frame is lost (one draw of the drop generator when drop_rate > 0)."""
        return self.drop_rate > 0.0 and self._rng.random() < self.drop_rate

    def delivery_due(self, end: float, last_due: float) -> float:
        """Delivery time of a frame that completed on the bus at ``end`` (monotonic s) when the
        previous frame on its bus is due at ``last_due``: end + delay_s + U(−jitter_s, jitter_s),
        never before ``end`` nor before ``last_due`` (CAN keeps the order of frames)."""
        if self.jitter_s == 0.0:
            due = end + self.delay_s
            return due if due > last_due else last_due
        delay = self.delay_s
        if self.jitter_s > 0.0:
            delay = max(0.0, delay + self._jitter_rng.uniform(-self.jitter_s, self.jitter_s))
        return max(end + delay, last_due)
