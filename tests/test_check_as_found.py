"""`drive-link check` against the README's own virtual drive (issue 23): the drive started as the
README starts it (``virtual-drive --hub --hub-port N``, no ``--store``) passes, its
``store_restore`` reports "not applicable" instead of failing, and the run leaves no error code,
error register, error history or communication setting behind.

Oracle: canopen's own SDO client (an independent master, not drive_link's) reads 0x603F, 0x1001,
every sub-index of 0x1003 and every communication object 0x1005–0x1A03 the EDS lists, before and
after the run of the installed ``drive-link`` console script.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import can
import canopen
import pytest

from firmware_protocol.od import EDS_PATH

pytestmark = pytest.mark.timeout(240)

BIN = Path(sys.executable).parent
ENV = {k: v for k, v in os.environ.items() if not k.startswith(("DRIVE_LINK_", "CAN_"))}
NODE = 1


@pytest.fixture(scope="module")
def readme_drive():
    """``virtual-drive --hub --hub-port 0`` as the README starts it (no parameter store);
    yields the hub's port."""
    p = subprocess.Popen(
        [str(BIN / "virtual-drive"), "--hub", "--hub-port", "0", "--log-level", "ERROR"],
        stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, env=ENV,
    )  # fmt: skip
    try:
        line = p.stdout.readline()
        m = re.search(r"ready on .*127\.0\.0\.1:(\d+)", line)
        assert m, line
        yield int(m[1])
    finally:
        p.terminate()
        try:
            p.wait(10)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()


def _addresses(node: canopen.RemoteNode) -> list[tuple[int, int]]:
    """0x603F, 0x1001, every sub-index of 0x1003 and of each communication object 0x1005–0x1A03
    in the EDS (canopen's parse of it)."""
    out = [(0x603F, 0), (0x1001, 0)]
    for obj in node.object_dictionary.values():
        if obj.index == 0x1003 or 0x1005 <= obj.index <= 0x1A03:
            if isinstance(obj, canopen.objectdictionary.Variable):
                out.append((obj.index, 0))
            else:
                out += [(obj.index, sub) for sub in obj.subindices]
    return sorted(set(out))


def _snapshot(port: int) -> dict[str, str]:
    """(index, sub) → raw value in hex, or the abort, read by canopen's SdoClient."""
    bus = can.Bus(interface="socketcand", host="127.0.0.1", port=port, channel="vcan0")
    net = canopen.Network(bus).connect()  # canopen's master on the hub's bus
    try:
        node = net.add_node(NODE, str(EDS_PATH))
        node.sdo.RESPONSE_TIMEOUT = 2.0
        out = {}
        for index, sub in _addresses(node):
            try:
                out[f"0x{index:04X}:{sub}"] = node.sdo.upload(index, sub).hex()
            except canopen.SdoAbortedError as exc:
                out[f"0x{index:04X}:{sub}"] = f"abort 0x{exc.code:08X}"
        return out
    finally:
        net.disconnect()


def test_check_passes_on_the_readme_drive_and_leaves_it_as_found(readme_drive):
    before = _snapshot(readme_drive)
    assert before["0x603F:0"] == "0000" and before["0x1003:0"] == "00", before
    assert len(before) > 40  # the communication area was read
    t0 = time.monotonic()
    p = subprocess.run(
        [str(BIN / "drive-link"), "check", "--json", "--host", "127.0.0.1",
         "--port", str(readme_drive)],
        capture_output=True, text=True, env=ENV, timeout=200,
    )  # fmt: skip
    took = time.monotonic() - t0
    results = {r["name"]: r for r in json.loads(p.stdout)}
    store = results["store_restore"]
    assert store["verdict"] == "not applicable" and store["ok"], store
    assert "the drive has no parameter store (start `virtual-drive` with `--store FILE`)" in (
        store["detail"]
    )
    failed = {n: r["detail"] for n, r in results.items() if not r["ok"]}
    assert p.returncode == 0 and not failed, (p.returncode, failed, p.stderr)
    after = _snapshot(readme_drive)
    changed = {k: (before[k], after.get(k)) for k in before if after.get(k) != before[k]}
    assert not changed, (changed, f"check took {took:.1f} s")


# --------------------------------------------------------------------------- a real failure fails
@pytest.fixture
def stored_drive(tmp_path):
    """An in-process virtual drive (python-can virtual bus) started on a parameter file that
    holds a stored set (0x2060 store_status "ok"); yields its channel."""
    from drive_link import Drive
    from virtual_drive.node import VirtualDrive

    path = tmp_path / "store.json"
    ch = f"store-{os.getpid()}-{time.monotonic_ns()}"
    for first in (True, False):
        bus = can.Bus(interface="virtual", channel=ch)
        vd = VirtualDrive(bus, node_id=NODE, store_path=path).start()
        if not first:
            break
        with Drive.connect(interface="virtual", channel=ch, node_id=NODE, heartbeat_ms=None) as d:
            d.store()
        vd.stop()
        bus.shutdown()
    try:
        yield ch
    finally:
        vd.stop()
        bus.shutdown()


@pytest.mark.parametrize("code", [0x08000020, 0x08000000])
def test_store_restore_fails_on_a_drive_with_a_store_that_refuses_to_save(
    stored_drive, monkeypatch, capsys, code
):
    """A drive that has stored parameters (store_status ok) and refuses "save" fails the item,
    whatever the abort code: only a drive without a store is "not applicable"."""
    from canopen.sdo.exceptions import SdoAbortedError

    from drive_link import cli
    from virtual_drive.node.parameters import ParameterSet

    def refuse(self):
        raise SdoAbortedError(code)

    monkeypatch.setattr(ParameterSet, "save", refuse)  # the defect
    rc = cli.main(["check", "--interface", "virtual", "--channel", stored_drive,
                   "--only", "store_restore", "--json"])  # fmt: skip
    (r,) = json.loads(capsys.readouterr().out)
    assert rc == 1 and r["verdict"] == "fail" and f"0x{code:08X}" in r["detail"], r
