"""drive_link's live streams decode frames in batches (issue 11): checked against struct, one
frame at a time, over batch boundaries, ring wrap-around, short frames, pauses and jittered
stamps, and read at arbitrary moments (a reader decodes whatever is queued)."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from drive_link.link._live import BATCH, LiveStreams, MappedField, TpdoConfig

pytestmark = pytest.mark.unit


class _Network:
    """Stands in for canopen's Network: keeps the subscriptions, delivers frames."""

    def __init__(self) -> None:
        self.subs: dict[int, list] = {}

    def subscribe(self, cob_id, cb) -> None:
        self.subs.setdefault(cob_id, []).append(cb)

    def unsubscribe(self, cob_id, cb) -> None:
        self.subs[cob_id].remove(cb)

    def notify(self, cob_id, data, stamp) -> None:
        for cb in self.subs.get(cob_id, ()):
            cb(cob_id, bytearray(data), stamp)


FIELDS_1 = [
    MappedField("statusword", 0x6041, 0, 0, 16, "<H"),
    MappedField("velocity_actual_value", 0x606C, 0, 16, 32, "<l", "rpm"),
    MappedField("0x2000:01", 0x2000, 1, 48, 8, ""),  # unknown to the host: not decoded
    MappedField("flag", 0x2000, 2, 56, 8, "<b"),
]
FIELDS_2 = [
    MappedField("measurements.i_p", 0x2040, 1, 0, 32, "<f", "A"),
    MappedField("measurements.speed", 0x2040, 5, 32, 32, "<f", "rpm"),
]


def test_batched_decode_matches_struct_frame_by_frame():
    net = _Network()
    cfgs = [TpdoConfig(1, 0x181, 0xFF, 10, FIELDS_1), TpdoConfig(2, 0x281, 0xFF, 1, FIELDS_2)]
    live = LiveStreams(net, cfgs, seconds=1.0)  # rings of 1000 samples: they wrap below
    rng = np.random.default_rng(11)
    want: dict[str, list[tuple[float, float]]] = {
        "statusword": [], "velocity_actual_value": [], "flag": [],
        "measurements.i_p": [], "measurements.speed": [],
    }  # fmt: skip
    short = {0x181: 0, 0x281: 0}
    t = 1000.0
    for k in range(3000):
        cob = 0x181 if k % 5 == 0 else 0x281
        t += 1e-3 + rng.uniform(-4e-4, 4e-4) + (2.5 if k == 1700 else 0.0)  # one pause
        fields = FIELDS_1 if cob == 0x181 else FIELDS_2
        data = rng.bytes(8)
        if k % 97 == 0:  # a short frame: counted, not decoded
            net.notify(cob, data[:5], t)
            short[cob] += 1
            continue
        net.notify(cob, data, t)
        for f in fields:
            if f.fmt:
                want[f.name].append((t, struct.unpack_from(f.fmt, data, f.offset // 8)[0]))
        if k in (5, BATCH + 3, 999, 2500):  # readers in the middle of a batch
            got = live.latest()
            for name, series in want.items():
                if series:
                    assert got[name] == series[-1][1] or (
                        np.isnan(got[name]) and np.isnan(series[-1][1])
                    )
    streams = live.streams()
    for name, series in want.items():
        tail = series[-1000:] if name.startswith("measurements") else series
        t_got, v_got = streams[name]
        np.testing.assert_array_equal(t_got, [s[0] for s in tail])
        np.testing.assert_array_equal(v_got, np.array([s[1] for s in tail], dtype=np.float64))
    stats = live.stats
    assert stats["tpdo"]["TPDO1"]["bad_length"] == short[0x181]
    assert stats["tpdo"]["TPDO2"]["bad_length"] == short[0x281]
    assert stats["tpdo"]["TPDO2"]["frames"] == len(want["measurements.i_p"])
    # the last 0.5 s: every sample stamped within it, none older, in arrival order
    w = live.window(0.5, ["measurements.speed"])
    series = want["measurements.speed"]
    newest = series[-1][0]
    expect = [s for s in series[-1000:] if s[0] >= newest - 0.5]
    np.testing.assert_array_equal(w["t"], [s[0] for s in expect])
    np.testing.assert_array_equal(w["measurements.speed"], [s[1] for s in expect])
    live.close()
    assert not any(net.subs.values())
