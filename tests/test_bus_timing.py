"""Timing the bus can check (issue 29, item 4): inhibit time and RPDO-before-SYNC, on the hub.

Truths: CiA 301 §7.5.2.35: the inhibit time (sub 3, 100 µs units) is the minimum time between
two transmissions of a TPDO, so on the bus no two frames of TPDO2 with inhibit 1.5 ms and
event timer 1 ms are closer than 1.5 ms (frame end to frame end, as a receiver stamps them;
the drive states and the hub stamps µs, hence 3 µs of tolerance). CiA 301 §7.2.2.4: a
synchronous TPDO (transmission type 1) carries the values the node holds when it serves the
SYNC; frames reach a node in bus order, so an RPDO that precedes the SYNC on the bus must be
in those values.
Measured with stock canopen (RemoteNode/SdoClient) and a python-can socketcand sniffer on the
loopback hub, whose time stamps are bus times; the drive is a ``virtual-drive run`` child.
"""

from __future__ import annotations

import itertools
import os
import struct
import time

import can
import canopen
import pytest

from firmware_protocol import load_od

pytestmark = pytest.mark.timeout(120)

TOL_S = 3e-6  #: µs stamps at both ends (the drive states µs, the hub stamps µs)


@pytest.fixture(scope="module")
def bench():
    from virtual_drive.launch import virtual_bench

    with virtual_bench(nodes=(1,)) as settings:
        hub = settings.hub
        net = canopen.Network(can.Bus(**hub.join_kwargs()))
        net.connect()
        node = canopen.RemoteNode(1, load_od(node_id=1).canopen_od(1))
        net.add_node(node)
        node.sdo.RESPONSE_TIMEOUT = 5.0
        sniff = can.Bus(**hub.join_kwargs())
        try:
            yield net, node, sniff, hub
        finally:
            net.send_message(0, bytes([0x81, 1]))  # reset node: the defaults for the next test
            sniff.shutdown()
            net.disconnect()


def drain(sniff: can.BusABC) -> None:
    while sniff.recv(0) is not None:
        pass


def collect(sniff: can.BusABC, seconds: float) -> list[can.Message]:
    out = []
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        m = sniff.recv(0.05)
        if m is not None:
            out.append(m)
    return out


def test_inhibit_time_holds_on_the_bus(bench):
    net, node, sniff, hub = bench
    comm = node.sdo[0x1801]
    comm[1].raw = 0x80000281
    comm[3].raw = 15  # 1.5 ms
    comm[5].raw = 1  # 1 ms event timer: the inhibit time binds
    comm[1].raw = 0x281
    missed0 = node.sdo["tpdo_missed_events"][2].raw
    net.send_message(0, bytes([0x01, 1]))
    time.sleep(0.3)
    drain(sniff)
    load = os.getloadavg()[0]
    late0 = hub.stats.frames_late
    frames = collect(sniff, 2.0)
    late = hub.stats.frames_late - late0
    net.send_message(0, bytes([0x80, 1]))
    t = [m.timestamp for m in frames if m.arbitration_id == 0x281]
    gaps = [b - a for a, b in itertools.pairwise(t)]
    short = [round(g * 1e3, 4) for g in gaps if g < 1.5e-3 - TOL_S]
    missed = node.sdo["tpdo_missed_events"][2].raw - missed0
    assert len(t) > 500, len(t)
    if short and late:
        # the hub (in this process) or the drive was kept from running for more than the
        # hub's 5 ms spacing hold: frames reached the bus late, and the emulated bus shows the
        # host's stall, not the drive's timing (which a frame reaching the hub on time keeps)
        pytest.skip(
            f"not judged: the host stalled the bus ({late} frames reached the hub more than "
            f"5 ms after their stated time; load {load:.1f}): {len(short)} of {len(gaps)} "
            f"gaps under 1.5 ms: {short[:10]}"
        )
    assert not short, f"{len(short)} of {len(gaps)} gaps under 1.5 ms: {short[:10]} (load {load})"
    # frames the drive could not send on time are counted, never squeezed in: the bus shows
    # at most the 666.7 Hz the inhibit time allows
    assert len(t) / (t[-1] - t[0]) <= 1 / 1.5e-3 * 1.001 + 1, len(t)
    assert missed >= 0


def test_rpdo_is_in_the_od_before_the_sync_that_follows_it(bench):
    """RPDO1 (controlword, target_velocity) and a SYNC right behind it on the bus; TPDO4 maps
    0x60FF with transmission type 1: each SYNC's TPDO carries the target sent just before."""
    net, node, sniff, _ = bench
    comm, mapping = node.sdo[0x1803], node.sdo[0x1A03]
    comm[1].raw = 0x80000481
    mapping[0].raw = 0
    mapping[1].raw = 0x60FF0020
    mapping[0].raw = 1
    comm[2].raw = 1  # every SYNC
    comm[1].raw = 0x481
    net.send_message(0, bytes([0x01, 1]))
    time.sleep(0.2)
    drain(sniff)
    n = 200
    for k in range(n):
        net.send_message(0x201, struct.pack("<Hi", 0, 1000 + k))
        net.send_message(0x080, b"")
        time.sleep(0.005)
    frames = collect(sniff, 0.5)
    net.send_message(0, bytes([0x80, 1]))
    # the k-th SYNC on the bus triggers the k-th TPDO4 (they may overtake the next RPDO:
    # the drive answers a SYNC within a few ms)
    last_target, rpdo_at = None, 0.0
    syncs, tpdos = [], []
    for m in frames:  # in bus order
        if m.arbitration_id == 0x201:
            last_target, rpdo_at = struct.unpack_from("<i", m.data, 2)[0], m.timestamp
        elif m.arbitration_id == 0x080:
            syncs.append((m.timestamp, last_target, m.timestamp - rpdo_at))
        elif m.arbitration_id == 0x481:
            tpdos.append((m.timestamp, struct.unpack("<i", m.data)[0]))
    checked = min(len(syncs), len(tpdos))
    stale = [(s[1], t[1]) for s, t in zip(syncs, tpdos, strict=False) if s[1] != t[1]]
    answer_ms = sorted((t[0] - s[0]) * 1e3 for s, t in zip(syncs, tpdos, strict=False))
    print(
        f"RPDO->SYNC max {max(s[2] for s in syncs) * 1e3:.3f} ms; SYNC->TPDO p50 "
        f"{answer_ms[len(answer_ms) // 2]:.2f} ms, max {answer_ms[-1]:.2f} ms "
        f"(load {os.getloadavg()[0]:.1f})"
    )
    assert checked >= 0.9 * n, checked
    assert not stale, f"{len(stale)} of {checked} SYNC TPDOs showed an older target: {stale[:5]}"
    # (the SYNC follows its RPDO by one frame time on an idle host, by the master's own
    # delays under load: the bound tested is "in bus order", whatever the distance)
