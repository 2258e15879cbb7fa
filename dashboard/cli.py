"""``drive-dashboard``: FastAPI (REST, WebSocket, docs) and the viser GUI in one process.

``drive-dashboard --virtual`` starts the loopback hub and a virtual drive (``virtual-drive run``
in a child process, stopped with SIGTERM, then SIGKILL, on every exit) too, so one command gives
a working bench. Binds 127.0.0.1; ``--allow-remote --token T`` exposes the REST API (the
GUI stays on 127.0.0.1: viser has no authentication; reach it through an SSH tunnel).
"""

from __future__ import annotations

import argparse
import logging
import os
import socket
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, NoReturn

from dashboard.config import GUI_RATE_HZ, GUI_RATE_RANGE_HZ, BenchConfig
from drive_link.cli.closed_pipe import run_quietly, silence_output
from drive_link.cli.connect import add_bus_arguments, bus_extras_from_args

if TYPE_CHECKING:
    from fastapi import FastAPI

__all__ = ["build_parser", "main"]


class _Parser(argparse.ArgumentParser):
    """One-line usage errors (exit 2); an option is spelled in full (no abbreviations)."""

    def __init__(self, *a: Any, **kw: Any) -> None:
        kw.setdefault("allow_abbrev", False)
        super().__init__(*a, **kw)

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="drive-dashboard", description=__doc__.splitlines()[0])
    p.add_argument(
        "--virtual",
        action="store_true",
        help="start the loopback hub and a virtual drive (the bench without hardware)",
    )
    p.add_argument(
        "--virtual-in-process",
        action="store_true",
        help="with --virtual: run the virtual drive in this process (default: a child process)",
    )
    p.add_argument(
        "--virtual-subprocess",
        action="store_true",
        help="with --virtual: the virtual drive in a child process (the default; kept for scripts)",
    )
    p.add_argument(
        "--speed-factor",
        type=float,
        default=1.0,
        help="virtual drive: simulated seconds per wall-clock second (default 1)",
    )
    p.add_argument(
        "--nodes",
        metavar="IDS",
        help="with --virtual: start drives with these node-IDs on the hub (1,2 or 1-4); the "
        "dashboard controls --node (default the first), the Bus tab and drive-link see them all",
    )
    p.add_argument(
        "--hub-port",
        type=int,
        default=0,
        help="virtual: TCP port of the loopback hub (default: any free)",
    )
    p.add_argument(
        "--join-hub",
        type=int,
        metavar="PORT",
        help="join a running loopback hub on 127.0.0.1:PORT (virtual-drive run --hub)",
    )
    # python-can's --interface/-i, --channel/-c, --bitrate/-b (default 1000000), --fd,
    # --data-bitrate, --timing, --bus-kwargs, and --node: drive_link.cli.connect, as everywhere
    add_bus_arguments(p, hub=False, defaults={"bitrate": 1_000_000})
    p.add_argument("--host", default="127.0.0.1", help="API bind address (default 127.0.0.1)")
    p.add_argument("--port", type=int, default=8000, help="API port (default 8000)")
    p.add_argument("--gui-port", type=int, default=8080, help="GUI port (default 8080; 0 = any)")
    p.add_argument(
        "--plot-rate",
        type=float,
        default=GUI_RATE_HZ,
        metavar="HZ",
        help=f"plot refreshes per second in each browser (default {GUI_RATE_HZ:g}; "
        f"{GUI_RATE_RANGE_HZ[0]:g}..{GUI_RATE_RANGE_HZ[1]:g}): a lower rate costs the bench "
        "and each browser less CPU (a weak laptop, many tabs); a step is pushed at once",
    )
    p.add_argument("--no-3d", action="store_true", help="no 3D rotor view (lighter browsers)")
    p.add_argument(
        "--show-3d",
        action="store_true",
        help="show the 3D rotor when a page opens (default: its checkbox starts unchecked; a "
        "turning rotor costs a browser with software WebGL 50-130 %% of a core)",
    )
    p.add_argument(
        "--allow-remote", action="store_true", help="allow a non-loopback --host (needs --token)"
    )
    p.add_argument(
        "--token",
        default=os.environ.get("DRIVE_DASHBOARD_TOKEN"),
        help="access token for the API (env DRIVE_DASHBOARD_TOKEN)",
    )
    return p


def _port_free(host: str, port: int) -> bool:
    """Whether nothing listens on ``host:port``: the probe binds with SO_REUSEADDR, as uvicorn
    and viser bind (asyncio's default on Unix), so the closed connections of the last run still
    in TIME_WAIT (a browser was connected when Ctrl-C stopped it) do not count as busy."""
    if port == 0:
        return True
    with socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind((host, port))
        except OSError:
            return False
    return True


