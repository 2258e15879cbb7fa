"""``virtual-drive run``: serve the virtual drive as a CANopen node until SIGINT/SIGTERM.

Bus selection follows python-can: options given on the command line are passed to
``can.Bus``; anything not given comes from python-can's configuration file and environment
(``can.util.load_config``), so ``virtual-drive run`` with no bus options uses the user's
python-can default. ``--hub`` starts a loopback hub in this process and joins it.

``--nodes 1-4`` serves several drives (node-IDs 1 to 4; also ``1,3,5`` or ``1-3,7``) from one
process: each is a full CANopen node with its own object dictionary, parameter file and bus
connection, and one pacing thread runs them all (:class:`virtual_drive.node.runner.Pacer`).

A socketcand bus (``--interface socketcand``, the loopback hub) is opened with the drive's own
lean client :class:`virtual_drive.node.hub_bus.HubBus` (same protocol as python-can's
``socketcand`` interface; the TPDOs of a tick go out in one write and frames no node here
listens to are dropped before they are parsed).

On start the process prints one line ``virtual-drive: node N ready on <bus>`` (``nodes 1,2,3,4
ready on <bus>`` with ``--nodes``) to stdout (tests and scripts wait for it); with ``--hub`` the
line also gives the hub's join line.
"""

from __future__ import annotations

import argparse
import logging
import os
import socket
import sys
import time
from pathlib import Path
from typing import Any, Protocol

import can
import can.cli

from virtual_drive.stop_signal import StopSignal

__all__ = [
    "BUS_GROUP_TITLE",
    "add_parser",
    "add_run_arguments",
    "bus_kwargs",
    "bus_lost",
    "open_bus",
    "parse_nodes",
    "run_command",
    "socketcand_defaults",
    "store_for",
]

logger = logging.getLogger("virtual_drive.run")

MAX_NODES = 16  #: drives one ``virtual-drive run --nodes`` process serves at most


def add_parser(
    subparsers: argparse._SubParsersAction[argparse.ArgumentParser],
) -> argparse.ArgumentParser:
    """Register the ``run`` sub-command."""
    p = subparsers.add_parser(
        "run",
        allow_abbrev=False,
        help="run the virtual drive as a CANopen CiA 402 node (default command)",
        description="Run the simulated drive paced to wall-clock time as a CANopen node on a "
        "python-can bus. Bus options not given come from python-can's config/environment.",
    )
    add_run_arguments(p)
    p.set_defaults(func=run_command)
    return p


#: Title of the bus options' group (the same as drive-link's).
BUS_GROUP_TITLE = "bus (unset = python-can config / CAN_* environment)"

#: One-line help for python-can's options (its own texts run to several lines each).
_SHORT_HELP = {
    "channel": "python-can channel (can0, vcan0; socketcand: the hub's bus)",
    "interface": "python-can interface (socketcan, socketcand, pcan, virtual, ...)",
    "bitrate": "bit/s",
    "fd": "CAN FD",
    "data_bitrate": "CAN FD data phase bit/s",
    "timing": "bit timing KEY=VALUE ... (can.BitTiming / BitTimingFd fields)",
    "bus_kwargs": "KEY=VALUE ... passed on to can.Bus",
}

#: python-can options :func:`bus_kwargs` passes on to ``can.Bus`` when given.
_BUS_KEYS = ("interface", "channel", "bitrate", "fd", "data_bitrate", "timing", "host", "port")


class _RecordingParser:
    """Stands in for a parser while python-can adds its bus options: the argument groups are
    the parser's own, and every action they add is kept in :attr:`actions` (to shorten their
    help texts)."""

    def __init__(self, parser: argparse.ArgumentParser) -> None:
        self.parser = parser
        self.actions: list[argparse.Action] = []

    def add_argument_group(self, *args: Any, **kwargs: Any) -> _RecordingGroup:
        return _RecordingGroup(self.parser.add_argument_group(*args, **kwargs), self.actions)

    def add_argument(self, *args: Any, **kwargs: Any) -> argparse.Action:
        action = self.parser.add_argument(*args, **kwargs)
        self.actions.append(action)
        return action


