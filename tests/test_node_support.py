"""Shared helpers of the tests/test_node_*.py files (no tests here).

A :class:`Bench` puts a :class:`virtual_drive.node.VirtualDrive` and a canopen master
(``canopen.RemoteNode`` with the drive's EDS) on one python-can ``virtual`` channel and logs
every frame the master side sees.
"""

from __future__ import annotations

import itertools
import os
import struct
import threading
import time

import can
import canopen
from canopen.sdo import SdoCommunicationError

from firmware_protocol import load_od
from virtual_drive.node import VirtualDrive

_counter = itertools.count()


class FrameLog(can.Listener):
    """Every received frame as (monotonic time, COB-ID, data)."""

    def __init__(self) -> None:
        self.frames: list[tuple[float, int, bytes]] = []
        self._cv = threading.Condition()

    def on_message_received(self, msg: can.Message) -> None:
        with self._cv:
            self.frames.append((time.monotonic(), msg.arbitration_id, bytes(msg.data)))
            self._cv.notify_all()

    def of(self, cob_id: int, since: float = 0.0) -> list[tuple[float, bytes]]:
        with self._cv:
            return [(t, d) for t, c, d in self.frames if c == cob_id and t >= since]

    def wait_for(self, cob_id: int, timeout: float = 2.0, since: float = 0.0, pred=None):
        """First frame on ``cob_id`` after ``since`` matching ``pred(data)``, or None."""
        deadline = time.monotonic() + timeout
        with self._cv:
            while True:
                for t, c, d in self.frames:
                    if c == cob_id and t >= since and (pred is None or pred(d)):
                        return t, d
                left = deadline - time.monotonic()
                if left <= 0:
                    return None
                self._cv.wait(left)


#: canopen's 0.3 s default is short for a shared 2-core machine under load: in a full run under
#: `stress-ng --cpu 4` (load 12) a write waited out 2 s twice. Only a lost answer waits this long.
SDO_TIMEOUT_S = 5.0


class Bench:
    """Drive + master on a private virtual channel."""

    def __init__(
        self,
        speed: float = 1.0,
        store_path=None,
        node_id: int = 1,
        start: bool = True,
        sdo2: bool = False,
    ) -> None:
        channel = f"node-test-{os.getpid()}-{next(_counter)}"
        self.channel = channel
        self.drive_bus = can.Bus(interface="virtual", channel=channel)
        self.bus = can.Bus(interface="virtual", channel=channel)
        self.log = FrameLog()
        self.net = canopen.Network(self.bus)
        self.net.listeners.append(self.log)
        self.net.connect()
        self.view = load_od(node_id=node_id)
        self.node = canopen.RemoteNode(node_id, self.view.canopen_od(node_id))
        if sdo2:  # second SDO channel 0x1201 (before add_node, see the field notes)
            self.sdo2 = self.node.add_sdo(0x680 + node_id, 0x6B0 + node_id)
        self.net.add_node(self.node)
        if sdo2:
            self.sdo2.network = self.net  # canopen leaves it unset (field notes)
            self.sdo2.RESPONSE_TIMEOUT = SDO_TIMEOUT_S
        self.node.sdo.RESPONSE_TIMEOUT = SDO_TIMEOUT_S
        self.node_id = node_id
        self.t_start = time.monotonic()
        self.drive = VirtualDrive(
            self.drive_bus, node_id=node_id, store_path=store_path, speed=speed
        )
        if start:
            self.drive.start()

    def close(self) -> None:
        self.drive.stop()
        self.net.disconnect()
        self.drive_bus.shutdown()

    # -- convenience ----------------------------------------------------------------------
    def sdo(self, name: str):
        """The master's SdoVariable for an OD name (``"current_controller.L_c"``)."""
        e = self.view.entry(name)
        obj = self.node.sdo[e.index]
        return obj if e.object_name == e.name else obj[e.subindex]

    def read(self, name: str):
        return self.sdo(name).raw

    def write(self, name: str, value) -> None:
        self.sdo(name).raw = value

    def nmt(self, command: int) -> None:
        self.net.send_message(0, bytes([command, self.node_id]))

    def wait(self, pred, timeout: float = 2.0, step: float = 0.005) -> bool:
        """Poll ``pred`` until true; an SDO timeout inside it (a stalled machine) counts as
        "not yet" until the deadline."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                if pred():
                    return True
            except SdoCommunicationError:
                pass
            time.sleep(step)
        return pred()

    def enable(self, mode: int) -> None:
        """Drive to OPERATION ENABLED in ``mode`` through the controlword."""
        self.write("modes_of_operation", mode)
        for cw in (0x06, 0x07, 0x0F):
            self.write("controlword", cw)
        assert self.read("statusword") & 0x6F == 0x27


def emcy_frames(log: FrameLog, node_id: int = 1, since: float = 0.0):
    """Decoded EMCY frames: list of (t, code, error_register)."""
    out = []
    for t, d in log.of(0x80 + node_id, since):
        code, reg = struct.unpack_from("<HB", d)
        out.append((t, code, reg))
    return out
