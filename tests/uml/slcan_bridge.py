"""Two virtual drives on vcan0 inside User-Mode Linux, reachable from the host through a serial
line speaking slcan (run INSIDE UML by tests/test_socketcan_dashboard.py).

The route (no network, no listening socket anywhere)::

    host: drive-dashboard --interface slcan --channel /dev/pts/N   (python-can's slcan client)
      │  pty pair made by the test; UML holds the other end: ``ssl1=fd:M`` (UML's ttyS1)
    UML:  /dev/ttyS1 ── python-can's slcan interface ⇄ python-can's socketcan on vcan0
          (one relay process: two python-can buses joined by ``can.RedirectReader``)
          vcan0: ``virtual-drive run --interface socketcan --channel vcan0 --nodes 1,2``
                 and a raw python-can socket writing every frame to a candump log (the truth)

slcan's frame lines (``t1238AABB...\\r``) read the same in both directions, so python-can's
slcan client on each end of the line is a complete link; the commands the host's client sends
(``O``, ``C``) are ignored by the one inside, as the inside's ``O`` is by the host's.

The kernel's own slcan line discipline (slcan.ko attached to ttyS1 by ``TIOCSETD``, routed to
vcan0 by can-gw configured over netlink) was tried first: the host's frames arrive on its
netdev, but it sends one frame to the host per frame the host sends (16 of 32 in 8 s with the
host sending every 0.5 s, then ENOBUFS): slcan stops its queue after each frame until the tty's
write wake-up, and UML's serial line gives that only from its interrupt (input or a write that
did not complete at once), never after a write that completed.

Steps: start the relay, the recorder and the drives,
set the drives' TPDO event timers to the lane's (``BENCH_TPDO_EVENT_TIMERS_MS``: UML moves about
800 frames/s, the defaults are 2,200 per drive) with canopen's SDO client, then write
``$SLCAN_OUT/ready`` and wait for ``$SLCAN_OUT/done`` (the host's session is over; at most
``SLCAN_HOLD_S``). The log is ``$SLCAN_OUT/vcan0.log`` (python-can's candump format).
"""

from __future__ import annotations

import os
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path

import can

TTY = "/dev/ttyS1"  # UML's serial line 1 (ssl1)
OUT = Path(os.environ["SLCAN_OUT"])
HOLD_S = float(os.environ.get("SLCAN_HOLD_S", "300"))
NODES = (1, 2)


def log(text: str) -> None:
    print(f"slcan-bridge {time.monotonic():.1f}: {text}", flush=True)


def relay() -> tuple[list[can.Notifier], can.BusABC, can.BusABC]:
    """ttyS1 (slcan) ⇄ vcan0: every frame read on one is sent on the other."""
    vcan = can.Bus(interface="socketcan", channel="vcan0")  # own frames not echoed: no loop
    line = can.Bus(interface="slcan", channel=TTY, sleep_after_open=0)
    notifiers = [
        can.Notifier(line, [can.RedirectReader(vcan)], timeout=0.2),
        can.Notifier(vcan, [can.RedirectReader(line)], timeout=0.2),
    ]
    return notifiers, line, vcan


def record(stop: threading.Event) -> None:
    """Every frame on vcan0 (a raw socket of its own) into ``vcan0.log``."""
    bus = can.Bus(interface="socketcan", channel="vcan0")
    writer = can.Logger(str(OUT / "vcan0.part.log"))
    try:
        while not stop.is_set():
            msg = bus.recv(0.2)
            if msg is not None:
                writer.on_message_received(msg)
    finally:
        writer.stop()
        bus.shutdown()
        (OUT / "vcan0.part.log").replace(OUT / "vcan0.log")


def lane_rates() -> None:
    """TPDO1..4 event timers (0x1800..0x1803 sub 5) of both drives, by canopen's SDO client."""
    import canopen

    timers = [int(x) for x in os.environ["BENCH_TPDO_EVENT_TIMERS_MS"].split(",")]
    net = canopen.Network()
    net.connect(interface="socketcan", channel="vcan0")
    try:
        for n in NODES:
            node = net.add_node(n)
            node.sdo.RESPONSE_TIMEOUT = 5.0
            deadline = time.monotonic() + 120
            while True:
                try:
                    node.sdo.download(0x1800, 5, struct.pack("<H", timers[0]))
                    break
                except (canopen.SdoCommunicationError, canopen.SdoAbortedError):
                    if time.monotonic() > deadline:
                        raise
                    time.sleep(0.5)
            for k, ms in enumerate(timers[1:], start=1):
                node.sdo.download(0x1800 + k, 5, struct.pack("<H", ms))
    finally:
        net.disconnect()


def main() -> int:
    notifiers, line, vcan = relay()
    log("ttyS1 (slcan) relayed to and from vcan0")
    stop = threading.Event()
    recorder = threading.Thread(target=record, args=(stop,), name="vcan0-recorder")
    recorder.start()
    drives = subprocess.Popen(
        ["virtual-drive", "run", "--interface", "socketcan", "--channel", "vcan0",
         "--nodes", ",".join(map(str, NODES))],
    )  # fmt: skip
    try:
        lane_rates()
        log("drives 1 and 2 up on vcan0 (TPDO event timers set)")
        (OUT / "ready").write_text("ready\n")
        deadline = time.monotonic() + HOLD_S
        while not (OUT / "done").exists() and time.monotonic() < deadline:
            if drives.poll() is not None:
                log(f"virtual-drive exited with {drives.returncode}")
                return 1
            time.sleep(0.2)
        return 0 if (OUT / "done").exists() else 2
    finally:
        drives.terminate()
        try:
            drives.wait(30)
        except subprocess.TimeoutExpired:
            drives.kill()
        stop.set()
        recorder.join(30)
        for n in notifiers:
            n.stop(2.0)
        line.shutdown()
        vcan.shutdown()
        log("stopped")


if __name__ == "__main__":
    sys.exit(main())
