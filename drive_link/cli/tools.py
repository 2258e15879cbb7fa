"""The tool sub-commands of ``drive-link``: ``shell``, ``live --plot``, ``record``, ``replay``.

:func:`add_parsers` adds them to :func:`drive_link.cli.main.build_parser`'s sub-parsers; the
tools live in their own modules (:mod:`.shell`, :mod:`.live_plot`, :mod:`.record`,
:mod:`.replay`), each imported only when its command runs.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any

from ._common import _Parser, quantity
from .connect import bus_settings_from_args

__all__ = ["add_parsers", "bus_settings"]


def _lazy(module: str, fn: str) -> Callable[..., int]:
    """A handler that imports ``drive_link.cli.<module>`` on first call and runs its ``fn``."""

    def run(*a: Any) -> int:
        import importlib

        handler: Callable[..., int] = getattr(
            importlib.import_module(f"drive_link.cli.{module}"), fn
        )
        return handler(*a)

    run.__name__ = fn
    return run


def bus_settings(args: argparse.Namespace) -> dict[str, Any]:
    """:meth:`Drive.connect` / :func:`drive_link.link.bus.open_bus` keywords from a command line's
    bus options (:func:`drive_link.cli.connect.bus_settings_from_args` where it exists)."""
    return dict(bus_settings_from_args(args))


def _unit(unit: str, integer: bool = False) -> Any:
    """argparse ``type=`` taking a value with a unit (``2min``, ``500ms``, ``20Hz``) through
    the CLI's units parser."""
    return quantity(unit, integer=integer)


def add_parsers(sub: argparse._SubParsersAction[_Parser], bus: _Parser) -> None:
    """Add ``shell``, ``record``, ``replay`` to ``sub`` and ``--plot`` to its ``live`` command.

    ``bus``: the parent parser carrying the bus options (--interface … --json). Handlers follow
    cli.py's contract: ``func(args, drive)`` when ``needs_drive`` is true, else ``func(args)``.
    """

    def add(name: str, fn: Any, help: str, needs_drive: bool = True) -> argparse.ArgumentParser:
        p = sub.add_parser(name, parents=[bus], help=help, description=help, allow_abbrev=False)
        p.set_defaults(func=fn, needs_drive=needs_drive)
        return p

    p = add(
        "shell",
        _lazy("shell", "cmd_shell"),
        "interactive session on one connection: the drive-link commands without the prefix, "
        "history and TAB completion of commands and object names; 'help', 'exit' or Ctrl-D",
        needs_drive=False,  # connects itself, with the session's heartbeat supervision
    )
    p.add_argument(
        "--history",
        default=None,
        metavar="FILE",
        help="history file (default ~/.drive_link_history; only kept on a terminal)",
    )
    p.add_argument(
        "--no-heartbeat",
        action="store_true",
        help="do not supervise the session (default: host heartbeat 100 ms and the drive's "
        "heartbeat consumer set, so the drive stops the motor if the shell dies)",
    )

    p = add(
        "record",
        _lazy("record", "cmd_record"),
        "record every frame on the bus to FILE until --seconds or Ctrl-C; the suffix picks the "
        "format: .asc/.blf (Vector, SavvyCAN), .log (candump/canplayer), .csv, .trc, "
        ".mf4 (with asammdf)",
        needs_drive=False,
    )
    p.add_argument("file", metavar="FILE", help="log file (.asc, .blf, .log, .csv, .trc, .mf4)")
    p.add_argument(
        "--seconds",
        type=_unit("s"),
        default=None,
        help="recording length, s (10, 2min; default: until Ctrl-C)",
    )

    p = add(
        "replay",
        _lazy("replay", "cmd_replay"),
        "decode a bus recording offline (any python-can log format): TPDO signals as in "
        "'live' (summary, --csv, --plot), SDO block uploads, trace uploads reassembled",
        needs_drive=False,
    )
    p.add_argument("file", metavar="FILE", help="recording (.asc, .blf, .log, .csv, .trc, .mf4)")
    p.add_argument("--csv", default=None, metavar="OUT", help="TPDO signals on one time base")
    p.add_argument(
        "--trace-csv",
        default=None,
        metavar="OUT",
        help="reassembled trace uploads (OUT_1, OUT_2 … when several)",
    )
    p.add_argument(
        "--trace-png", default=None, metavar="OUT", help="the reassembled traces as plots"
    )
    p.add_argument(
        "--plot", nargs="+", default=None, metavar="SIGNAL", help="text plot of these signals"
    )
    p.add_argument("--width", type=int, default=100, help="plot width, columns (default 100)")
    p.add_argument("--height", type=int, default=24, help="plot height, rows (default 24)")

    live = sub.choices.get("live")
    if live is not None:
        _add_live_plot(live)


def _add_live_plot(p: argparse.ArgumentParser) -> None:
    """``live --plot SIGNAL...``: the existing ``live`` command draws a terminal plot instead of
    its summary when ``--plot`` is given (its handler is wrapped, its options kept)."""
    g = p.add_argument_group("terminal plot (--plot)")
    g.add_argument(
        "--plot",
        nargs="+",
        metavar="SIGNAL",
        default=None,
        help="plot these TPDO signals live (i_p, speed, i_p_ref, speed_ref, v_L, e_L …); keys: "
        "space quick stop, q quick stop and quit, x quit",
    )
    g.add_argument("--window", type=_unit("s"), default=5.0, help="time span shown, s (default 5)")
    g.add_argument("--fps", type=float, default=10.0, help="redraws per second (default 10)")
    g.add_argument(
        "--frames",
        type=int,
        default=None,
        help="print N frames as text and exit (no terminal needed)",
    )
    g.add_argument(
        "--width", type=int, default=None, help="text width, columns (default: terminal)"
    )
    g.add_argument("--height", type=int, default=None, help="text height, rows (default: terminal)")
    summary: Callable[[argparse.Namespace, Any], int] = p.get_default("func")

    def run(args: argparse.Namespace, d: Any) -> int:
        if args.plot:
            return _lazy("live_plot", "cmd_live_plot")(args, d)
        return summary(args, d)

    p.set_defaults(func=run)
