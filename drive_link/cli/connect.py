"""Bus options of every command line of the project, and the drive they name.

One definition of the options that choose a CAN bus and a node, shared by ``drive-link``,
``drive-dashboard`` and ``virtual-drive run``:

- python-can's own options, taken from :func:`can.cli.add_bus_arguments` (python-can ≥ 4.5):
  ``--interface/-i``, ``--channel/-c``, ``--bitrate/-b``, ``--fd``, ``--data-bitrate``,
  ``--timing``, ``--bus-kwargs`` (``KEY=VALUE ...`` passed to :class:`can.Bus`);
- ``--host``/``--port``: the project's loopback hub (socketcand rawmode on 127.0.0.1);
- ``--node``: the CANopen node-ID (1..127; the old spellings ``-n``/``--node-id`` are accepted
  as hidden aliases).

An option not given is ``None``: python-can fills the bus settings from its config file and
``CAN_*`` environment; ``DRIVE_LINK_HOST``, ``DRIVE_LINK_PORT`` and ``DRIVE_LINK_NODE`` give
the defaults of ``--host``, ``--port`` and ``--node`` (node 1 without it).

Two ways to add them:

- :func:`add_bus_arguments` for a command line without sub-commands (plain defaults);
- :func:`bus_options` + :func:`add_hidden_aliases` for ``drive-link``, whose options are added
  with ``SUPPRESS`` defaults before *and* after the sub-command and merged after parsing (the
  one after the sub-command wins; see ``drive_link.cli._merge_bus``).
"""

from __future__ import annotations

import argparse
import os
from typing import Any

import can.cli

from ..link.drive import Drive

__all__ = [
    "BUS_GROUP_TITLE",
    "HIDDEN_NODE_ALIASES",
    "Option",
    "add_bus_arguments",
    "add_hidden_aliases",
    "bus_extras_from_args",
    "bus_options",
    "bus_settings_from_args",
    "connect_from_args",
]

#: (flags, add_argument keywords without ``dest``/``default``, default); ``flags[0]`` is the
#: long spelling that names the attribute (``--data-bitrate`` → ``data_bitrate``).
Option = tuple[tuple[str, ...], dict[str, Any], Any]

BUS_GROUP_TITLE = "bus (unset = python-can config / CAN_* environment)"
#: Earlier spellings of ``--node`` (virtual-drive's), accepted but not shown in ``--help``.
HIDDEN_NODE_ALIASES = ("-n", "--node-id")


def _env_int(name: str) -> int | None:
    v = os.environ.get(name)
    try:
        return int(v) if v else None
    except ValueError:
        return None


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


def _python_can_options() -> list[Option]:
    """python-can's bus options as :func:`can.cli.add_bus_arguments` defines them."""
    scratch = argparse.ArgumentParser(add_help=False, allow_abbrev=False)  # only read, never parses
    can.cli.add_bus_arguments(scratch)
    out: list[Option] = []
    for a in scratch._actions:
        longs = [s for s in a.option_strings if s.startswith("--")]
        flags = (*longs, *(s for s in a.option_strings if s not in longs))
        kw: dict[str, Any] = {"help": _SHORT_HELP.get(a.dest, a.help)}
        if isinstance(a, argparse._StoreTrueAction):
            kw["action"] = "store_true"
        else:
            if type(a) is not argparse._StoreAction:
                kw["action"] = type(a)  # python-can's parsers of --timing, --bus-kwargs
            # no ``choices`` for --interface: can.Bus names an unknown interface itself (one
            # line, exit 3 in drive-link) and the usage line stays short
            for attr in ("type", "nargs", "metavar"):
                if getattr(a, attr) is not None:
                    kw[attr] = getattr(a, attr)
        out.append((flags, kw, None))
    return out


#: python-can options every caller can pass on (the others need ``bus_settings_from_args``).
_BASIC = ("interface", "channel", "bitrate")


