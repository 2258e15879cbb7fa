"""Live values from the drive's TPDOs as timestamped numpy ring buffers.

Each TPDO is decoded with the mapping the drive reports (0x1800+k / 0x1A00+k read by SDO), so the
host follows whatever mapping the drive really has. Per TPDO the stream counts received frames,
estimates dropped frames against the expected event-timer cadence (frames the period says should
have arrived between the first and the latest frame, minus those that did: jitter cancels out,
a lost frame does not; a pause longer than 1 s, e.g. NMT PRE-OPERATIONAL, starts a new count
window instead of counting as losses), and measures its rate; the bus monitor gives the bus load.

Frames are decoded in batches (issue 11): the bus thread only queues each frame's stamp, bytes
and arrival time; the queue is decoded with one numpy view per batch (:data:`BATCH` frames, or
whatever is queued when a reader asks), so a reader always sees every frame received so far.
"""

from __future__ import annotations

import bisect
import struct
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any

import canopen
import numpy as np
from canopen.pdo import PdoVariable

from ._connection import BusMonitor
from ._objects import ObjectTable

__all__ = [
    "BATCH",
    "LiveStreams",
    "MappedField",
    "TpdoConfig",
    "mapped_fields",
    "read_tpdo_configs",
]

#: A TPDO silence longer than this (s) is a pause (NMT state, drive restart), not lost frames.
_PAUSE_S = 1.0
#: Frames of one TPDO queued on the bus thread before they are decoded there in one go.
BATCH = 64
#: A window's copy reaches this far (s) past its start: samples stamped out of order by less
#: than this are still found (frames are stamped in bus order; jitter is well below 1 ms).
_SNAP_MARGIN_S = 0.25
#: struct type letter → numpy kind (the sizes are struct's standard sizes, "<" formats)
_KINDS = {
    "b": "i", "h": "i", "i": "i", "l": "i", "q": "i",
    "B": "u", "H": "u", "I": "u", "L": "u", "Q": "u",
    "e": "f", "f": "f", "d": "f", "?": "b",
}  # fmt: skip


