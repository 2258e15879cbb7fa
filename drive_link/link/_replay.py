"""``drive-link replay FILE``: a bus recording decoded offline into the live and trace views.

The file is read once with :class:`can.LogReader` (any format python-can reads: .asc, .blf, .log,
.csv, .trc, .mf4 with asammdf), so recordings from Vector tools, SavvyCAN or candump work too.

* TPDOs are decoded by the same :class:`~drive_link.link._live.LiveStreams` the live view uses, fed
  from the file instead of the bus. The mapping is the one the drive reported in the recording
  (SDO reads of 0x1800+k/0x1A00+k, as ``drive-link`` does when its live view starts) or, if the
  recording has none, the object dictionary's defaults for node ``--node``.
* SDO traffic of node N on both servers (0x600+N/0x580+N and 0x1201's COB-IDs) is followed:
  expedited values are kept, and every block upload is reassembled (CiA 301 §7.2.4.3.10-14: the
  sub-blocks as acknowledged by the client, so retransmitted segments count once, the unused
  bytes of the last segment dropped). A block upload of trace_data (0x2102) becomes a
  :class:`~drive_link.link.trace.Trace` with the channel list, length, divider and trigger position
  the client read just before it.
"""

from __future__ import annotations

import binascii
import bisect
import collections
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import can
import canopen
import numpy as np

from ..errors import InvalidValue
from ._live import LiveStreams, TpdoConfig, mapped_fields
from ._objects import ObjectTable, default_table
from ._replay_epochs import Epoch, count_drops, epochs
from .trace import TRACE_DATA, TS, Trace

__all__ = ["BlockUpload", "Replay", "SdoFollower", "replay_file"]

#: Timestamps fed to LiveStreams start here (it takes 0.0 as "no timestamp").
_T0 = 1.0


@dataclass
class BlockUpload:
    """One reassembled SDO upload (``kind`` "block" or "segmented"): ``index``, ``subindex``,
    ``data``, time ``t`` (s from the start of the recording) of its end, ``size`` announced by
    the server (None if not), ``crc_ok`` (the CRC-16 of a block upload's end frame checked
    against the data; None without CRC)."""

    index: int
    subindex: int
    data: bytes
    t: float
    size: int | None = None
    crc_ok: bool | None = None
    kind: str = "block"  # or "segmented"

    @property
    def complete(self) -> bool:
        """The data has the announced size and CRC (as far as the transfer gave them)."""
        return (self.size is None or len(self.data) == self.size) and self.crc_ok is not False


class _BlockState:
    def __init__(self, index: int, sub: int, crc: bool):
        self.index, self.sub = index, sub
        self.phase = "init"  # init → start → segments → end
        self.crc = crc  # client offered CRC; the server's answer confirms
        self.size: int | None = None
        self.data = bytearray()
        self.block: list[tuple[int, bytes, bool]] = []
        self.await_first = True  # after an acknowledgement: leftovers until seqno 1
        self.ack_no: int | None = None  # drive_link's acknowledgement number (byte 3)


