"""The ``virtual-drive run`` process across processes over the loopback hub: CANopen master
in this process (canopen over python-can socketcand), drive in a child process. Store and kill
-9, corrupt parameter files, atomic writes, bus errors, clean SIGTERM."""

from __future__ import annotations

import json
import os
import random
import re
import signal
import subprocess
import sys
import time

import can
import canopen
import numpy as np
import pytest
from conftest import RunQueueProbe, min_rate

from firmware_protocol import load_od
from virtual_drive.node import spawn_virtual_drive, storage

pytestmark = pytest.mark.timeout(90)

SAVE = 0x65766173
LOAD = 0x64616F6C


class HubProcess:
    """``virtual-drive hub --port 0`` in its own process (as on a bench: hub, drive and master
    in three processes, so none steals the others' interpreter time)."""

    def __init__(self) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "virtual_drive.cli", "hub", "--port", "0"],
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
        )
        line = self.proc.stdout.readline()
        m = re.search(r"port=(\d+)", line)
        assert m, line
        self.port = int(m.group(1))

    def join_kwargs(self) -> dict:
        return dict(
            interface="socketcand", host="127.0.0.1", port=self.port, channel="vcan0",
            tcp_tune=True,
        )  # fmt: skip

    def stop(self) -> None:
        self.proc.send_signal(signal.SIGTERM)
        self.proc.wait(10)


@pytest.fixture(scope="module")
def hub():
    h = HubProcess()
    yield h
    h.stop()


@pytest.fixture
def master(hub):
    bus = can.Bus(**hub.join_kwargs())
    net = canopen.Network(bus)
    net.connect()
    node = canopen.RemoteNode(1, load_od().canopen_od(1))
    net.add_node(node)
    node.sdo.RESPONSE_TIMEOUT = 1.0
    yield net, node
    net.disconnect()


def test_402_and_trace_block_upload_across_processes(hub, master):
    net, node = master
    with spawn_virtual_drive(port=hub.port) as proc:
        assert "ready" in proc.ready_line
        node.nmt.send_command(0x01)
        node.sdo[0x6060].raw = -1
        for cw in (0x06, 0x07, 0x0F):
            node.sdo[0x6040].raw = cw
        assert node.sdo[0x6041].raw & 0x6F == 0x27
        node.sdo[0x2030][1].raw = 15.0
        time.sleep(0.05)
        # capture the 15 -> 20 A step: 2 channels, 1000 samples, 100 before the step
        tc = node.sdo[0x2100]
        tc[4].raw = 0
        tc[3].raw = 1000
        tc[4].raw = 100
        tc[8].raw = 2  # setpoint step
        for attempt in range(1, 5):
            tc[9].raw = 1  # arm
            # a step is a trigger once the 100 pre-trigger samples (2 ms) are in; on a busy
            # host the drive may not have run for longer than that: step again if so
            time.sleep(0.1 * attempt)
            node.sdo[0x2030][1].raw = 20.0
            deadline = time.monotonic() + 3
            while tc[10].raw != 3 and time.monotonic() < deadline:
                time.sleep(0.01)
            if tc[10].raw == 3:
                break
            tc[9].raw = 0  # stop
            node.sdo[0x2030][1].raw = 15.0
        assert tc[10].raw == 3
        with node.sdo.open(0x2102, 0, "rb", block_transfer=True) as f:
            data = f.read()
        trace = np.frombuffer(data, "<f4").reshape(-1, 2)
        assert trace.shape == (1000, 2)
        assert tc[11].raw == 100
        assert np.all(trace[:100, 1] == 15.0) and np.all(trace[100:, 1] == 20.0)
        assert abs(trace[-1, 0] - 20.0) < 1.0
        # live TPDO2 stream at 1 kHz over the emulated 1 Mbit/s bus
        got = []
        net.subscribe(0x281, lambda cid, d, ts: got.append(time.monotonic()))
        probe = RunQueueProbe(proc.pid)  # what the kernel gave the drive meanwhile
        time.sleep(1.0)
        probe.stop()
        net.unsubscribe(0x281)
        rate = len(got) / (got[-1] - got[0]) if len(got) > 1 else 0
        assert min_rate(1000.0, probe.wait) < rate < 1150, (rate, probe)
        assert proc.stop() == 0  # SIGTERM: clean exit


