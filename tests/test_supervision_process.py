"""The drive process dies (SIGKILL) and is started again behind the loopback hub: the session's
heartbeat consumer is back in the drive before the first user command reads it, and losing the
host heartbeat afterwards still makes the drive react (EMCY 0x8130)."""

from __future__ import annotations

import threading
import time

import pytest

from drive_link import Drive

pytestmark = pytest.mark.timeout(120)

NODE = 3
HOST = 0x7F
CONSUMER_MS = 1000  # a busy host stalls the producer thread for 300 ms and more


def test_killed_and_restarted_drive_process_is_rearmed(tmp_path):
    from virtual_drive.hub import Hub
    from virtual_drive.node import spawn_virtual_drive

    store = tmp_path / "params.json"
    with Hub(port=0) as hub:
        proc = spawn_virtual_drive(port=hub.port, node_id=NODE, store=store)
        try:
            d = Drive.connect(host="127.0.0.1", port=hub.port, node_id=NODE, heartbeat_ms=50,
                              host_id=HOST, sdo_timeout=0.5)
            try:
                detected = threading.Event()
                events: list[dict] = []
                d.on_supervision(events.append)
                d.on_supervision(
                    lambda e: detected.set() if e["event"] == "reboot_detected" else None
                )
                d.configure_heartbeat_consumer(CONSUMER_MS)
                proc.kill()
                proc = spawn_virtual_drive(port=hub.port, node_id=NODE, store=store)
                assert detected.wait(10.0), "restart not noticed"
                # first user command after the boot-up was noticed
                entry = int(d.read("consumer_heartbeat_time.consumer_1"))
                assert entry == (HOST << 16) | CONSUMER_MS
                assert d.boots_seen == 1 and d.status()["supervision_rearmed_at"]
                n = len(d.emcy_history)
                d.stop_host_heartbeat()
                deadline = time.monotonic() + 10.0
                while time.monotonic() < deadline:
                    if any(e.code == 0x8130 for e in d.emcy_history[n:]):
                        break
                    time.sleep(0.05)
                assert any(e.code == 0x8130 for e in d.emcy_history[n:]), (
                    "consumer not armed",
                    hex(int(d.read("consumer_heartbeat_time.consumer_1"))),
                    d.state,
                    [e.code for e in d.emcy_history],
                    [(e["event"], e.get("reason"), e.get("written")) for e in events],
                )
            finally:
                d.close()
        finally:
            proc.stop()