class SdoFollower:
    """Follows the SDO traffic of one server (client→server ``rx`` COB-ID, server→client ``tx``):
    expedited and segmented upload answers and confirmed expedited downloads into ``values``
    ((index, sub) → raw bytes), completed block and segmented uploads into ``uploads``
    (a segment repeating the previous toggle bit is the answer to a resent request: dropped).

    Block uploads are followed as the client takes them (:mod:`drive_link.link._sdo_block`): a
    sub-block starts at seqno 1 (segments still arriving from the previous one are dropped),
    the acknowledgement's ``ackseq`` says how many segments count, and an acknowledgement that
    repeats the previous one's number (reserved byte 3, drive_link's extension; 0 = none) is a
    resend the server ignores, so it is ignored here too.
    """

    def __init__(self, rx: int, tx: int):
        self.rx, self.tx = rx, tx
        self.values: dict[tuple[int, int], bytes] = {}
        #: (t, index, sub, raw) of every value seen, in time order: ``writes`` are downloads
        #: the server confirmed, ``reads`` upload answers
        self.writes: list[tuple[float, int, int, bytes]] = []
        self.reads: list[tuple[float, int, int, bytes]] = []
        self.uploads: list[BlockUpload] = []
        self.aborted = 0
        self._block: _BlockState | None = None
        self._download: tuple[int, int, bytes] | None = None
        self._seg: list = []  # segmented upload: [index, sub, size, toggle, data]

    def feed(self, can_id: int, data: bytes, t: float) -> None:
        """One frame (ignored unless it is on this server's COB-IDs)."""
        if len(data) < 1:
            return
        if can_id == self.rx:
            self._client(data)
        elif can_id == self.tx:
            self._server(data, t)

    def _client(self, d: bytes) -> None:
        b0 = d[0]
        blk = self._block
        if b0 == 0x80:  # abort
            self._block = None
            self._seg = []
            self.aborted += 1
            return
        ccs, cs = b0 >> 5, b0 & 0x03
        if b0 == 0x40 and len(d) >= 4:  # upload initiate (expedited or segmented answer)
            self._seg = [d[1] | d[2] << 8, d[3], None, None, bytearray()]
            return
        if ccs == 5 and len(d) >= 4 and cs == 0:  # block upload initiate
            self._block = _BlockState(d[1] | d[2] << 8, d[3], bool(b0 & 0x04))
        elif ccs == 5 and blk is not None and cs == 3 and blk.phase == "start":
            blk.phase = "segments"
        elif ccs == 5 and blk is not None and cs == 2 and blk.phase == "segments":
            number = d[3] if len(d) > 3 else 0
            if number and number == blk.ack_no:
                return  # a resent acknowledgement: the server ignores it
            blk.ack_no = number
            self._ack(blk, d[1] if len(d) > 1 else 0)
        elif ccs == 5 and cs == 1:  # client's end confirmation
            self._block = None
        elif ccs == 1 and len(d) >= 8 and b0 & 0x02 and b0 & 0x01:  # expedited download, size
            n = 4 - ((b0 >> 2) & 0x03)
            self._download = (d[1] | d[2] << 8, d[3], bytes(d[4 : 4 + n]))

    def _ack(self, blk: _BlockState, ackseq: int) -> None:
        """Commit segments 1..ackseq of the sub-block in order (first copy of each)."""
        got: dict[int, tuple[bytes, bool]] = {}
        for seq, payload, last in blk.block:
            got.setdefault(seq, (payload, last))
        for seq in range(1, ackseq + 1):
            if seq not in got:
                break  # the recording missed a segment the client had: data incomplete
            payload, last = got[seq]
            blk.data += payload
            if last:
                blk.phase = "end"
                break
        blk.block = []
        blk.await_first = True

    def _server(self, d: bytes, t: float) -> None:
        b0 = d[0]
        blk = self._block
        if blk is not None and blk.phase == "segments":
            seq = b0 & 0x7F
            if seq == 0:  # not a segment: an abort (0x80 …)
                self._block = None
                self.aborted += 1
                return
            if blk.await_first and seq != 1:
                return  # a leftover of the sub-block already acknowledged
            blk.await_first = False
            blk.block.append((seq, bytes(d[1:8]).ljust(7, b"\0"), bool(b0 & 0x80)))
            return
        if b0 == 0x80:
            self._block = None
            self._download = None
            self.aborted += 1
            return
        scs = b0 >> 5
        if scs == 6 and blk is not None:
            if blk.phase == "init" and (b0 & 0x01) == 0:
                blk.crc = blk.crc and bool(b0 & 0x04)
                if b0 & 0x02 and len(d) >= 8:
                    blk.size = int.from_bytes(d[4:8], "little")
                blk.phase = "start"
            elif blk.phase == "end" and (b0 & 0x03) == 1:
                unused = (b0 >> 2) & 0x07
                data = bytes(blk.data[: len(blk.data) - unused] if unused else blk.data)
                crc_ok = None
                if blk.crc and len(d) >= 3:
                    crc_ok = binascii.crc_hqx(data, 0) == (d[1] | d[2] << 8)
                self.uploads.append(BlockUpload(blk.index, blk.sub, data, t, blk.size, crc_ok))
                self._block = None
        elif scs == 2 and not b0 & 0x02 and self._seg:  # segmented upload begins
            if b0 & 0x01 and len(d) >= 8:
                self._seg[2] = int.from_bytes(d[4:8], "little")
            self._seg[3] = 0
        elif scs == 0 and self._seg and self._seg[3] is not None:  # an upload segment
            index, sub, size, toggle, data = self._seg
            if (b0 >> 4) & 1 != toggle:
                return  # the same segment again (a resent request answered twice)
            data += d[1 : 8 - ((b0 >> 1) & 0x07)]
            self._seg[3] = toggle ^ 1
            if b0 & 0x01:  # the last one
                self.values[(index, sub)] = bytes(data)
                self.reads.append((t, index, sub, bytes(data)))
                self.uploads.append(BlockUpload(index, sub, bytes(data), t, size, None,
                                                "segmented"))
                self._seg = []
        elif scs == 2 and len(d) >= 8 and b0 & 0x02:  # expedited upload answer
            n = 4 - ((b0 >> 2) & 0x03) if b0 & 0x01 else 4
            self.values[(d[1] | d[2] << 8, d[3])] = bytes(d[4 : 4 + n])
            self.reads.append((t, d[1] | d[2] << 8, d[3], bytes(d[4 : 4 + n])))
        elif scs == 3 and len(d) >= 4 and self._download is not None:  # download confirmed
            idx, sub, raw = self._download
            if (d[1] | d[2] << 8, d[3]) == (idx, sub):
                self.values[(idx, sub)] = raw
                self.writes.append((t, idx, sub, raw))
            self._download = None