def _no_startup_traceback(record: logging.LogRecord) -> bool:
    """Drop uvicorn's lifespan traceback and its "startup failed" line (main prints one line)."""
    msg = record.getMessage()
    return not (msg.startswith("Traceback") or msg.startswith("Application startup failed"))


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``drive-dashboard``; a closed output pipe ends it quietly (status 141)."""
    return run_quietly(lambda: _main(argv))


def _main(argv: Sequence[str] | None) -> int:
    args = build_parser().parse_args(argv)
    nodes: tuple[int, ...] = ()
    if args.nodes is not None:
        from virtual_drive.node.cli_run import parse_nodes

        try:
            nodes = tuple(parse_nodes(args.nodes))
        except ValueError as exc:
            print(f"drive-dashboard: error: {exc}", file=sys.stderr)
            return 2
        given = argv if argv is not None else sys.argv[1:]
        if not any(a.split("=")[0] in ("--node", "-n", "--node-id") for a in given):
            args.node = nodes[0]  # no --node: the first of --nodes
    config = BenchConfig(
        host=args.host,
        api_port=args.port,
        gui_port=args.gui_port,
        virtual=args.virtual,
        virtual_in_process=args.virtual_in_process,
        speed_factor=args.speed_factor,
        hub_port=args.hub_port,
        join_hub=args.join_hub,
        interface=args.interface,
        channel=args.channel,
        bitrate=args.bitrate,
        bus_options=bus_extras_from_args(args),
        scene_3d=not args.no_3d,
        gui_rate_hz=args.plot_rate,
        scene_3d_shown=args.show_3d,
        node_id=args.node,
        nodes=nodes,
        allow_remote=args.allow_remote,
        token=args.token,
    )
    if args.virtual_in_process and args.virtual_subprocess:
        print(
            "drive-dashboard: error: --virtual-in-process and --virtual-subprocess exclude "
            "each other",
            file=sys.stderr,
        )
        return 2
    try:
        config.validate()
    except ValueError as exc:
        print(f"drive-dashboard: error: {exc}", file=sys.stderr)
        return 2
    if not _port_free(config.host, config.api_port):
        print(
            f"drive-dashboard: error: port {config.api_port} on {config.host} is busy "
            "(choose another with --port)",
            file=sys.stderr,
        )
        return 2
    if config.gui_port and not _port_free("127.0.0.1", config.gui_port):
        print(
            f"drive-dashboard: error: GUI port {config.gui_port} is busy "
            "(choose another with --gui-port, or 0 for any)",
            file=sys.stderr,
        )
        return 2

    import uvicorn

    from dashboard.app import create_app

    def ready(app: FastAPI) -> None:
        gui = app.state.gui
        api = f"http://{_url_host(config.host)}:{config.api_port}"
        try:
            print(f"open http://127.0.0.1:{gui.port}/", flush=True)
            print(
                f"  (REST API {api}/api/state, docs {api}/docs; bus: "
                f"{app.state.bench.description}; Ctrl-C stops)",
                flush=True,
            )
        except BrokenPipeError:  # `drive-dashboard | head -1`: the bench serves on, silently
            silence_output()

    class _Server(uvicorn.Server):
        """Prints the URLs once the REST port listens: the lifespan's startup runs before
        uvicorn binds, and a URL printed then was refused (UML lane, load 9)."""

        async def startup(self, sockets: list[socket.socket] | None = None) -> None:
            await super().startup(sockets=sockets)
            if self.started:
                ready(app)

    app = create_app(config)
    server = _Server(
        uvicorn.Config(
            app,
            host=config.host,
            port=config.api_port,
            log_level="warning",
            workers=1,
            lifespan="on",
        )
    )
    # a bench that cannot open (e.g. --join-hub with no hub) is one line below, not a traceback
    logging.getLogger("uvicorn.error").addFilter(_no_startup_traceback)
    try:
        server.run()
    except KeyboardInterrupt:
        pass
    except SystemExit:  # uvicorn exits 3 when the lifespan failed: reported below
        pass
    if not getattr(server, "started", False):
        reason = getattr(app.state, "startup_error", None) or "could not start"
        print(f"drive-dashboard: error: {reason}", file=sys.stderr)
        return 1
    return 0


def _url_host(host: str) -> str:
    return f"[{host}]" if ":" in host else host


if __name__ == "__main__":
    sys.exit(main())