def bus_options(hub: bool = True, node: bool = True, extras: bool = True) -> list[Option]:
    """The bus options: python-can's (only ``--interface``/``--channel``/``--bitrate`` without
    ``extras``), then ``--host``/``--port`` (``hub``), then ``--node``."""
    opts = [
        o for o in _python_can_options()
        if extras or o[0][0].lstrip("-").replace("-", "_") in _BASIC
    ]  # fmt: skip
    if hub:
        opts += [
            (
                ("--host",),
                {"help": "loopback hub host (socketcand on 127.0.0.1)"},
                os.environ.get("DRIVE_LINK_HOST"),
            ),
            (
                ("--port",),
                {"type": int, "help": "loopback hub TCP port"},
                _env_int("DRIVE_LINK_PORT"),
            ),
        ]
    if node:
        opts.append(
            (
                ("--node",),
                {"type": int, "metavar": "ID", "help": "CANopen node-ID 1..127 (default 1)"},
                _env_int("DRIVE_LINK_NODE") or 1,
            )
        )
    return opts


def add_hidden_aliases(
    parser: argparse.ArgumentParser | argparse._ArgumentGroup, dest: str = "node"
) -> None:
    """``-n``/``--node-id`` as unlisted spellings of ``--node`` (``SUPPRESS`` default)."""
    parser.add_argument(
        *HIDDEN_NODE_ALIASES, dest=dest, type=int, default=argparse.SUPPRESS,
        help=argparse.SUPPRESS,
    )  # fmt: skip


def add_bus_arguments(
    parser: argparse.ArgumentParser,
    *,
    hub: bool = True,
    node: bool = True,
    extras: bool = True,
    node_dest: str = "node",
    defaults: dict[str, Any] | None = None,
) -> None:
    """Add the bus options (see the module doc) to a parser without sub-commands.

    ``hub=False`` leaves out ``--host``/``--port`` (e.g. the dashboard, whose ``--host`` is the
    address it serves on); ``extras=False`` leaves out ``--fd``, ``--data-bitrate``,
    ``--timing`` and ``--bus-kwargs`` (for a caller that passes only interface, channel and
    bitrate on: an accepted option must not be ignored); ``node_dest`` names the attribute of
    ``--node``; ``defaults`` overrides defaults (e.g. ``{"bitrate": 1_000_000}``).
    """
    group = parser.add_argument_group(BUS_GROUP_TITLE)
    given = defaults or {}
    for flags, kw, default in bus_options(hub=hub, node=node, extras=extras):
        dest = flags[0].lstrip("-").replace("-", "_")
        if dest == "node":
            dest = node_dest
        group.add_argument(*flags, dest=dest, default=given.get(dest, default), **kw)
    if node:
        add_hidden_aliases(group, node_dest)


def bus_settings_from_args(args: argparse.Namespace) -> dict[str, Any]:
    """Keyword arguments for :meth:`Drive.connect` / :func:`drive_link.link.bus.open_bus` from the
    bus options given (``None`` = python-can's config; ``--bus-kwargs`` merged in)."""
    out: dict[str, Any] = {}
    for key in ("interface", "channel", "bitrate", "host", "port", "fd", "data_bitrate", "timing"):
        value = getattr(args, key, None)
        if value is not None and value is not False:
            out[key] = value
    out.update(getattr(args, "bus_kwargs", None) or {})
    for key in ("interface", "channel", "bitrate", "host", "port"):
        out.setdefault(key, None)
    return out


def bus_extras_from_args(args: argparse.Namespace) -> dict[str, Any]:
    """python-can's bus options beyond interface/channel/bitrate/host/port that were given
    (``fd``, ``data_bitrate``, ``timing`` and the ``--bus-kwargs``), for a caller that keeps
    those three itself (e.g. ``drive-dashboard``'s :class:`~dashboard.config.BenchConfig`)."""
    basic = ("interface", "channel", "bitrate", "host", "port")
    return {k: v for k, v in bus_settings_from_args(args).items() if k not in basic}


def connect_from_args(args: argparse.Namespace) -> Drive:
    """:meth:`Drive.connect` with a command line's bus options, no heartbeat consumer.

    Reads the bus options (:func:`bus_settings_from_args`), ``node`` (node-ID) and, when the
    command has it, ``sdo_timeout`` (s per frame; otherwise :meth:`Drive.connect`'s default).
    """
    sdo_timeout = getattr(args, "sdo_timeout", None)
    return Drive.connect(
        **bus_settings_from_args(args),
        node_id=args.node,
        heartbeat_ms=None,
        **({} if sdo_timeout is None else {"sdo_timeout": sdo_timeout}),
    )