def _default_int(table: ObjectTable, name: str, node: int) -> int:
    text = str(table[name].default).replace("$NODEID", str(node)).replace(" ", "")
    return sum(int(part, 0) for part in text.split("+") if part)


class _Known:
    """Values of node N's objects: what the recording showed, else the EDS default; with
    ``at`` set (s from the first frame), the value in force then: the last value written or
    read by then, else the first one read later (unless a write came first: the EDS default)."""

    def __init__(self, table: ObjectTable, node: int, followers: list[SdoFollower]):
        self.table, self.node, self.followers = table, node, followers
        self.at: float | None = None
        self._events: dict[tuple[int, int], list[tuple[float, bool, bytes]]] = {}
        for f in followers:
            for tt, index, sub, raw in f.writes:
                self._events.setdefault((index, sub), []).append((tt, True, raw))
            for tt, index, sub, raw in f.reads:
                self._events.setdefault((index, sub), []).append((tt, False, raw))
        for ev in self._events.values():
            ev.sort(key=lambda e: e[0])

    def _seen(self, index: int, sub: int) -> bytes | None:
        ev = self._events.get((index, sub), [])
        if self.at is None:
            return ev[-1][2] if ev else None
        before = [e for e in ev if e[0] <= self.at]
        if before:
            return before[-1][2]
        later = [e for e in ev if e[0] > self.at]
        return later[0][2] if later and not later[0][1] else None

    def raw(self, name: str) -> Any:
        obj = self.table[name]
        raw = self._seen(obj.index, obj.subindex)
        if raw is not None:
            try:
                return obj.decode(raw)
            except Exception:
                pass
        return _default_int(self.table, name, self.node)

    def int(self, name: str) -> int:
        return int(self.raw(name))


def tpdo_configs(known: _Known, at: float | None = None) -> list[TpdoConfig]:
    """The node's TPDOs as the recording (or the EDS) has them (at ``at`` s, or at the end)."""
    known.at = at
    try:
        return _tpdo_configs(known)
    finally:
        known.at = None


def _tpdo_configs(known: _Known) -> list[TpdoConfig]:
    table = known.table
    out = []
    for k in range(1, 513):
        comm = f"tpdo{k}_communication"
        if f"{comm}.cob_id" not in table:
            break
        cob = known.int(f"{comm}.cob_id")
        refs = [
            known.int(f"tpdo{k}_mapping.mapped_object_{i}")
            for i in range(1, known.int(f"tpdo{k}_mapping.number_of_mapped_objects") + 1)
        ]
        flds = mapped_fields(((r >> 16, (r >> 8) & 0xFF, r & 0xFF) for r in refs), table)
        out.append(
            TpdoConfig(
                k,
                cob & 0x7FF,
                known.int(f"{comm}.transmission_type"),
                known.int(f"{comm}.event_timer"),
                flds,
                valid=not cob & 0x80000000,
            )
        )
    return out


