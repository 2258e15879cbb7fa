"""``drive-link``'s parser and entry point: the top-level parser with the bus options, each
command group adding its own sub-commands (as python-can's logger, player and viewer each
build their own), and :func:`main`, which runs one command and turns every failure into one
line and an exit code (see :mod:`drive_link.cli`)."""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Callable

from ..errors import DriveError, SdoAbort
from ..link.drive import Drive
from . import _common, config, conformance, design, experiments, lss, monitor, objects, state, tools
from ._common import (
    _ABORT_STATE,
    _EPILOG,
    _TOP,
    EXIT_CODES,
    EXIT_UNSAFE,
    Refused,
    _add_bus_options,
    _bus_parent,
    _fail,
    _merge_bus,
    _Parser,
    _state_hint,
)
from .closed_pipe import run_quietly
from .connect import connect_from_args
from .experiments import apply_step_defaults as _apply_step_defaults
from .report import add_parser as add_report_parser

__all__ = ["build_parser", "main"]


def build_parser() -> argparse.ArgumentParser:
    """The ``drive-link`` argument parser."""
    bus = _bus_parent()
    ap = _Parser(
        prog="drive-link",
        description="Talk to a drive (DSP or virtual) over CAN: state, setpoints, objects,\n"
        "gains, traces, step tests, identification, configuration files, conformance.",
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    _add_bus_options(ap, _TOP)  # accepted before the sub-command too
    sub = ap.add_subparsers(dest="cmd", metavar="COMMAND", required=True)

    def add(
        name: str, fn: Callable, help: str, needs_drive: bool = True, omit_bus: tuple = ()
    ) -> argparse.ArgumentParser:
        parent = _bus_parent(omit_bus) if omit_bus else bus
        p = sub.add_parser(name, parents=[parent], help=help, description=help, epilog=_EPILOG,
                           formatter_class=argparse.RawDescriptionHelpFormatter,
                           allow_abbrev=False)  # fmt: skip
        p.set_defaults(func=fn, needs_drive=needs_drive)
        return p

    state.add_parsers(add)
    objects.add_parsers(add)
    experiments.add_parsers(add)
    conformance.add_parsers(add)
    config.add_parsers(add)
    tools.add_parsers(sub, bus)
    lss.add_parsers(sub, bus)
    monitor.add_parsers(sub, bus)
    add_report_parser(sub, bus)
    design.add_parsers(sub)
    return ap


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the exit code (see module docstring)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    _common._JSON_ERRORS = "--json" in argv
    try:
        return run_quietly(lambda: _main(argv))  # `drive-link objects | head -1`: quiet end
    finally:
        _common._JSON_ERRORS = False


def _main(argv: list[str]) -> int:
    ap = build_parser()
    try:
        args = ap.parse_args(argv)
    except SystemExit as exc:  # usage error (printed) or --help: the exit code, no raise
        return exc.code if isinstance(exc.code, int) else 2
    _merge_bus(args)
    # Library log lines (canopen, python-can) would break the one-line-error rule.
    logging.getLogger().addHandler(logging.NullHandler())
    for name in ("canopen", "can"):
        logging.getLogger(name).setLevel(logging.CRITICAL)
    _apply_step_defaults(args)
    d: Drive | None = None
    try:
        func: Callable[..., int] = args.func  # (set by each sub-command's parser)
        if getattr(args, "needs_drive", False):
            d = connect_from_args(args)
            return func(args, d)
        return func(args)
    except Refused as exc:
        return _fail(args, str(exc), EXIT_UNSAFE, prefix="")
    except DriveError as exc:
        msg = str(exc)
        if isinstance(exc, SdoAbort) and exc.code == _ABORT_STATE:
            msg += f": {_state_hint(exc)}"
        for cls, code in EXIT_CODES:
            if isinstance(exc, cls):
                return _fail(args, msg, code)
        return _fail(args, msg, 1)
    except KeyboardInterrupt:
        return _fail(args, "interrupted", 130, prefix="")
    except BrokenPipeError:  # the reader of our output is gone: main() ends quietly
        raise
    except (ValueError, OSError) as exc:
        return _fail(args, str(exc), 1)
    finally:
        if d is not None:
            try:
                d.close()
            except Exception:
                pass
