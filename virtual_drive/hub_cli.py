"""``virtual-drive hub``: run the loopback CAN hub (:class:`virtual_drive.hub.Hub`) until SIGINT or
SIGTERM, optionally with virtual drives on it (``--nodes 1-4``: served by a ``virtual-drive run
--nodes`` child process, started and stopped by :func:`virtual_drive.launch.virtual_bench`).

The first line on stdout is the python-can line that joins the hub (scripts parse its port).
"""

from __future__ import annotations

import argparse
import errno
import sys

from virtual_drive.hub import DEFAULT_PORT, Hub
from virtual_drive.stop_signal import StopSignal

__all__ = ["add_parser", "run_hub_command"]


def add_parser(
    subparsers: argparse._SubParsersAction[argparse.ArgumentParser],
) -> argparse.ArgumentParser:
    """Register the ``hub`` sub-command on a ``virtual-drive`` argparse sub-parser set."""
    p = subparsers.add_parser(
        "hub",
        allow_abbrev=False,
        help="run the loopback CAN hub (socketcand rawmode on 127.0.0.1)",
        description="Loopback CAN hub: processes join it with python-can's socketcand "
        "interface. Binds 127.0.0.1 only. Stop with Ctrl-C or SIGTERM.",
    )
    p.add_argument("--host", default="127.0.0.1", help="must be 127.0.0.1 or localhost")
    p.add_argument("--port", type=int, default=DEFAULT_PORT, help="TCP port, 0 = any free port")
    p.add_argument("--bitrate", type=int, default=1_000_000, help="emulated bit rate, bit/s")
    p.add_argument(
        "--drop-rate", "--drop", type=float, default=0.0, help="probability 0..1 a frame is lost"
    )
    p.add_argument("--delay-ms", type=float, default=0.0, help="extra delivery delay, ms")
    p.add_argument(
        "--jitter-ms", type=float, default=0.0,
        help="± uniform jitter of the delivery delay per frame, ms (frame order is kept)",
    )  # fmt: skip
    p.add_argument("--seed", type=int, default=0, help="seed of the drop and jitter RNGs")
    p.add_argument("--channel", default="vcan0", help="channel shown in the join line")
    p.add_argument(
        "--nodes",
        metavar="IDS",
        help="also run a virtual drive per node-ID on the hub, e.g. 1-4 or 1,3 "
        "(served by one `virtual-drive run --nodes` child process)",
    )
    p.add_argument(
        "--speed", type=float, default=1.0, help="--nodes: simulated seconds per wall-clock second"
    )
    p.add_argument(
        "--store-dir",
        metavar="DIR",
        help="--nodes: folder of the parameter files node<N>.json (default: a temporary one)",
    )
    p.set_defaults(func=run_hub_command)
    return p


def _error(message: str, code: int) -> int:
    print(f"virtual-drive hub: error: {message}", file=sys.stderr, flush=True)
    return code


def run_hub_command(args: argparse.Namespace) -> int:
    """Run the hub (and the ``--nodes`` drives) until SIGINT/SIGTERM; returns the exit code."""
    from virtual_drive.bus_load import overload_warning
    from virtual_drive.launch import parse_nodes, virtual_bench

    faults = {
        "drop_rate": args.drop_rate,
        "delay_s": args.delay_ms / 1000.0,
        "jitter_s": args.jitter_ms / 1000.0,
        "seed": args.seed,
    }
    try:
        Hub(host=args.host, port=args.port, bitrate=args.bitrate, **faults)  # validation only
        nodes = parse_nodes(args.nodes) if args.nodes is not None else ()
        if not args.speed > 0:
            raise ValueError(f"--speed must be > 0, got {args.speed}")
    except ValueError as exc:
        return _error(str(exc), 2)
    stop = StopSignal().__enter__()  # (restored in the finally below)
    try:
        with virtual_bench(
            nodes,
            hub_port=args.port,
            bitrate=args.bitrate,
            channel=args.channel,
            speed=args.speed,
            store_dir=args.store_dir,
            **faults,
        ) as bench:
            hub = bench.hub
            print(hub.join_line(args.channel), flush=True)
            for n, proc in bench.drives.items():
                print(f"virtual-drive: node {n} ready (pid {proc.pid})", flush=True)
            warning = overload_warning(len(nodes), args.bitrate) if nodes else None
            if warning is not None:
                print(f"virtual-drive hub: {warning}", file=sys.stderr, flush=True)
            while not stop.wait(0.2):
                if not hub.running:
                    return _error("hub thread stopped", 1)
                for n, proc in bench.drives.items():
                    if proc.proc.poll() is not None:
                        tail = proc.stderr_tail.strip().splitlines()
                        why = tail[-1] if tail else f"exit status {proc.proc.returncode}"
                        return _error(f"virtual drive node {n} stopped: {why}", 1)
            st = hub.stats
    except OSError as exc:
        if exc.errno == errno.EADDRINUSE:
            return _error(f"port {args.port} on 127.0.0.1 is already in use", 1)
        return _error(f"cannot listen on 127.0.0.1:{args.port}: {exc.strerror or exc}", 1)
    except RuntimeError as exc:  # a drive did not come up (all stopped again)
        return _error(str(exc).splitlines()[0] if str(exc) else "a drive did not come up", 1)
    finally:
        stop.__exit__()
    print(
        f"virtual-drive hub: stopped; {st.frames_forwarded} frames forwarded, "
        f"{st.frames_dropped} dropped, {st.clients_total} clients",
        file=sys.stderr,
    )
    return 0