@dataclass
class Replay:
    """A decoded recording: ``live`` (TPDO streams, times from :data:`_T0`), ``traces``,
    frames per CAN-ID, ``duration`` (s), ``start`` (timestamp of the first frame)."""

    path: Path
    node: int
    live: LiveStreams
    frames: int
    error_frames: int
    duration: float
    start: float
    per_id: dict[int, int]
    uploads: list[BlockUpload] = field(default_factory=list)
    traces: list[Trace] = field(default_factory=list)
    #: per TPDO ("TPDO2"): dropped and expected rates judged per configuration epoch
    judged: dict[str, dict[str, Any]] = field(default_factory=dict)
    #: configuration epochs (1 = the TPDO configuration never changed in the recording)
    epochs: int = 1

    def table(self) -> dict[str, np.ndarray]:
        """Every TPDO signal on one time base (``t`` in s from the first frame of the file)."""
        w = self.live.window(self.duration + 2 * _T0)
        w["t"] = w["t"] - _T0
        return w

    def summary(self) -> dict[str, Any]:
        """JSON-ready: frames, duration, per-ID counts, per-TPDO frames/rate/dropped, signal
        statistics (min, max, mean, last), traces (samples, dt, channels)."""
        st = self.live.stats
        dur = max(self.duration, 1e-9)
        tpdo = {
            k: {
                "cob_id": f"0x{v['cob_id']:03X}",
                "frames": v["frames"],
                "dropped": v["dropped"],
                "rate_hz": v["frames"] / dur,
                "expected_hz": v["expected_hz"],
                **self.judged.get(k, {}),
            }
            for k, v in st["tpdo"].items()
        }
        sig = {}
        for name, (_t, y) in self.live.streams().items():
            y = y[np.isfinite(y)]
            if len(y):
                sig[name] = {
                    "unit": self.live.units.get(name, ""),
                    "min": float(y.min()),
                    "max": float(y.max()),
                    "mean": float(y.mean()),
                    "last": float(y[-1]),
                }
        return {
            "file": str(self.path),
            "node": self.node,
            "frames": self.frames,
            "error_frames": self.error_frames,
            "seconds": self.duration,
            "tpdo_configurations": self.epochs,
            "frames_per_id": {f"0x{k:03X}": v for k, v in sorted(self.per_id.items())},
            "tpdo": tpdo,
            "signals": sig,
            "uploads": [
                {"kind": u.kind, "index": f"0x{u.index:04X}", "subindex": u.subindex,
                 "bytes": len(u.data),
                 "size": u.size, "crc_ok": u.crc_ok, "complete": u.complete, "t": u.t}
                for u in self.uploads
            ],
            "traces": [
                {"samples": len(tr.t), "dt": tr.dt, "trigger_index": tr.trigger_index,
                 "channels": list(tr.signals), "t": tr.meta.get("t")}
                for tr in self.traces
            ],
        }


def _trace_from(upload: BlockUpload, known: _Known) -> Trace | None:
    """The trace in ``upload`` with the configuration read before it (None if it does not fit)."""
    table = known.table
    try:
        count = known.int("trace_config.channel_count")
        length = known.int("trace_config.length")
        divider = known.int("trace_config.divider")
        trig = known.int("trace_config.trigger_position")
        names = []
        for i in range(1, count + 1):
            ref = known.int(f"trace_channels.channel_{i}")
            obj = table.by_index(ref >> 16, (ref >> 8) & 0xFF)
            names.append(obj.name if obj else f"0x{ref >> 16:04X}:{(ref >> 8) & 0xFF:02X}")
    except (KeyError, ValueError):
        return None
    if count < 1 or not upload.complete or len(upload.data) != length * count * 4:
        return None
    data = np.frombuffer(upload.data, dtype="<f4").reshape(length, count)
    t = (np.arange(length, dtype=np.float64) - trig) * divider * TS
    signals = {n: data[:, i].copy() for i, n in enumerate(names)}
    units = {n: (table[n].unit if n in table else "") for n in names}
    return Trace(t, signals, units, trig, divider, meta={"t": upload.t, "source": "replay"})


def _reader(path: Path) -> Iterable[can.Message]:
    """python-can's reader for ``path`` (``can.LogReader`` is a function: its result is a
    ``MessageReader``, iterable over the recorded frames)."""
    if not path.is_file():
        raise InvalidValue(f"{path}: no such file")
    try:
        return can.LogReader(path)
    except (ValueError, NotImplementedError, ImportError) as exc:
        raise InvalidValue(f"{path}: {str(exc).splitlines()[0]}") from None


