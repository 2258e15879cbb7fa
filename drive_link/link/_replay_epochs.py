"""The TPDO configuration of a recording as it changed: SDO writes followed in time.

A recording often holds the host setting the drive up: ``drive-link live`` or the dashboard
write event timers (0x1800+k:5), remap (0x1A00+k) or switch a TPDO off and on (0x1800+k:1,
bit 31) while the frames flow. Judging drops against the configuration at the end of the file
counts every frame sent at another rate as dropped (or none when there were). Here the file is
cut into epochs at every change the recording confirmed (an SDO download the drive answered),
each epoch has the configuration in force then, and drops are counted per epoch with the event
timer of that epoch, as :class:`drive_link.link._live.LiveStreams` counts them live (a pause longer
than 1 s opens a new count window).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from firmware_protocol.index_ranges import PDO_PARAMETERS, TPDO_COMM

from ._live import _PAUSE_S, TpdoConfig

__all__ = ["Epoch", "count_drops", "epochs", "is_tpdo_object"]


def is_tpdo_object(index: int) -> bool:
    """0x1800-0x19FF (TPDO communication) or 0x1A00-0x1BFF (TPDO mapping)."""
    return TPDO_COMM <= index < PDO_PARAMETERS.stop


@dataclass
class Epoch:
    """From ``t0`` (s from the first frame) until the next epoch: the TPDO ``configs``."""

    t0: float
    configs: list[TpdoConfig]


def epochs(
    writes: list[tuple[float, int, int, bytes]],
    configs_at: Callable[[float], list[TpdoConfig]],
) -> list[Epoch]:
    """One epoch from 0, then one from each time a confirmed write changed a TPDO object.

    ``writes``: (t, index, sub, raw) of confirmed SDO downloads in time order; ``configs_at(t)``
    the TPDO configurations in force just after ``t``."""
    times = sorted({t for t, index, _sub, _raw in writes if is_tpdo_object(index)})
    out = [Epoch(0.0, configs_at(-1.0))]
    for t in times:
        cfg = configs_at(t)
        if _key(cfg) != _key(out[-1].configs):
            out.append(Epoch(t, cfg))
    return out


def _key(cfgs: list[TpdoConfig]) -> list[tuple]:
    return [
        (c.number, c.cob_id, c.valid, c.event_timer_ms, tuple(f.name for f in c.fields))
        for c in cfgs
    ]


def count_drops(stamps: list[float], event_timer_ms: int) -> int:
    """Frames an event timer of ``event_timer_ms`` promised between the first and the last of
    ``stamps`` (s, in order) that are not there; count windows restart after a pause > 1 s."""
    if not event_timer_ms or not stamps:
        return 0
    period = event_timer_ms / 1000.0
    dropped = 0
    t0 = last = stamps[0]
    n = 0
    for t in stamps:
        if t - last > _PAUSE_S:
            dropped += max(0, round((last - t0) / period) + 1 - n)
            t0, n = t, 0
        n += 1
        last = t
    return dropped + max(0, round((last - t0) / period) + 1 - n)
