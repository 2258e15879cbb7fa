"""drive_link: a quick stop wins over "leave the drive as found" (drive_link.workflows.restore and
drive_link.link._stop_guard). Found enabled in speed mode at 1000 rpm; inside ``leave_as_found`` an
experiment switches to current mode and runs; another thread sends a quick stop. Then the
experiment's own enable is refused, and the restore puts back the mode and setpoints but leaves
the drive stopped. The truth is the drive's statusword read over SDO and decoded with the
CiA 402-2 table here; the user's own Enable afterwards works."""

from __future__ import annotations

import threading
import time

import pytest

from drive_link import Drive
from drive_link.errors import StateError
from drive_link.workflows.restore import leave_as_found, switch_mode

pytestmark = pytest.mark.timeout(120)


def state(d: Drive) -> str:
    sw = int(d.read("statusword"))
    if sw & 0x4F == 0x40:
        return "SWITCH ON DISABLED"
    return {0x27: "OPERATION ENABLED", 0x07: "QUICK STOP ACTIVE", 0x23: "SWITCHED ON",
            0x21: "READY TO SWITCH ON"}.get(sw & 0x6F, hex(sw))


def test_quick_stop_from_another_thread_wins_over_the_restore(hub_drive):
    with Drive.connect(host="127.0.0.1", port=hub_drive.port, node_id=1) as d:
        d.nmt("start")
        d.set_mode("speed")
        d.set_speed(1000)
        d.enable(timeout=3.0)
        deadline = time.monotonic() + 30
        while abs(float(d.read("measurements.speed")) - 1000) > 50:
            assert time.monotonic() < deadline, "never reached 1000 rpm"
            time.sleep(0.1)
        refused: list[str] = []
        with pytest.raises(RuntimeError, match="stopped by the user"):
            with leave_as_found(d):
                switch_mode(d, "current")
                d.set_current(5.0)
                assert state(d) == "OPERATION ENABLED"
                stopper = threading.Thread(target=d.quick_stop)
                stopper.start()
                stopper.join(timeout=10)
                assert state(d) in ("QUICK STOP ACTIVE", "SWITCH ON DISABLED")
                try:
                    d.enable(timeout=2.0)  # the experiment would carry on: refused
                except StateError as exc:
                    refused.append(str(exc))
                raise RuntimeError("stopped by the user")
        assert refused and "quick stop" in refused[0]
        time.sleep(0.3)
        assert state(d) != "OPERATION ENABLED"
        assert d.mode == "speed" and int(d.read("target_velocity")) == 1000
        d.enable(timeout=3.0)  # the user's own Enable is not refused
        assert state(d) == "OPERATION ENABLED"
        d.disable()
