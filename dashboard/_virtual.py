"""Open the bench: a real bus and node, or (``--virtual``) the loopback hub plus a virtual drive.

The hub and the drive come from :func:`virtual_drive.launch.virtual_bench`: the virtual drive
runs as ``virtual-drive run`` in a child process (default: its TPDOs keep their rate while the
dashboard is busy; the child is stopped with SIGTERM, then SIGKILL, when the bench closes, also
on errors) or, with ``virtual_in_process``, in this process (``VirtualDrive`` on its own
socketcand connection to the hub); either way the dashboard reaches it only through the hub,
exactly like a real drive on a bus.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Iterator
from typing import TYPE_CHECKING

from dashboard._bench import Bench
from dashboard.config import BenchConfig

if TYPE_CHECKING:
    from drive_link import Drive

__all__ = ["open_bench"]


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
                **config.bus_options,
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
    """Start the hub and a virtual drive on it (:func:`virtual_drive.launch.virtual_bench`);
    yields the hub's TCP port on 127.0.0.1."""
    from virtual_drive.launch import virtual_bench

    with virtual_bench(
        nodes=tuple(getattr(config, "nodes", ())) or (config.node_id,),
        hub_port=config.hub_port,
        bitrate=config.bitrate,
        speed=config.speed_factor,
        drives_in_process=config.virtual_in_process,
    ) as bus:
        yield bus.port


def _wait_operational(drive: Drive, timeout: float = 2.0) -> None:
    deadline = time.monotonic() + timeout
    while drive.nmt_state != "OPERATIONAL":
        if time.monotonic() > deadline:
            raise RuntimeError(f"drive did not enter OPERATIONAL ({drive.nmt_state})")
        time.sleep(0.02)
