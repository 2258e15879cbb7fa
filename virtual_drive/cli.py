"""The ``virtual-drive`` command: one argparse program, one sub-command per module.

Each sub-command lives in its own module, which provides ``add_parser(subparsers)``: it registers
its parser and sets ``func`` (a callable ``func(args) -> int`` returning the exit code) with
``parser.set_defaults(func=...)``. Adding a sub-command is one entry in ``_SUBCOMMANDS``.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Sequence
from typing import Any, NoReturn

__all__ = ["build_parser", "main"]

#: Modules providing ``add_parser(subparsers)``, in the order shown by ``--help``.
_SUBCOMMANDS: tuple[str, ...] = (
    "virtual_drive.node.cli_run",
    "virtual_drive.hub_cli",
    "virtual_drive.sweep.cli",
)


class _OneLineErrorParser(argparse.ArgumentParser):
    """Reports bad arguments as one line on stderr and exit status 2; no abbreviated options
    (the sub-parsers are of this class too)."""

    def __init__(self, *a: Any, **kw: Any) -> None:
        kw.setdefault("allow_abbrev", False)
        super().__init__(*a, **kw)

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    """The ``virtual-drive`` argument parser with every sub-command registered."""
    parser = _OneLineErrorParser(
        prog="virtual-drive",
        description="Virtual BLDC drive tools: loopback CAN hub and the virtual drive node.",
    )
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module_name in _SUBCOMMANDS:
        importlib.import_module(module_name).add_parser(subparsers)
    return parser


#: Exit status after the reader closed the output pipe (128 + SIGPIPE, as for other tools).
EXIT_CLOSED_PIPE = 141


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``virtual-drive``; returns the process exit status. A reader that closes
    the output pipe (``virtual-drive --hub | head -1``) ends it quietly: no traceback, stdout and
    stderr pointed at /dev/null, status 141 (drive_link.cli.closed_pipe does the same for
    ``drive-link``; this package does not import it)."""
    try:
        rc = _main(argv)
        sys.stdout.flush()
        return rc
    except BrokenPipeError:
        devnull = os.open(os.devnull, os.O_WRONLY)
        for stream in (sys.stdout, sys.stderr):
            os.dup2(devnull, stream.fileno())
        return EXIT_CLOSED_PIPE


def _main(argv: Sequence[str] | None) -> int:
    parser = build_parser()
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or (argv[0].startswith("-") and argv[0] not in ("-h", "--help")):
        argv.insert(0, "run")  # bare `virtual-drive [options]` means `virtual-drive run`
    args = parser.parse_args(argv)
    return int(args.func(args))


if __name__ == "__main__":
    sys.exit(main())