def test_store_kill9_restart_and_restore_defaults(hub, master, tmp_path):
    _net, node = master
    store = tmp_path / "params.json"
    proc = spawn_virtual_drive(port=hub.port, store=store)
    try:
        node.sdo[0x2010][4].raw = 0.33  # current_controller.k_p
        node.sdo[0x2020][3].raw = 80.0  # speed_controller.current_limit
        node.sdo[0x1017].raw = 250
        node.sdo[0x1010][1].raw = SAVE
        node.sdo[0x2010][4].raw = 0.44  # changed after the save: not stored
    finally:
        assert proc.kill() == -signal.SIGKILL
    proc = spawn_virtual_drive(port=hub.port, store=store)
    try:
        assert node.sdo[0x2010][4].raw == pytest.approx(0.33)
        assert node.sdo[0x2020][3].raw == pytest.approx(80.0)
        assert node.sdo[0x1017].raw == 250
        node.sdo[0x1011][1].raw = LOAD  # restore defaults: active after reset
        assert node.sdo[0x2010][4].raw == pytest.approx(0.33)
        node.nmt.send_command(0x81)

        def k_p_is_default() -> bool:  # after the reset, however long a busy host takes
            try:
                return node.sdo[0x2010][4].raw == pytest.approx(0.4647)
            except (canopen.SdoAbortedError, canopen.SdoCommunicationError):
                return False  # resetting

        deadline = time.monotonic() + 15
        while not k_p_is_default() and time.monotonic() < deadline:
            time.sleep(0.05)
        assert node.sdo[0x2010][4].raw == pytest.approx(0.4647)
        assert node.sdo[0x1017].raw == 100
    finally:
        proc.stop()


def test_corrupt_store_reported_and_defaults_used(hub, master, tmp_path):
    _net, node = master
    store = tmp_path / "params.json"
    storage.save(store, {(0x2010, 4): np.float32(0.25).tobytes()})
    doc = json.loads(store.read_text())
    doc["params"]["2010:04"] = np.float32(0.5).tobytes().hex()  # checksum no longer matches
    store.write_text(json.dumps(doc))
    proc = spawn_virtual_drive(port=hub.port, store=store)
    try:
        assert node.sdo[0x2010][4].raw == pytest.approx(0.4647)
    finally:
        proc.stop()
    assert "checksum" in proc.stderr_tail
    store.write_bytes(b'{"format": "bldc-bench-drive-par')  # torn file
    proc = spawn_virtual_drive(port=hub.port, store=store)
    try:
        assert node.sdo[0x2010][4].raw == pytest.approx(0.4647)
    finally:
        proc.stop()
    assert "defaults used" in proc.stderr_tail


_SAVER = """
import importlib.util, sys
spec = importlib.util.spec_from_file_location("storage", sys.argv[2])  # stdlib-only module
storage = importlib.util.module_from_spec(spec)
spec.loader.exec_module(storage)
path = sys.argv[1]
a = {(0x2010, 4): bytes(4000 * [1])}
b = {(0x2010, 4): bytes(4000 * [2]), (0x2020, 1): bytes(4)}
print("go", flush=True)
while True:
    storage.save(path, a)
    storage.save(path, b)
"""