class _RecordingGroup:
    """An argument group that keeps the actions it adds (see :class:`_RecordingParser`)."""

    def __init__(self, group: argparse._ArgumentGroup, actions: list[argparse.Action]) -> None:
        self.group = group
        self.actions = actions

    def add_argument(self, *args: Any, **kwargs: Any) -> argparse.Action:
        action = self.group.add_argument(*args, **kwargs)
        self.actions.append(action)
        return action


def add_run_arguments(p: argparse.ArgumentParser) -> None:
    """The options of ``virtual-drive run``: python-can's own bus options
    (:func:`can.cli.add_bus_arguments`, the spelling drive-link shares: ``-i/--interface``,
    ``-c/--channel``, ``-b/--bitrate``, ``--fd``, ``--data-bitrate``, ``--timing``,
    ``--bus-kwargs``), the loopback hub's ``--host``/``--port``/``--hub``/``--hub-port``, then
    the node options."""
    recording = _RecordingParser(p)
    # (python-can types the parser as ArgumentParser; the recorder stands in for one by duck
    # typing: add_argument/add_argument_group, which is all add_bus_arguments calls)
    can.cli.add_bus_arguments(recording, group_title=BUS_GROUP_TITLE)  # type: ignore[arg-type]
    for action in recording.actions:
        action.help = _SHORT_HELP.get(action.dest, action.help)
        if action.dest == "interface":
            # no choices: can.Bus names an unknown interface itself (one line, exit 1) and
            # the usage line stays short
            action.choices = None
    bus = p.add_argument_group("loopback hub (socketcand rawmode on 127.0.0.1)")
    bus.add_argument("--host", help="socketcand host (the loopback hub: 127.0.0.1)")
    bus.add_argument("--port", type=int, help="socketcand TCP port")
    bus.add_argument(
        "--hub",
        action="store_true",
        help="start a loopback hub in this process (127.0.0.1, --hub-port) and join it",
    )
    bus.add_argument("--hub-port", type=int, default=0, help="port of --hub (0 = any free)")
    # one spelling with drive-link/drive-dashboard (drive_link.cli.connect; not imported here:
    # virtual_drive does not depend on the host package); -n/--node-id stay as hidden aliases
    p.add_argument("--node", dest="node_id", type=int, help="CANopen node-ID 1..127 (default 1)")
    p.add_argument("-n", "--node-id", dest="node_id", type=int, help=argparse.SUPPRESS)
    p.add_argument(
        "--nodes",
        metavar="IDS",
        help="serve several drives from this process, e.g. 1-4 or 1,3,5 (one pacing loop)",
    )
    p.add_argument(
        "--store",
        metavar="FILE",
        help="parameter file for 0x1010/0x1011; with --nodes '{node}' in FILE is the node-ID, "
        "else FILE gets '-node<N>' before its suffix",
    )
    p.add_argument(
        "--speed", type=float, default=1.0, help="simulated seconds per wall-clock second"
    )
    p.add_argument(
        "--tick-ms",
        type=float,
        default=float(os.environ["VIRTUAL_DRIVE_TICK_MS"])
        if os.environ.get("VIRTUAL_DRIVE_TICK_MS")
        else None,
        help="wall-clock period of the pacing loop, ms (default $VIRTUAL_DRIVE_TICK_MS, else 10 "
        "on the loopback hub, whose frames carry their bus time, and 1 elsewhere): simulation "
        "chunks and heartbeats run on this grid, TPDOs on their own event timer (on the hub "
        "sent in batches with their exact times; elsewhere on this grid), SDO reads of "
        "measurements see the present; a longer tick costs less CPU, a shorter one delivers "
        "TPDOs sooner (User-Mode Linux: 10)",
    )
    p.add_argument("--log-level", default="INFO", choices=["DEBUG", "INFO", "WARNING", "ERROR"])
    from virtual_drive.node.cli_lss import add_lss_arguments

    add_lss_arguments(p)  # --unconfigured N, --serial-base S: LSS slaves (CiA 305)