def _record_dtype(fields: list[MappedField], itemsize: int) -> np.dtype | None:
    """One numpy record type for a PDO's decoded fields (little-endian, at their byte offsets),
    or None if a field's format has no plain numpy equivalent."""
    names, formats, offsets = [], [], []
    for k, f in enumerate(fields):
        if not f.fmt:
            continue
        letter = f.fmt.lstrip("<")
        if len(letter) != 1 or letter not in _KINDS or f.offset % 8:
            return None
        names.append(f"f{k}")
        formats.append(f"<{_KINDS[letter]}{struct.calcsize('<' + letter)}")
        offsets.append(f.offset // 8)
    return np.dtype(
        {"names": names, "formats": formats, "offsets": offsets, "itemsize": max(itemsize, 1)}
    )


@dataclass(frozen=True)
class MappedField:
    """One mapped object inside a PDO: ``name`` (OD name), bit ``offset`` and ``bits``,
    struct ``fmt`` ("<f", "<h", ...; "" for unsupported types), ``unit``."""

    name: str
    index: int
    subindex: int
    offset: int
    bits: int
    fmt: str
    unit: str = ""


@dataclass
class TpdoConfig:
    """A TPDO as configured on the drive: number (1-based), COB-ID, transmission type,
    event timer (ms), mapped fields, valid flag (COB-ID bit 31 clear)."""

    number: int
    cob_id: int
    transmission_type: int
    event_timer_ms: int
    fields: list[MappedField] = field(default_factory=list)
    valid: bool = True


def mapped_fields(mapped: Iterable[tuple[int, int, int]], table: ObjectTable) -> list[MappedField]:
    """The fields of a PDO mapping given as (index, sub-index, bits) in order: named and typed
    from ``table`` where the object exists with that length, else ``0xIIII:SS`` (not decoded)."""
    flds = []
    offset = 0
    for index, sub, bits in mapped:
        obj = table.by_index(index, sub)
        if obj is not None and obj.bits == bits:
            flds.append(MappedField(obj.name, index, sub, offset, bits, obj.fmt, obj.unit))
        else:
            flds.append(MappedField(f"0x{index:04X}:{sub:02X}", index, sub, offset, bits, ""))
        offset += bits
    return flds


def read_tpdo_configs(node: canopen.RemoteNode, table: ObjectTable) -> list[TpdoConfig]:
    """The node's TPDO communication and mapping parameters (0x1800–, 0x1A00–), read by SDO
    with canopen's ``TPDO.read()``, as :class:`TpdoConfig` (fields named from ``table``).

    Two things are taken around canopen: every mapping entry is recorded as read (canopen 2.4.1
    drops an entry naming an object its OD lacks with a log warning, which would shift every
    later field; here it is kept as ``0xIIII:SS``, not decoded), and the subscriptions
    ``read()`` makes are dropped again (canopen would decode each frame into ``PdoVariable``
    objects on the bus thread, up to 1 kHz per TPDO; :class:`LiveStreams` decodes into numpy).
    """
    out = []
    maps = node.tpdo.map
    if maps is None:  # canopen makes the maps with the TPDO object: never None for a node
        raise TypeError("the node has no TPDO maps")
    for number, pdo_map in sorted(maps.items()):
        mapped: list[tuple[int, int, int]] = []
        add_variable: Callable[[int, int, int | None], PdoVariable] = pdo_map.add_variable

        def record(
            index: int, subindex: int = 0, length: int | None = None,
            _add: Callable[[int, int, int | None], PdoVariable] = add_variable,
            _mapped: list[tuple[int, int, int]] = mapped,
        ) -> PdoVariable:  # fmt: skip
            _mapped.append((index, subindex, length or 0))
            return _add(index, subindex, length)

        pdo_map.add_variable = record
        try:
            pdo_map.read()
        finally:
            del pdo_map.add_variable
        if pdo_map.enabled and pdo_map.cob_id is not None:
            try:
                node.network.unsubscribe(pdo_map.cob_id, pdo_map.on_message)
            except (KeyError, ValueError):
                pass
        flds = mapped_fields(mapped, table)
        out.append(
            TpdoConfig(
                number,
                (pdo_map.cob_id or 0) & 0x7FF,
                int(pdo_map.trans_type or 0),
                int(pdo_map.event_timer or 0),
                flds,
                valid=bool(pdo_map.enabled),
            )
        )
    return out


class _Stream:
    def __init__(self, cfg: TpdoConfig, capacity: int):
        self.cfg = cfg
        self.capacity = capacity
        self.t = np.zeros(capacity, dtype=np.float64)
        self.values = {f.name: np.zeros(capacity, dtype=np.float64) for f in cfg.fields if f.fmt}
        self.n = 0  # total frames written
        self.frames = 0
        self.bad_length = 0
        self.last_t: float | None = None
        self.window_t0 = 0.0  # first frame of the current cadence window, s
        self.window_frames = 0  # frames received in it
        self.dropped_before = 0  # drops counted in closed windows
        self.recent: list[float] = []  # monotonic arrival times in the last second
        self.since = time.monotonic()  # listening since (s): a rate over less than 1 s
        self.need = sum(f.bits for f in cfg.fields) // 8  # bytes a frame must carry
        self.decoded = [(f"f{k}", f) for k, f in enumerate(cfg.fields) if f.fmt]
        self.dtype = _record_dtype(cfg.fields, self.need)
        #: (stamp s, data, monotonic arrival s) of frames not decoded yet (bus thread appends)
        self.inbox: deque[tuple[float, bytes | bytearray, float]] = deque()

    def window_drops(self) -> int:
        """Frames the event timer promised in the current window that never arrived."""
        ms = self.cfg.event_timer_ms
        if not ms or self.last_t is None:
            return 0
        expected = round((self.last_t - self.window_t0) / (ms / 1000.0)) + 1
        return max(0, expected - self.window_frames)

    @property
    def dropped(self) -> int:
        return self.dropped_before + self.window_drops()


class LiveStreams:
    """Ring buffers for every valid TPDO of one node.

    ``seconds`` × the fastest expected rate sets each buffer's length (at least 1000 samples).
    Thread-safe: frames arrive on the notifier thread, readers take a snapshot under a lock.
    """

    def __init__(
        self,
        network: canopen.Network,
        tpdos: list[TpdoConfig],
        monitor: BusMonitor | None = None,
        bitrate: int | None = None,
        seconds: float = 30.0,
    ):
        self._network = network
        self._lock = threading.Lock()
        self._monitor = monitor
        self._bitrate = bitrate
        self._streams: dict[int, _Stream] = {}
        self.tpdos = [t for t in tpdos if t.valid and t.fields]
        for cfg in self.tpdos:
            rate = 1000.0 / cfg.event_timer_ms if cfg.event_timer_ms > 0 else 1000.0
            self._streams[cfg.cob_id] = _Stream(cfg, max(1000, int(rate * seconds)))
            network.subscribe(cfg.cob_id, self._on_frame)

    def close(self) -> None:
        """Stop listening."""
        for cob_id in self._streams:
            try:
                self._network.unsubscribe(cob_id, self._on_frame)
            except (KeyError, ValueError):
                pass

    @property
    def signals(self) -> list[str]:
        """Names of every decoded signal."""
        return [f.name for c in self.tpdos for f in c.fields if f.fmt]

    @property
    def units(self) -> dict[str, str]:
        """Unit of every decoded signal."""
        return {f.name: f.unit for c in self.tpdos for f in c.fields if f.fmt}

    def _on_frame(self, can_id: int, data: bytearray, timestamp: float) -> None:
        s = self._streams.get(can_id)
        if s is None:
            return
        inbox = s.inbox
        inbox.append((timestamp or time.time(), data, time.monotonic()))  # no copy: each
        # frame's data is its own (python-can's Message, the hub client's direct path)
        if len(inbox) >= BATCH:
            with self._lock:
                self._decode(s)

    def _decode_all(self) -> None:
        """Decode every queued frame (call with the lock held)."""
        for s in self._streams.values():
            if s.inbox:
                self._decode(s)

    def _decode(self, s: _Stream) -> None:
        """Decode the frames queued for ``s`` into its ring buffers (call with the lock held)."""
        inbox = s.inbox
        frames = [inbox.popleft() for _ in range(len(inbox))]  # others may append meanwhile
        if not frames:
            return
        need = s.need
        good = [f for f in frames if len(f[1]) >= need]
        s.bad_length += len(frames) - len(good)
        if not good:
            return
        good = good[-s.capacity :]  # a batch longer than the ring: its newest frames
        m = len(good)
        stamps = [f[0] for f in good]
        idx = (s.n + np.arange(m)) % s.capacity
        s.t[idx] = stamps
        if s.dtype is not None:
            raw = b"".join(f[1] if len(f[1]) == need else f[1][:need] for f in good)
            rec = np.frombuffer(raw, dtype=s.dtype, count=m)
            with np.errstate(invalid="ignore"):  # a signalling NaN stays NaN, as in struct
                for key, fld in s.decoded:
                    s.values[fld.name][idx] = rec[key]
        else:  # a format numpy does not read: one frame at a time
            for _key, fld in s.decoded:
                off = fld.offset // 8
                s.values[fld.name][idx] = [
                    struct.unpack_from(fld.fmt, f[1], off)[0] for f in good
                ]
        last = s.last_t
        for t in stamps:
            if last is None or t - last > _PAUSE_S:  # a pause: a new count window
                s.last_t = last
                s.dropped_before += s.window_drops()
                s.window_t0 = t
                s.window_frames = 0
            s.window_frames += 1
            last = t
        s.last_t = last
        s.n += m
        s.frames += m
        s.recent.extend(f[2] for f in good)
        now_mono = good[-1][2]
        if len(s.recent) > 4 * s.capacity or now_mono - s.recent[0] > 2.0:
            cut = now_mono - 1.0
            s.recent = [x for x in s.recent if x >= cut]

    def _snapshot(
        self, s: _Stream, seconds: float | None
    ) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """Copies of the buffered samples in arrival order: all of them, or those stamped at
        most ``seconds`` before the newest. Only the tail that can hold them is copied: it
        reaches back to a sample stamped _SNAP_MARGIN_S before that (found by bisection on
        the nearly sorted stamps), so a sample stamped that much out of order is not seen."""
        cap = s.capacity
        n = min(s.n, cap)
        if seconds is not None and n:
            newest = s.t[(s.n - 1) % cap]
            below = newest - seconds - _SNAP_MARGIN_S
            t_ring, end = s.t, s.n
            if t_ring[(end - n) % cap] < below:  # the oldest is out of the window: bisect
                lo, hi = 0, n  # a tail of hi samples reaches below, one of lo does not
                while hi - lo > 1:
                    mid = (lo + hi) // 2
                    if t_ring[(end - mid) % cap] < below:
                        hi = mid
                    else:
                        lo = mid
                n = hi
        i0 = (s.n - n) % cap
        if i0 + n <= cap:
            t = s.t[i0 : i0 + n].copy()
            vals = {k: v[i0 : i0 + n].copy() for k, v in s.values.items()}
        else:  # wraps around the ring's end
            j = i0 + n - cap
            t = np.concatenate((s.t[i0:], s.t[:j]))
            vals = {k: np.concatenate((v[i0:], v[:j])) for k, v in s.values.items()}
        if seconds is not None and n:
            keep = t >= t[-1] - seconds
            if not keep.all():
                t = t[keep]
                vals = {k: v[keep] for k, v in vals.items()}
        return t, vals

    def streams(self, seconds: float | None = None) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """Every signal with its own time base: ``{name: (t, values)}`` (t in s, host clock)."""
        out: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        with self._lock:
            self._decode_all()
            for s in self._streams.values():
                t, vals = self._snapshot(s, seconds)
                for k, v in vals.items():
                    out[k] = (t, v)
        return out

    def window(self, seconds: float, signals: list[str] | None = None) -> dict[str, np.ndarray]:
        """The last ``seconds`` s of live data on one time base.

        ``"t"`` (s, host clock, float64) is the time base of the fastest stream holding a
        requested signal; every other signal is sampled on it with zero-order hold (NaN before
        its first frame). Empty arrays before any frame.
        """
        wanted = signals or self.signals
        with self._lock:
            self._decode_all()
            snaps = {  # only the streams that hold a wanted signal
                cob: self._snapshot(s, seconds)
                for cob, s in self._streams.items()
                if any(w in s.values for w in wanted)
            }
        unknown = [w for w in wanted if not any(w in v for _, v in snaps.values())]
        if unknown:
            raise KeyError(
                f"not a live signal: {', '.join(unknown)} (live: {', '.join(self.signals)})"
            )
        candidates = [snap for snap in snaps.values() if any(w in snap[1] for w in wanted)]
        base_t = max(candidates, key=lambda snap: len(snap[0]))[0] if candidates else np.zeros(0)
        out: dict[str, np.ndarray] = {"t": base_t}
        held: dict[int, tuple[np.ndarray, np.ndarray]] = {}  # per time base: (index, before)
        for name in wanted:
            for t, vals in snaps.values():
                if name in vals:
                    v = vals[name]
                    if t is base_t:
                        out[name] = v
                    elif len(t) == 0:
                        out[name] = np.full(len(base_t), np.nan)
                    else:
                        if id(t) not in held:  # once per stream, not per signal
                            j = np.searchsorted(t, base_t, side="right") - 1
                            held[id(t)] = (np.maximum(j, 0), j < 0)
                        j0, before = held[id(t)]
                        res = v[j0]
                        res[before] = np.nan
                        out[name] = res
                    break
        return out

    def latest(self) -> dict[str, float]:
        """Most recent value of every signal (NaN before the first frame)."""
        out: dict[str, float] = {}
        with self._lock:
            self._decode_all()
            for s in self._streams.values():
                for k, v in s.values.items():
                    out[k] = float(v[(s.n - 1) % s.capacity]) if s.n else float("nan")
        return out

    @property
    def stats(self) -> dict[str, Any]:
        """Counters: per TPDO frames, dropped (estimated from cadence gaps), rate_hz (measured
        over the last second, or over the time since listening began when that is shorter: a
        0.5 s ``live`` run reported 50 Hz for a 100 Hz TPDO), expected_hz; totals; bus frames/s
        and bus load (fraction of bitrate)."""
        now = time.monotonic()
        per: dict[str, dict[str, Any]] = {}
        with self._lock:
            self._decode_all()
            for s in self._streams.values():
                # arrival times are appended in order: count the last second by bisection
                in_last_s = len(s.recent) - bisect.bisect_left(s.recent, now - 1.0)
                span = min(1.0, max(now - s.since, 1e-3))
                per[f"TPDO{s.cfg.number}"] = {
                    "cob_id": s.cfg.cob_id,
                    "signals": list(s.values),
                    "frames": s.frames,
                    "dropped": s.dropped,
                    "bad_length": s.bad_length,
                    "rate_hz": in_last_s / span,
                    "expected_hz": 1000.0 / s.cfg.event_timer_ms if s.cfg.event_timer_ms else None,
                }
        out: dict[str, Any] = {
            "tpdo": per,
            "frames": sum(p["frames"] for p in per.values()),
            "dropped": sum(p["dropped"] for p in per.values()),
        }
        if self._monitor is not None:
            fps, bps = self._monitor.rates()
            out["bus_frames_per_s"] = fps
            out["bus_load"] = bps / self._bitrate if self._bitrate else None
        return out

    def reset_counters(self) -> None:
        """Zero the frame and drop counters (buffers are kept)."""
        with self._lock:
            self._decode_all()
            for s in self._streams.values():
                s.frames = s.bad_length = s.dropped_before = s.window_frames = 0
                s.last_t = None
