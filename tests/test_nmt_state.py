"""NMT state from heartbeats (CiA 301 §7.2.8.3.2): one-shot `drive-link status` calls and long
sessions report what the node's own heartbeat frames say, on an idle and on a busy host.

Truth: the heartbeat byte (0x700 + N) read by an independent raw python-can listener, and frames
this test sends itself (HeartbeatMonitor unit tests on a python-can virtual bus).
"""

from __future__ import annotations

import contextlib
import io
import json
import subprocess
import sys
import threading
import time
import uuid

import can
import canopen
import pytest
from scenarios.conditions import CpuHog

from drive_link import cli
from drive_link.errors import DriveTimeout, SdoAbort
from drive_link.link._nmt import NMT_STATES, HeartbeatMonitor

pytestmark = pytest.mark.timeout(240)


# --------------------------------------------------------------------------- helpers
@contextlib.contextmanager
def busy_host():
    """A busy host: two CPU-bound processes per core, fewer or none where the host's load is
    already there (a run beside other jobs; :class:`scenarios.conditions.CpuHog`)."""
    hog = CpuHog().start()
    try:
        yield
    finally:
        hog.stop()


def status_here(port: int) -> tuple[int, dict | str]:
    """One `drive-link status --json` via cli.main: a new bus connection and a fresh
    HeartbeatMonitor each time, as in a one-shot call (without the interpreter start)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli.main(["--host", "127.0.0.1", "--port", str(port), "status", "--json"])
    if rc == 0:
        return rc, json.loads(out.getvalue())
    return rc, (err.getvalue() + out.getvalue()).strip()  # --json: the error is JSON on stdout


class HeartbeatProbe:
    """Independent truth: the last heartbeat byte of node 1 seen on the hub by a raw bus."""

    def __init__(self, port: int):
        self.bus = can.Bus(
            interface="socketcand", host="127.0.0.1", port=port, channel="vcan0", tcp_tune=True
        )
        self.state: str | None = None
        self._stop = threading.Event()
        self._t = threading.Thread(target=self._run, daemon=True)
        self._t.start()

    def _run(self) -> None:
        while not self._stop.is_set():
            msg = self.bus.recv(0.1)
            if msg is not None and msg.arbitration_id == 0x701 and msg.data:
                self.state = NMT_STATES.get(msg.data[0] & 0x7F)

    def wait(self, state: str, timeout: float = 20.0) -> None:
        deadline = time.monotonic() + timeout
        while self.state != state:
            assert time.monotonic() < deadline, f"node never reported {state} ({self.state})"
            time.sleep(0.02)

    def close(self) -> None:
        self._stop.set()
        self._t.join(2)
        self.bus.shutdown()


@pytest.fixture(scope="module")
def hub_drive(tmp_path_factory):
    from virtual_drive.hub import Hub
    from virtual_drive.node import spawn_virtual_drive

    store = tmp_path_factory.mktemp("store") / "params.json"
    with Hub(port=0) as hub:
        proc = spawn_virtual_drive(port=hub.port, node_id=1, store=store, timeout=60)
        probe = HeartbeatProbe(hub.port)
        try:
            yield hub, probe
        finally:
            probe.close()
            proc.stop()


def _nmt(port: int, command: str) -> None:
    with contextlib.redirect_stdout(io.StringIO()):
        assert cli.main(["nmt", command, "--host", "127.0.0.1", "--port", str(port)]) == 0


# --------------------------------------------------------------------------- one-shot calls
@pytest.mark.parametrize(
    "command,state", [("start", "OPERATIONAL"), ("pre-operational", "PRE-OPERATIONAL")]
)
def test_twenty_one_shot_status_calls_report_the_heartbeat_state(hub_drive, command, state):
    hub, probe = hub_drive
    _nmt(hub.port, command)
    probe.wait(state)
    seen = [status_here(hub.port) for _ in range(20)]
    assert probe.state == state  # the node stayed there throughout
    bad = [s if rc else s["nmt_state"] for rc, s in seen if rc or s["nmt_state"] != state]
    assert not bad, f"{len(bad)} of 20 calls said: {bad[:5]}"


def test_one_shot_status_on_a_busy_host(hub_drive):
    hub, probe = hub_drive
    _nmt(hub.port, "start")
    probe.wait("OPERATIONAL")
    with busy_host():
        time.sleep(1.0)  # let the load take hold
        seen = [status_here(hub.port) for _ in range(20)]
        # and as a real process: interpreter start, own bus, exit
        cmd = [sys.executable, "-m", "drive_link.cli", "status", "--json"]
        cmd += ["--host", "127.0.0.1", "--port", str(hub.port)]
        procs = [subprocess.run(cmd, capture_output=True, text=True, timeout=120) for _ in range(3)]
    assert probe.state == "OPERATIONAL"
    bad = [s if rc else s["nmt_state"] for rc, s in seen if rc or s["nmt_state"] != "OPERATIONAL"]
    assert not bad, f"{len(bad)} of 20 calls said: {bad[:5]}"
    for p in procs:
        assert p.returncode == 0, p.stderr
        assert json.loads(p.stdout)["nmt_state"] == "OPERATIONAL"


def test_long_session_on_a_busy_host_never_says_offline(hub_drive):
    from drive_link import Drive

    hub, probe = hub_drive
    _nmt(hub.port, "start")
    probe.wait("OPERATIONAL")
    d = Drive.connect(host="127.0.0.1", port=hub.port, node_id=1, heartbeat_ms=None)
    try:
        with busy_host():
            states = []
            t_end = time.monotonic() + 6.0
            while time.monotonic() < t_end:
                states.append(d.nmt_state)
                time.sleep(0.05)
        assert probe.state == "OPERATIONAL"
        assert set(states) == {"OPERATIONAL"}, {s: states.count(s) for s in set(states)}
    finally:
        d.close()


# --------------------------------------------------------------------------- monitor rules
@pytest.fixture
def vbus():
    ch = f"nmt-{uuid.uuid4().hex}"
    net = canopen.Network(can.Bus(interface="virtual", channel=ch))
    net.connect()
    tx = can.Bus(interface="virtual", channel=ch)
    yield net, tx
    net.disconnect()
    tx.shutdown()


def _hb(tx: can.BusABC, state: int, node: int = 1) -> None:
    tx.send(can.Message(arbitration_id=0x700 + node, data=[state], is_extended_id=False))


@pytest.mark.unit
def test_first_heartbeat_is_awaited_per_producer_time(vbus):
    net, tx = vbus
    mon = HeartbeatMonitor(net, 1)
    mon.attach_reader(lambda name: {"producer_heartbeat_time": 500, "device_type": 0x20192}[name])
    threading.Timer(0.4, _hb, (tx, 0x05)).start()  # first heartbeat 0.4 s after start
    t0 = time.monotonic()
    assert mon.state == "OPERATIONAL"
    assert time.monotonic() - t0 < 1.05 + 0.5  # waited at most 1.5 × 0.5 s + 0.3 s (+ slack)
    mon.close()


@pytest.mark.unit
def test_without_heartbeat_sdo_answer_means_pre_operational_and_tpdos_operational(vbus):
    net, tx = vbus
    mon = HeartbeatMonitor(net, 1)
    reads = []

    def read(name):
        reads.append(name)
        if name == "producer_heartbeat_time":
            return 0  # heartbeat off: no wait
        raise SdoAbort(0x06020000, 0x1000, 0, name)  # an abort is still an answer

    mon.attach_reader(read)
    t0 = time.monotonic()
    assert mon.state == "PRE-OPERATIONAL"
    assert time.monotonic() - t0 < 2.0 and reads == ["producer_heartbeat_time", "device_type"]
    # TPDOs flow only in OPERATIONAL (CiA 301 §7.3.2.2)
    mon2 = HeartbeatMonitor(net, 1)
    mon2.attach_reader(read)
    stop = threading.Event()

    def tpdos():
        while not stop.is_set():
            tx.send(can.Message(arbitration_id=0x281, data=bytes(8), is_extended_id=False))
            time.sleep(0.01)

    t = threading.Thread(target=tpdos, daemon=True)
    t.start()
    try:
        assert mon2.state == "OPERATIONAL"
    finally:
        stop.set()
        t.join(2)
    mon.close()
    mon2.close()


@pytest.mark.unit
def test_silent_node_is_offline_within_bounded_time(vbus):
    net, _ = vbus
    mon = HeartbeatMonitor(net, 1)

    def read(name):
        raise DriveTimeout("no answer")

    mon.attach_reader(read)
    t0 = time.monotonic()
    assert mon.state == "OFFLINE"
    assert time.monotonic() - t0 < 3.5  # DEFAULT_PERIOD window (1.8 s) + slack
    mon.close()


@pytest.mark.unit
def test_heartbeat_gap_tolerated_up_to_period_plus_one_second(vbus):
    net, tx = vbus
    mon = HeartbeatMonitor(net, 1)
    mon.producer_time = 0.1
    for _ in range(3):
        _hb(tx, 0x7F)
        time.sleep(0.1)
    deadline = time.monotonic() + 2
    while mon.count < 3 and time.monotonic() < deadline:
        time.sleep(0.01)
    last = mon.last_time
    assert mon.stale_after() == pytest.approx(1.1, abs=0.05)
    # a 0.6 s gap (a busy host) is not "OFFLINE"
    while time.monotonic() < last + 0.6:
        time.sleep(0.02)
    assert mon.state == "PRE-OPERATIONAL"
    # heartbeats stopped for good: OFFLINE after the limit
    while time.monotonic() < last + mon.stale_after() + 0.05:
        time.sleep(0.02)
    assert mon.state == "OFFLINE"
    mon.close()