def bus_kwargs(args: argparse.Namespace) -> dict:
    """``can.Bus`` keyword arguments from the options actually given (``--bus-kwargs``
    merged in; an option not given is absent, so python-can's configuration fills it)."""
    kw: dict = {}
    for key in _BUS_KEYS:
        value = getattr(args, key, None)
        if value is not None and value is not False:
            kw[key] = value
    kw.update(getattr(args, "bus_kwargs", None) or {})
    return kw


def socketcand_defaults(cfg: dict) -> dict:
    """The loopback hub's defaults for a socketcand bus (tcp_tune: 4x faster SDO)."""
    if cfg.get("interface") == "socketcand":
        for key, value in (("channel", "vcan0"), ("host", "127.0.0.1"), ("tcp_tune", True)):
            if cfg.get(key) is None:
                cfg[key] = value
    return cfg


def parse_nodes(text: str) -> list[int]:
    """Node-IDs from ``1-4``, ``1,3,5`` or ``1-3,7`` (each 1..127, no repeats, at most
    :data:`MAX_NODES`); raises ValueError with a one-line reason."""
    ids: list[int] = []
    for part in text.split(","):
        part = part.strip()
        lo, sep, hi = part.partition("-")
        try:
            a = int(lo)
            b = int(hi) if sep else a
        except ValueError:
            raise ValueError(f"--nodes: {part!r} is not a node-ID or range like 1-4") from None
        if not (1 <= a <= 127 and 1 <= b <= 127) or b < a:
            raise ValueError(f"--nodes: {part!r} is not within 1..127 (low-high)")
        ids.extend(range(a, b + 1))
    if len(set(ids)) != len(ids):
        raise ValueError(f"--nodes: {text!r} names a node twice")
    if not 1 <= len(ids) <= MAX_NODES:
        raise ValueError(f"--nodes: 1..{MAX_NODES} drives per process, got {len(ids)}")
    return ids


def store_for(store: str | None, node_id: int, several: bool) -> Path | None:
    """The parameter file of ``node_id``: ``{node}`` in ``store`` is replaced by the node-ID;
    else with several nodes ``params.json`` becomes ``params-node2.json``."""
    if store is None:
        return None
    if "{node}" in store:
        return Path(store.replace("{node}", str(node_id)))
    path = Path(store)
    if not several:
        return path
    return path.with_name(f"{path.stem}-node{node_id}{path.suffix}")


def open_bus(cfg: dict) -> can.BusABC:
    """``can.Bus(**cfg)``, except that a socketcand bus uses the lean
    :class:`~virtual_drive.node.hub_bus.HubBus` (same protocol, batched sends)."""
    if cfg.get("interface") == "socketcand":
        from virtual_drive.node.hub_bus import HubBus

        kw = {k: v for k, v in cfg.items() if k != "interface"}
        return HubBus(**kw)
    return can.Bus(**cfg)


class SendCounts(Protocol):
    """What :func:`bus_lost` reads of a drive (:class:`.VirtualDrive`'s send counters)."""

    @property
    def tx_errors(self) -> int: ...  # frames the bus refused

    @property
    def last_tx_ok(self) -> float: ...  # monotonic s of the last frame the bus took


