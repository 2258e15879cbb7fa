"""Configuration of one bench session (what `drive-dashboard` was asked to do)."""

from __future__ import annotations

import ipaddress
from dataclasses import dataclass, field
from typing import Any

__all__ = ["GUI_RATE_HZ", "GUI_RATE_RANGE_HZ", "LOOPBACK_HOSTS", "BenchConfig", "is_loopback"]

LOOPBACK_HOSTS = ("127.0.0.1", "localhost", "::1")


def is_loopback(host: str) -> bool:
    """True if ``host`` names an address on this machine only."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


#: Plot refreshes per second in each browser by default (``--plot-rate``): smooth to the eye.
GUI_RATE_HZ = 24.0
#: ``--plot-rate`` accepted, Hz: below 1 Hz a plot is no longer live; above 60 Hz no screen shows
#: more, and every refresh costs the bench and each browser CPU.
GUI_RATE_RANGE_HZ = (1.0, 60.0)


@dataclass
class BenchConfig:
    """Everything the dashboard needs to open its bench.

    host/api_port: FastAPI bind (127.0.0.1 unless ``allow_remote``); gui_port: viser bind
    (0 = any free port).
    interface/channel/bitrate/node_id: the python-can bus and CANopen node when not ``virtual``.
    speed_factor: virtual drive only, simulated seconds per wall-clock second.
    virtual_in_process: run the virtual drive in this process (tests that want the drive
    object); by default it runs as ``virtual-drive run`` in a child process, so that its TPDOs
    keep their rate while the dashboard is busy.
    hub_port: TCP port of the loopback hub on 127.0.0.1 (0 = any free port).
    join_hub: TCP port of an already running loopback hub to join (instead of interface).
    token: access token; required (and checked on every request) when ``allow_remote``.
    scene_3d: the 3D rotor view exists (each browser then has a "3D rotor" checkbox).
    gui_rate_hz: plot refreshes per second in each browser (``--plot-rate``, 1..60 Hz).
    scene_3d_shown: the checkbox starts checked. Off by default: a turning rotor keeps the
    page re-rendering, 50–130 % of a core in a browser with software WebGL (benchmarks/
    bench_dashboard.py --rotor), while hidden it costs nothing.
    """

    host: str = "127.0.0.1"
    api_port: int = 8000
    gui_port: int = 8080
    virtual: bool = False
    interface: str | None = None
    channel: str | None = None
    bitrate: int = 1_000_000
    #: python-can's other bus options for ``interface`` (fd, data_bitrate, timing, --bus-kwargs)
    bus_options: dict[str, Any] = field(default_factory=dict)
    node_id: int = 1
    #: with ``virtual``: node-IDs of the drives started on the hub (empty: ``node_id`` alone)
    nodes: tuple[int, ...] = ()
    speed_factor: float = 1.0
    virtual_in_process: bool = False
    hub_port: int = 0
    join_hub: int | None = None
    allow_remote: bool = False
    token: str | None = None
    live_window_s: float = 4.0
    gui_rate_hz: float = GUI_RATE_HZ  # plot refreshes/s (≤ 0.5 MB/s per tab); a step pushes at once
    scene_3d: bool = True
    scene_3d_shown: bool = False
    stream_rate_hz: float = 20.0
    extra_origins: list[str] = field(default_factory=list)

    def validate(self) -> None:
        """Raise ValueError (one line) when the combination is unsafe or incomplete."""
        if not is_loopback(self.host) and not self.allow_remote:
            raise ValueError(
                f"refusing to bind {self.host}: remote binding needs --allow-remote and --token"
            )
        if self.allow_remote and not self.token:
            raise ValueError("--allow-remote needs an access token (--token)")
        if self.token is not None and len(self.token) < 12:
            raise ValueError("--token must be at least 12 characters")
        if not 1 <= self.node_id <= 127:
            raise ValueError(f"node id {self.node_id} is outside 1..127")
        if self.speed_factor <= 0:
            raise ValueError("--speed-factor must be > 0")
        lo, hi = GUI_RATE_RANGE_HZ
        if not lo <= self.gui_rate_hz <= hi:  # (also refuses nan)
            raise ValueError(f"--plot-rate must be {lo:g}..{hi:g} Hz, got {self.gui_rate_hz:g}")
        if self.nodes and not self.virtual:
            raise ValueError("--nodes starts virtual drives: it needs --virtual")
        if self.nodes and self.node_id not in self.nodes:
            raise ValueError(f"--node {self.node_id} is not one of --nodes {self.nodes}")
        if self.bus_options and (self.virtual or self.join_hub is not None):
            raise ValueError(
                f"--{next(iter(self.bus_options)).replace('_', '-')} applies to an --interface "
                "bus, not to the loopback hub (--virtual, --join-hub)"
            )
        if not self.virtual and self.interface is None and self.join_hub is None:
            raise ValueError(
                "give --virtual, --join-hub PORT, or --interface (and --channel) of the CAN bus"
            )
