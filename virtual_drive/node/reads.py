"""Objects computed on read (statusword, measurements, error objects, trace data, counters).

:func:`make_live_getters` gives the table ``(index, sub) -> getter`` the LocalNode consults
before its data store; a getter returns the value in the object's Python type (or raw bytes).
A measurement's getter also carries ``live_item = (live dict, signal name)``: the TPDO engine
then reads all the measurements of a TPDO with one :func:`operator.itemgetter` call.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from .od_maps import MEASUREMENTS

if TYPE_CHECKING:
    from .drive_node import VirtualDrive

__all__ = ["clamp_int", "make_live_getters"]


def make_live_getters(d: VirtualDrive) -> dict[tuple[int, int], Callable[[], Any]]:
    """The live objects of drive ``d``: CiA 301 error objects, CiA 402 actual values (0x6041,
    0x6061, 0x606C rpm, 0x6077/0x6078 per mille of rated, 0x6079 mV), 0x2040 measurements, the
    recorder's read-only objects and the simulator's clock."""
    live = d.live
    g: dict[tuple[int, int], Callable[[], Any]] = {
        (0x1001, 0): lambda: d.emcy.error_register,
        (0x2060, 0): lambda: int(d.store_status),
        (0x2070, 1): lambda: d.pdo.missed[0],
        (0x2070, 2): lambda: d.pdo.missed[1],
        (0x2070, 3): lambda: d.pdo.missed[2],
        (0x2070, 4): lambda: d.pdo.missed[3],
        (0x1003, 0): lambda: len(d.emcy.history),
        (0x603F, 0): lambda: d.emcy.last_code,
        (0x6041, 0): d.statusword,
        (0x6061, 0): lambda: d._mode,
        (0x606C, 0): lambda: clamp_int(live["speed"], 32),
        (0x6077, 0): lambda: clamp_int(live["T_e"] / (d._value(0x6076) / 1000.0) * 1000.0, 16),
        (0x6078, 0): lambda: clamp_int(live["i_p"] / (d._value(0x6075) / 1000.0) * 1000.0, 16),
        (0x6079, 0): lambda: max(0, round(live["V_dc"] * 1000.0)),
        (0x2100, 10): lambda: d.recorder.state,
        (0x2100, 11): lambda: d.recorder.trigger_position,
        (0x2100, 12): lambda: d.recorder.capacity,
        (0x2100, 13): lambda: d.recorder.pre_trigger_filled,
        (0x2102, 0): d.recorder.data_bytes,
        (0x5030, 1): lambda: float(d.sim.time),
        (0x5030, 2): lambda: d.speed,
    }
    for k in range(1, 9):
        g[(0x1003, k)] = lambda k=k: d.emcy.history[k - 1] if k <= len(d.emcy.history) else 0
    for sub, name in MEASUREMENTS.items():
        if name == "hall_sector":
            g[(0x2040, sub)] = lambda: int(live["hall_sector"])
        else:
            getter = g[(0x2040, sub)] = lambda name=name: float(live[name])
            getter.live_item = (live, name)  # type: ignore[attr-defined]  # (see pdo: one pick)
    return g


def clamp_int(x: float, bits: int) -> int:
    """``round(x)`` saturated to a signed ``bits``-bit integer; 0 for NaN/inf."""
    lim = (1 << (bits - 1)) - 1
    if not math.isfinite(x):
        return 0
    return max(-lim - 1, min(lim, round(x)))