def bus_lost(bus: can.BusABC, drive: SendCounts) -> str | None:
    """Why the bus is gone, or None while it works.

    python-can's socketcand interface does not notice a closed connection (its receive loop
    then spins on the dead socket), so the socket is peeked for end-of-file; on any bus, sends
    failing for more than 2 s also count as a lost bus.
    """
    lost = getattr(bus, "lost", None)
    if callable(lost):
        reason = lost()
        if reason is not None:
            return str(reason)  # (HubBus.lost: a str; getattr leaves it untyped)
    sock = getattr(bus, "_SocketCanDaemonBus__socket", None)
    if sock is not None:
        try:
            if sock.recv(1, socket.MSG_PEEK | socket.MSG_DONTWAIT) == b"":
                return "the socketcand server closed the connection"
        except BlockingIOError:
            pass
        except OSError as exc:
            return f"socketcand connection failed: {exc}"
    if drive.tx_errors and time.monotonic() - drive.last_tx_ok > 2.0:
        return f"no frame could be sent for 2 s ({drive.tx_errors} send errors)"
    return None


def _fail(message: str, code: int = 1) -> int:
    print(f"virtual-drive: error: {message}", file=sys.stderr, flush=True)
    return code


def run_command(args: argparse.Namespace) -> int:
    """Run until SIGINT/SIGTERM; returns the exit status."""
    logging.basicConfig(
        level=getattr(logging, args.log_level),
        format="%(asctime)s %(levelname)s %(name)s: %(message)s",
        stream=sys.stderr,
    )
    if args.nodes is not None:
        if args.node_id is not None:
            return _fail("give --node-id or --nodes, not both", 2)
        try:
            node_ids = parse_nodes(args.nodes)
        except ValueError as exc:
            return _fail(str(exc), 2)
    else:
        node_ids = [1 if args.node_id is None else args.node_id]
        if not 1 <= node_ids[0] <= 127:
            return _fail(f"--node-id must be 1..127, got {node_ids[0]}", 2)
    if not args.speed > 0:
        return _fail(f"--speed must be > 0, got {args.speed}", 2)
    if args.tick_ms is not None and not 0.1 <= args.tick_ms <= 20.0:
        return _fail(f"--tick-ms must be 0.1..20 ms, got {args.tick_ms:g}", 2)
    hub = None
    if args.hub:
        from virtual_drive.hub import Hub

        try:
            bitrate = getattr(args, "bitrate", None) or 1_000_000
            hub = Hub(port=args.hub_port, bitrate=bitrate).start()
        except (OSError, ValueError) as exc:
            return _fail(f"cannot start the hub on 127.0.0.1:{args.hub_port}: {exc}")
        args.interface, args.host, args.port = "socketcand", "127.0.0.1", hub.port
        args.bitrate = None
    logging.getLogger("canopen").setLevel(max(logging.WARNING, logging.root.level))
    kw = bus_kwargs(args)
    shown = ", ".join(f"{k}={v}" for k, v in kw.items()) or "python-can configuration"
    try:
        # options given here win; the rest comes from python-can's config file / CAN_* env
        cfg = socketcand_defaults(dict(can.util.load_config(config=kw)))
    except Exception as exc:
        if hub is not None:
            hub.stop()
        return _fail(f"no usable CAN bus configuration ({shown}): {exc}")
    if cfg.get("interface") == "socketcand" and cfg.get("port") is not None:
        # python-can retries a refused socketcand connection for 10 s with a warning per try:
        # check the server is there first and fail with one line.
        host = cfg.get("host", "127.0.0.1")
        try:
            socket.create_connection((host, int(cfg["port"])), timeout=2.0).close()
        except (OSError, ValueError) as exc:
            if hub is not None:
                hub.stop()
            return _fail(
                f"cannot open the CAN bus ({shown}): {getattr(exc, 'strerror', None) or exc}"
            )
    if getattr(args, "unconfigured", None) is not None:
        from virtual_drive.node.cli_lss import run_unconfigured

        with StopSignal() as stop_lss:
            try:
                return run_unconfigured(args, cfg, open_bus, stop_lss)
            finally:
                if hub is not None:
                    hub.stop()
    buses: list[can.BusABC] = []
    conn = None
    try:
        if len(node_ids) > 1 and cfg.get("interface") == "socketcand":
            # one hub connection for all nodes: each frame crosses the socket once
            from virtual_drive.node.hub_bus import HubConnection

            conn = HubConnection(**{k: v for k, v in cfg.items() if k != "interface"})
            buses = [conn.port() for _ in node_ids]
        else:
            for _ in node_ids:  # one connection per node: each sees the others' frames
                buses.append(open_bus(cfg))
    except Exception as exc:  # python-can raises many types (CanError, OSError, ValueError...)
        for bus in buses:
            bus.shutdown()
        if conn is not None:
            conn.close()
        if hub is not None:
            hub.stop()
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        return _fail(f"cannot open the CAN bus ({shown}): {reason}")

    from virtual_drive.node.drive_node import TIMED_PERIOD, VirtualDrive
    from virtual_drive.node.runner import Pacer

    stop = StopSignal().__enter__()  # (restored in the finally below)
    # The drive process runs a pacing thread (simulation chunks and TPDOs of all nodes) and a
    # receive thread per node: hand the GIL over every 0.5 ms instead of 5 ms so an SDO request
    # or a TPDO due on its exact time does not wait for another thread's Python work
    # (median 2 ms-inhibit gap 2.6 -> 2.2 ms measured at load 25).
    sys.setswitchinterval(0.0005)
    if args.tick_ms is not None:
        period = args.tick_ms / 1000.0
    elif all(getattr(bus, "timed_sends", False) for bus in buses):
        period = TIMED_PERIOD
    else:
        period = 1e-3
    pacer = Pacer(period)
    drives: list = []
    several = len(node_ids) > 1
    try:
        for node_id, bus in zip(node_ids, buses, strict=True):
            try:
                drive = VirtualDrive(
                    bus,
                    node_id=node_id,
                    store_path=store_for(args.store, node_id, several),
                    speed=args.speed,
                )
            except Exception as exc:
                return _fail(f"cannot start the drive (node {node_id}): {exc}")
            if drive.parameters.store_error:
                logger.error(
                    "node %d parameter file: %s (defaults used)",
                    node_id,
                    drive.parameters.store_error,
                )
            pacer.adopt(drive.runner)  # one pacing thread for all nodes
            if hasattr(bus, "rx_wanted"):
                bus.rx_wanted = drive.network.subscribers  # drop frames this node ignores
            drives.append(drive)
        if conn is not None:
            pacer.flush_hooks.append(conn.flush)
        for drive in drives:
            drive.start()
        if conn is not None:  # the nodes' frames of one pacer wake-up in one write
            conn.batch_on(pacer.thread_ident)
        where = buses[0].channel_info
        if several:
            line = f"virtual-drive: nodes {','.join(map(str, node_ids))} ready on {where}"
        else:
            line = f"virtual-drive: node {node_ids[0]} ready on {where}"
        if hub is not None:
            line += f"; hub: {hub.join_line()}"
        print(line, flush=True)
        parent = os.environ.get("VIRTUAL_DRIVE_PARENT_PID")
        while not stop.wait(0.2):
            if parent and parent.isdigit() and os.getppid() != int(parent):
                return _fail(f"parent process {parent} is gone")
            for drive in drives:
                prefix = f"node {drive.node_id}: " if several else ""
                if drive.runner.error is not None:
                    return _fail(f"{prefix}simulation loop stopped: {drive.runner.error}")
                lost = bus_lost(drive.bus, drive)
                if lost is not None:
                    return _fail(f"{prefix}CAN bus lost: {lost}")
        logger.info("signal received, shutting down")
        return 0
    finally:
        for drive in drives:
            drive.stop()
        pacer.stop()
        for bus in buses:
            bus.shutdown()
        if conn is not None:
            conn.close()
        if hub is not None:
            hub.stop()
        stop.__exit__()
