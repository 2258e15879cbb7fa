"""64 KiB trace uploads with drive_link through the loopback hub with 1 % and 5 % frame loss and
a USB-adapter-like latency of 2 ms ± 1 ms per frame.

The hub runs as its own process (``virtual-drive hub --drop … --delay-ms 2 --jitter-ms 1``);
the drive runs in this process on its own socketcand connection, so its recorder buffer
(``drive.recorder.data_bytes()``, read in-process, not over CAN) is the truth every upload is
compared with, byte for byte, together with its CRC-16/CCITT from ``binascii.crc_hqx``.
"""

from __future__ import annotations

import binascii
import re
import signal
import subprocess
import sys

import can
import numpy as np
import pytest

from drive_link import Drive
from virtual_drive.node import VirtualDrive

pytestmark = pytest.mark.timeout(420)


class LossyHub:
    """``virtual-drive hub`` in a child process with loss and jitter."""

    def __init__(self, drop: float, seed: int) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "virtual_drive.cli", "hub", "--port", "0",
             "--drop", str(drop), "--delay-ms", "2", "--jitter-ms", "1", "--seed", str(seed)],
            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
        )  # fmt: skip
        line = self.proc.stdout.readline()
        m = re.search(r"port=(\d+)", line)
        assert m, line
        self.port = int(m.group(1))

    def stop(self) -> None:
        self.proc.send_signal(signal.SIGTERM)
        self.proc.wait(10)


@pytest.mark.parametrize("drop, uploads", [(0.01, 3), (0.05, 2)])
def test_trace_uploads_complete_and_exact_under_loss_and_jitter(drop, uploads):
    hub = LossyHub(drop, seed=int(drop * 1000))
    drive_bus = can.Bus(
        interface="socketcand", host="127.0.0.1", port=hub.port, channel="vcan0", tcp_tune=True
    )
    vd = VirtualDrive(drive_bus, node_id=1, speed=0.25).start()
    d = None
    try:
        d = Drive.connect(host="127.0.0.1", port=hub.port, node_id=1, heartbeat_ms=None)
        channels = ["V_dc", "i_p", "speed", "theta_e"]  # V_dc: non-zero data
        trace = d.trace.capture(channels, length=4096, trigger="immediate", timeout=60.0)
        truth = vd.recorder.data_bytes()
        assert len(truth) == 65536
        samples = np.frombuffer(truth, dtype="<f4").reshape(4096, 4)
        for i, name in enumerate(trace.signals):
            assert np.array_equal(trace.signals[name], samples[:, i])
        for _ in range(uploads - 1):
            raw = d.sdo_trace.upload_block(0x2102, 0, name="trace_data")
            assert raw == truth
            assert binascii.crc_hqx(raw, 0) == binascii.crc_hqx(truth, 0)
    finally:
        if d is not None:
            d.close()
        vd.stop()
        drive_bus.shutdown()
        hub.stop()
