"""Open the bench: a real bus and node, or (``--virtual``) the loopback hub plus a virtual drive.

The virtual drive runs as ``virtual-drive run`` in a child process (default: its TPDOs keep
their rate while the dashboard is busy; the child is stopped with SIGTERM, then SIGKILL, when
the bench closes, also on errors) or, with ``virtual_in_process``, in this process
(``VirtualDrive`` on its own socketcand connection to the hub); either way the dashboard reaches
it only through the hub, exactly like a real drive on a bus.
"""

from __future__ import annotations

import contextlib
import tempfile
import time
from collections.abc import Iterator

from dashboard.bench import Bench
from dashboard.config import BenchConfig


@contextlib.contextmanager
def open_bench(config: BenchConfig) -> Iterator[Bench]:
    """The bench for ``config`` (closed on exit, with the hub and virtual drive if started)."""
    from drive_link import Drive

    with contextlib.ExitStack() as stack:
        if config.virtual:
            port = stack.enter_context(_virtual_bus(config))
            drive = Drive.connect(
                host="127.0.0.1", port=port, bitrate=config.bitrate, node_id=config.node_id
            )
            where = "in-process" if config.virtual_in_process else "subprocess"
            desc = f"loopback hub 127.0.0.1:{port} (virtual drive, {where})"
        elif config.join_hub is not None:
            drive = Drive.connect(
                host="127.0.0.1",
                port=config.join_hub,
                bitrate=config.bitrate,
                node_id=config.node_id,
            )
            desc = f"loopback hub 127.0.0.1:{config.join_hub}"
        else:
            drive = Drive.connect(
                interface=config.interface,
                channel=config.channel,
                bitrate=config.bitrate,
                node_id=config.node_id,
            )
            desc = f"{config.interface} {config.channel or ''}".strip()
        stack.callback(drive.close)
        if drive.nmt_state != "OPERATIONAL":
            drive.nmt("start")  # TPDOs (live values) flow in OPERATIONAL only
            _wait_operational(drive)
        bench = Bench(drive, description=desc, node_id=config.node_id, virtual=config.virtual)
        bench.hub_port = port if config.virtual else None
        stack.callback(bench.close)
        yield bench


@contextlib.contextmanager
def _virtual_bus(config: BenchConfig) -> Iterator[int]:
    """Start the hub and a virtual drive on it; yields the hub's TCP port on 127.0.0.1."""
    from virtual_drive.hub import Hub

    with contextlib.ExitStack() as stack:
        hub = Hub(port=config.hub_port, bitrate=config.bitrate)
        hub.start()
        stack.callback(hub.stop)
        if config.virtual_in_process:
            stack.enter_context(_drive_in_process(config, hub.port))
        else:
            stack.enter_context(_drive_process(config, hub.port))
        yield hub.port


@contextlib.contextmanager
def _drive_in_process(config: BenchConfig, port: int) -> Iterator[None]:
    import can

    from virtual_drive.node import VirtualDrive

    bus = can.Bus(
        interface="socketcand", host="127.0.0.1", port=port, channel="vcan0", tcp_tune=True
    )
    with tempfile.TemporaryDirectory(prefix="drive-dashboard-") as tmp:
        try:
            vd = VirtualDrive(
                bus, config.node_id, store_path=f"{tmp}/parameters.json", speed=config.speed_factor
            )
            vd.start()
            try:
                yield
            finally:
                vd.stop()
        finally:
            bus.shutdown()


@contextlib.contextmanager
def _drive_process(config: BenchConfig, port: int) -> Iterator[None]:
    from virtual_drive.node.process import spawn_virtual_drive

    with tempfile.TemporaryDirectory(prefix="drive-dashboard-") as tmp:
        proc = spawn_virtual_drive(
            port=port,
            node_id=config.node_id,
            store=f"{tmp}/parameters.json",
            speed=config.speed_factor,
        )
        try:
            yield
        finally:
            proc.stop()  # SIGTERM, then SIGKILL after 10 s


def _wait_operational(drive, timeout: float = 2.0) -> None:
    deadline = time.monotonic() + timeout
    while drive.nmt_state != "OPERATIONAL":
        if time.monotonic() > deadline:
            raise RuntimeError(f"drive did not enter OPERATIONAL ({drive.nmt_state})")
        time.sleep(0.02)
