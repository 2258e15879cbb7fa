"""The drive a parsed command line names (shared by `drive-link` and `benchmarks/bench_link.py`)."""

from __future__ import annotations

import argparse

from .drive import Drive


def connect_from_args(args: argparse.Namespace) -> Drive:
    """:meth:`Drive.connect` with a command line's bus options, no heartbeat consumer.

    Reads ``interface``, ``channel``, ``bitrate`` (bit/s), ``host``, ``port`` (loopback hub),
    ``node`` (node-ID) and, when the command has it, ``sdo_timeout`` (s per frame; otherwise
    :meth:`Drive.connect`'s default).
    """
    sdo_timeout = getattr(args, "sdo_timeout", None)
    return Drive.connect(
        interface=args.interface,
        channel=args.channel,
        bitrate=args.bitrate,
        host=args.host,
        port=args.port,
        node_id=args.node,
        heartbeat_ms=None,
        **({} if sdo_timeout is None else {"sdo_timeout": sdo_timeout}),
    )