def replay_file(path: str | Path, node: int = 1, table: ObjectTable | None = None) -> Replay:
    """Decode the recording at ``path`` for node ``node`` (see the module docstring)."""
    p = Path(path)
    if not 1 <= node <= 127:
        raise InvalidValue(f"node-ID {node} outside 1..127")
    table = table or default_table()  # defaults keep $NODEID: resolved for ``node`` here
    servers = [(0x600 + node, 0x580 + node)]
    try:
        servers.append(
            (
                _default_int(table, "sdo_server_2.cob_id_client_to_server", node) & 0x7FF,
                _default_int(table, "sdo_server_2.cob_id_server_to_client", node) & 0x7FF,
            )
        )
    except KeyError:
        pass
    followers = [SdoFollower(rx, tx) for rx, tx in servers]
    per_id: collections.Counter[int] = collections.Counter()
    errors = 0
    start = end = None
    pdo_frames: list[tuple[int, bytes, float]] = []  # decoded once the mapping is known
    try:
        for msg in _reader(p):
            if msg.is_error_frame:
                errors += 1
                continue
            ts = float(msg.timestamp)
            if start is None:
                start = ts
            end = ts
            cid = msg.arbitration_id
            per_id[cid] += 1
            if 0x180 <= cid < 0x580:
                pdo_frames.append((cid, bytes(msg.data), ts - start))
            else:
                for f in followers:
                    f.feed(cid, bytes(msg.data), ts - start)
    except InvalidValue:
        raise
    except Exception as exc:  # a damaged or foreign file: one line
        why = str(exc).splitlines()[0] if str(exc) else repr(exc)
        raise InvalidValue(f"{p}: cannot read: {why}") from None
    if start is None or end is None:
        raise InvalidValue(f"{p}: no CAN frames in the file")
    duration = float(end - start)
    known = _Known(table, node, followers)
    writes = sorted((w for f in followers for w in f.writes), key=lambda w: w[0])
    eps = epochs(writes, lambda at: tpdo_configs(known, at))
    chosen, judged = _judge(eps, pdo_frames)
    net = canopen.Network()  # no bus: frames are handed to its subscribers by notify()
    live = LiveStreams(net, chosen, seconds=duration + 2.0)
    starts = [e.t0 for e in eps]
    for cid, data, t in pdo_frames:  # the live view's own decoder, each frame in its mapping
        ep = eps[bisect.bisect_right(starts, t) - 1]
        if any(c.cob_id == cid and c in chosen for c in ep.configs):
            net.notify(cid, bytearray(data), t + _T0)
    uploads = [u for f in followers for u in f.uploads]
    uploads.sort(key=lambda u: u.t)
    traces = []
    for u in uploads:
        if (u.index, u.subindex) == TRACE_DATA:
            tr = _trace_from(u, known)
            if tr is not None:
                traces.append(tr)
    return Replay(p, node, live, sum(per_id.values()), errors, duration, start, dict(per_id),
                  uploads, traces, judged, len(eps))


def _judge(
    eps: list[Epoch], pdo_frames: list[tuple[int, bytes, float]]
) -> tuple[list[TpdoConfig], dict[str, dict[str, Any]]]:
    """Per TPDO: the configuration its signals are decoded with (the one in force for most of
    its frames) and, over every epoch, the drops against that epoch's event timer."""
    starts = [e.t0 for e in eps]
    stamps: dict[tuple[int, int], list[float]] = collections.defaultdict(list)  # (epoch, cob)
    for cid, _data, t in pdo_frames:
        stamps[(bisect.bisect_right(starts, t) - 1, cid)].append(t)
    best: dict[int, tuple[int, TpdoConfig]] = {}
    judged: dict[str, dict[str, Any]] = {}
    for i, ep in enumerate(eps):
        for c in ep.configs:
            if not (c.valid and c.fields):
                continue
            got = stamps.get((i, c.cob_id), [])
            j = judged.setdefault(f"TPDO{c.number}", {"dropped": 0, "expected_hz": []})
            j["dropped"] += count_drops(got, c.event_timer_ms)
            hz = 1000.0 / c.event_timer_ms if c.event_timer_ms else None
            if got and hz not in j["expected_hz"]:
                j["expected_hz"].append(hz)
            if len(got) > best.get(c.number, (-1, c))[0]:
                best[c.number] = (len(got), c)
    for k, j in judged.items():  # one rate: a number, as before; several: the list in order
        rates = j["expected_hz"]
        if not rates:  # no frame at all: the rate configured at the end
            last = [c for c in eps[-1].configs if f"TPDO{c.number}" == k]
            rates = [1000.0 / last[0].event_timer_ms if last and last[0].event_timer_ms else None]
        j["expected_hz"] = rates[0] if len(rates) == 1 else rates
    return [c for _n, c in sorted(best.values(), key=lambda nc: nc[1].number)], judged
