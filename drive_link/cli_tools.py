"""The tool sub-commands of ``drive-link``: ``shell``, ``live --plot``, ``record``, ``replay``.

:func:`register_tools` adds them to :func:`drive_link.cli.build_parser`'s sub-parsers (one hook
call there), so the tools live in their own modules (:mod:`drive_link.shell`,
:mod:`drive_link.live_plot`, :mod:`drive_link.record`, :mod:`drive_link.replay`) and the
one-shot CLI stays one module. Each module is imported only when its command runs.
"""

from __future__ import annotations

import argparse
from typing import Any

__all__ = ["register_tools"]


def _lazy(module: str, fn: str) -> Any:
    """A handler that imports ``drive_link.<module>`` on first call and runs its ``fn``."""

    def run(*a: Any) -> int:
        import importlib

        return getattr(importlib.import_module(f"drive_link.{module}"), fn)(*a)

    run.__name__ = fn
    return run


def register_tools(sub: argparse._SubParsersAction, bus: argparse.ArgumentParser) -> None:
    """Add ``shell``, ``record``, ``replay`` to ``sub`` and ``--plot`` to its ``live`` command.

    ``bus``: the parent parser carrying the bus options (--interface … --json). Handlers follow
    cli.py's contract: ``func(args, drive)`` when ``needs_drive`` is true, else ``func(args)``.
    """

    def add(name: str, fn: Any, help: str, needs_drive: bool = True) -> argparse.ArgumentParser:
        p = sub.add_parser(name, parents=[bus], help=help, description=help)
        p.set_defaults(func=fn, needs_drive=needs_drive)
        return p

    p = add(
        "shell",
        _lazy("shell", "cmd_shell"),
        "interactive session on one connection: the drive-link commands without the prefix, "
        "history and TAB completion of commands and object names; 'help', 'exit' or Ctrl-D",
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
