"""``drive-link lss`` when the drives' LSS answers come later than ``--lss-timeout`` (a busy
host, an adapter with latency): canopen's fast scan then gives up half-way and returns the same
``(False, None)`` as for an empty bus. The command must not report "no unconfigured drive" and
exit 0 while a drive is left without a node-ID: it asks "identify non-configured remote slave"
(CiA 305), scans again with a longer timeout, and configures the drive.

Bench: the loopback hub with a delivery delay of 15 ms per frame (each request and each answer:
a round trip of 30 ms and more), one ``virtual-drive run --unconfigured 1``, ``--lss-timeout
0.025``. Truth: canopen's own SDO client reads the identity serial number (0x1018:4) at the new
node-ID; before this fix the command printed "no unconfigured drive answered" and exited 0.
Answers later than every retry's timeout: one line on stderr, exit 1, and the drive is still
unconfigured (it answers "identify non-configured remote slave" afterwards).
"""

from __future__ import annotations

import contextlib
import io
import json
import subprocess
import sys
import time
from pathlib import Path

import canopen
import pytest

from drive_link import cli
from virtual_drive.hub import Hub

pytestmark = pytest.mark.timeout(180)

BIN = Path(sys.executable).parent
SERIAL = 0x77


def _bench(delay_s: float) -> tuple[Hub, subprocess.Popen]:
    """The hub with ``delay_s`` per frame and one unconfigured drive on it."""
    hub = Hub(port=0, delay_s=delay_s).start()
    proc = subprocess.Popen(
        [str(BIN / "virtual-drive"), "run", "-i", "socketcand", "--host", "127.0.0.1",
         "--port", str(hub.port), "--unconfigured", "1", "--serial-base", str(SERIAL)],
        stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
    )  # fmt: skip
    assert "1 unconfigured drive(s)" in proc.stdout.readline()
    return hub, proc


def test_lss_answers_later_than_every_retry_is_one_error_and_nothing_changed(capsys):
    """Round trip ≥ 0.4 s, ``--lss-timeout 0.01``: five scans (0.01 .. 0.16 s) all miss."""
    hub, proc = _bench(0.2)
    try:
        rc = cli.main(["lss", "--host", "127.0.0.1", "--port", str(hub.port),
                       "--lss-timeout", "0.01"])  # fmt: skip
        err = capsys.readouterr().err.strip().splitlines()
        assert rc == 1 and len(err) == 1, (rc, err)
        assert "an unconfigured drive answers" in err[0] and "raise --lss-timeout" in err[0]
        net = canopen.Network()
        net.connect(interface="socketcand", host="127.0.0.1", port=hub.port, channel="vcan0")
        try:
            seen = []
            net.subscribe(0x7E4, lambda cid, data, ts: seen.append(bytes(data)[0]))
            net.send_message(0x7E5, bytes([0x4C, 0, 0, 0, 0, 0, 0, 0]))
            time.sleep(1.5)
            assert 0x50 in seen  # still unconfigured (CiA 305: identify non-configured)
        finally:
            net.disconnect()
    finally:
        proc.terminate()
        proc.wait(10)
        hub.stop()


def test_lss_with_answers_later_than_the_timeout_still_configures_the_drive():
    hub, proc = _bench(0.015)
    try:
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            rc = cli.main(["lss", "--host", "127.0.0.1", "--port", str(hub.port),
                           "--first-id", "12", "--lss-timeout", "0.025", "--json"])  # fmt: skip
        assert rc == 0
        done = json.loads(out.getvalue())
        assert [(d["node_id"], d["serial"]) for d in done] == [(12, SERIAL)], done
        net = canopen.Network()
        net.connect(interface="socketcand", host="127.0.0.1", port=hub.port, channel="vcan0")
        try:
            node = net.add_node(12)
            node.sdo.RESPONSE_TIMEOUT = 2.0
            deadline = time.monotonic() + 10
            while True:
                try:
                    serial = node.sdo.upload(0x1018, 4)
                    break
                except canopen.SdoCommunicationError:
                    if time.monotonic() > deadline:
                        raise
            assert int.from_bytes(serial, "little") == SERIAL
        finally:
            net.disconnect()
    finally:
        proc.terminate()
        proc.wait(10)
        hub.stop()
