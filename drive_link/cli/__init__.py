"""The drive-link command: talk to a drive (DSP or virtual) from a shell.

Every command takes the bus options (--interface/--channel/--bitrate, or --host/--port for the
loopback hub; unset = python-can config/env), --node and --json. Values take units (20uH, 50A,
1000rpm, "-1e30"), converted to the object's unit in the object dictionary; a bare number is in
that unit. Every failure is one line on stderr (with --json: {"error": ..., "exit_code": N} on
stdout) and a non-zero exit code:

1 drive refused / failed check, 2 usage, 3 bus error, 4 node not found (``scan``: none), 5 timeout,
6 SDO abort, 7 invalid value (an option's too), 8 unsafe gains refused (use --force), 130
interrupted, 141 the reader closed the output pipe (quietly, as other Unix tools).

One module per command group, each adding its own sub-parsers (as python-can keeps its logger,
player and viewer apart over the shared ``can.cli``): :mod:`._common` (exit codes, output,
parser, bus options), :mod:`.main` (``build_parser``, ``main``), :mod:`.state`,
:mod:`.objects`, :mod:`.experiments`, :mod:`.conformance`, :mod:`.config`, :mod:`.tools`
(``shell``, ``record``, ``replay``, ``live --plot``), :mod:`.lss`, :mod:`.monitor`,
:mod:`.design` (offline ``design``/``identify``); ``report`` is :mod:`drive_link.cli.report`.
"""

from __future__ import annotations

from ._common import EXIT_CODES, EXIT_UNSAFE, Failed, Refused, _merge_bus, quantity
from .main import build_parser, main

__all__ = [
    "EXIT_CODES",
    "EXIT_UNSAFE",
    "Failed",
    "Refused",
    "build_parser",
    "main",
    "quantity",
]
# ``_merge_bus`` stays reachable as ``drive_link.cli._merge_bus`` (tests parse as main does).
_ = _merge_bus