def test_store_is_atomic_under_kill9(tmp_path):
    path = tmp_path / "params.json"
    a = {(0x2010, 4): bytes(4000 * [1])}
    b = {(0x2010, 4): bytes(4000 * [2]), (0x2020, 1): bytes(4)}
    rng = random.Random(1)
    for _ in range(4):
        proc = subprocess.Popen(
            [sys.executable, "-c", _SAVER, str(path), storage.__file__],
            stdout=subprocess.PIPE,
            text=True,
        )
        assert proc.stdout.readline().strip() == "go"
        deadline = time.monotonic() + 30  # a busy host may not have run the first save yet
        while not path.exists() and time.monotonic() < deadline:
            time.sleep(0.01)
        time.sleep(rng.uniform(0.02, 0.2))
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        assert storage.load(path) in (a, b)
    leftovers = [p for p in tmp_path.iterdir() if p.name != "params.json"]
    assert len(leftovers) <= 4  # at most one temp file per kill, never the real file torn


def test_bus_errors_exit_non_zero_with_one_line():
    r = subprocess.run(
        [sys.executable, "-m", "virtual_drive.cli", "--interface", "socketcand",
         "--host", "127.0.0.1", "--port", "1", "--channel", "vcan0"],
        capture_output=True, text=True, timeout=30,
    )  # fmt: skip
    assert r.returncode == 1
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("virtual-drive: error: cannot open the CAN bus")
    r = subprocess.run(
        [sys.executable, "-m", "virtual_drive.cli", "run", "--interface", "nosuchbus"],
        capture_output=True, text=True, timeout=30,
    )  # fmt: skip
    assert r.returncode == 1 and "nosuchbus" in r.stderr


def test_bare_command_with_own_hub_and_sigint():
    proc = subprocess.Popen(
        [sys.executable, "-m", "virtual_drive.cli", "--hub", "--hub-port", "0"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        line = proc.stdout.readline()
        assert "ready" in line, line
        port = int(re.search(r"port=(\d+)", line.split("hub:")[1]).group(1))
        bus = can.Bus(interface="socketcand", host="127.0.0.1", port=port, channel="vcan0")
        net = canopen.Network(bus)
        net.connect()
        try:
            node = canopen.RemoteNode(1, load_od().canopen_od(1))
            net.add_node(node)
            node.sdo.RESPONSE_TIMEOUT = 1.0
            assert node.sdo[0x6041].raw & 0x4F == 0x40  # SWITCH ON DISABLED
        finally:
            net.disconnect()
        proc.send_signal(signal.SIGINT)
        assert proc.wait(15) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_bus_from_python_can_environment(hub):
    """No bus option on the command line: python-can's CAN_* environment chooses the bus."""
    env = {
        **os.environ,
        "CAN_INTERFACE": "socketcand",
        "CAN_CHANNEL": "vcan0",
        "CAN_CONFIG": json.dumps({"host": "127.0.0.1", "port": hub.port}),
    }
    proc = subprocess.Popen(
        [sys.executable, "-m", "virtual_drive.cli", "run", "--node-id", "5"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
    )  # fmt: skip
    try:
        line = proc.stdout.readline()
        assert "node 5 ready" in line and "socketcand" in line, line
        bus = can.Bus(**hub.join_kwargs())
        net = canopen.Network(bus)
        net.connect()
        try:
            node = canopen.RemoteNode(5, load_od(node_id=5).canopen_od(5))
            net.add_node(node)
            node.sdo.RESPONSE_TIMEOUT = 1.0
            assert node.sdo[0x1018][2].raw == 0x5048  # identity.product_code
        finally:
            net.disconnect()
    finally:
        proc.send_signal(signal.SIGTERM)
        # communicate() drains both pipes (wait() with PIPEs deadlocks once the child has
        # written a pipe's worth of log lines); the drive's stderr explains a slow exit
        try:
            _out, err = proc.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            proc.kill()
            _out, err = proc.communicate()
            raise AssertionError(f"no exit 30 s after SIGTERM; stderr: {err[-3000:]}") from None
        assert proc.returncode == 0, err[-3000:]
    env["CAN_CONFIG"] = json.dumps({"host": "127.0.0.1", "port": 1})
    r = subprocess.run(
        [sys.executable, "-m", "virtual_drive.cli", "run"],
        capture_output=True, text=True, timeout=30, env=env,
    )  # fmt: skip
    assert r.returncode == 1 and len(r.stderr.strip().splitlines()) == 1, r.stderr


@pytest.mark.parametrize("nodes", [None, "1-2"])
def test_drive_exits_when_the_hub_goes_away(nodes):
    """A lost bus ends the process with one line (no orphan spinning on a dead socket), also
    with several nodes on one shared connection (and no traceback per failed write)."""
    hub = HubProcess()
    proc = spawn_virtual_drive(port=hub.port, nodes=nodes)
    try:
        hub.stop()
        assert proc.proc.wait(10) == 1
        proc.stop()  # stderr read to the end
        assert "CAN bus lost" in proc.stderr_tail
        assert "Traceback" not in proc.stderr_tail, proc.stderr_tail
    finally:
        if proc.proc.poll() is None:
            proc.kill()


def test_drive_exits_when_its_parent_is_killed(hub):
    code = (
        "import sys, time\n"
        "from virtual_drive.node import spawn_virtual_drive\n"
        f"p = spawn_virtual_drive(port={hub.port})\n"
        "print(p.pid, flush=True)\n"
        "time.sleep(60)\n"
    )
    parent = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    child = int(parent.stdout.readline())
    os.kill(parent.pid, signal.SIGKILL)
    parent.wait()
    deadline = time.monotonic() + 30  # it checks every 0.2 s; exiting is slow on a busy host
    while time.monotonic() < deadline:
        try:
            os.kill(child, 0)
        except ProcessLookupError:
            return
        time.sleep(0.1)
    os.kill(child, signal.SIGKILL)
    pytest.fail("the drive outlived its killed parent")


def test_nodes_1_to_3_in_one_process(hub, tmp_path):
    """``--nodes 1-3``: three full CANopen nodes in one process, each with its own OD state and
    parameter file; bad node lists fail with one line."""
    store = tmp_path / "params.json"
    with spawn_virtual_drive(port=hub.port, nodes="1-3", store=store) as proc:
        assert "nodes 1,2,3 ready" in proc.ready_line, proc.ready_line
        bus = can.Bus(**hub.join_kwargs())
        net = canopen.Network(bus)
        net.connect()
        try:
            nodes = {}
            for nid in (1, 2, 3):
                node = canopen.RemoteNode(nid, load_od(node_id=nid).canopen_od(nid))
                net.add_node(node)
                node.sdo.RESPONSE_TIMEOUT = 2.0
                nodes[nid] = node
            for nid, node in nodes.items():
                assert node.sdo[0x1018][2].raw == 0x5048  # identity.product_code
                assert node.sdo[0x1200][2].raw == 0x580 + nid  # its own SDO server COB-ID
            nodes[2].sdo[0x6060].raw = 4  # profile torque on node 2 only
            assert [nodes[n].sdo[0x6060].raw for n in (1, 2, 3)] == [3, 4, 3]
            nodes[2].sdo[0x1010][1].raw = SAVE
            assert (tmp_path / "params-node2.json").exists()
            assert not (tmp_path / "params-node1.json").exists()
            # every node produces its heartbeat (0x700 + node-ID)
            seen: set[int] = set()

            class Ids(can.Listener):
                def on_message_received(self, msg: can.Message) -> None:
                    seen.add(msg.arbitration_id)

            net.notifier.add_listener(Ids())
            end = time.monotonic() + 10
            while not {0x701, 0x702, 0x703} <= seen and time.monotonic() < end:
                time.sleep(0.1)
            assert {0x701, 0x702, 0x703} <= seen
        finally:
            net.disconnect()
    for bad in (["--nodes", "0-3"], ["--nodes", "1-2", "--node-id", "3"]):
        r = subprocess.run(
            [sys.executable, "-m", "virtual_drive.cli", "run", "--hub", *bad],
            capture_output=True, text=True, timeout=30,
        )  # fmt: skip
        assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
