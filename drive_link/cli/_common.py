"""What every ``drive-link`` command shares (as python-can's ``can.cli`` is for its logger,
player and viewer): the exit codes and the errors behind them, the one-line output and failure
report (``--json`` too), the argument parser with values in units, and the bus options accepted
before and after the sub-command. The command groups (:mod:`.state`, :mod:`.objects`,
:mod:`.experiments`, :mod:`.conformance`, :mod:`.config`, :mod:`.tools`, :mod:`.lss`,
:mod:`.monitor`, :mod:`.design`) import from here; nothing here imports them.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any, NoReturn, Protocol

from firmware_protocol import abort_codes
from firmware_protocol.index_ranges import PDO_PARAMETERS

from .._jsonable import jsonable as _jsonable
from ..errors import (
    BusError,
    DriveError,
    DriveTimeout,
    InvalidValue,
    NodeNotFound,
    SdoAbort,
    StateError,
    UnknownObject,
)
from ..link import units
from ..link.cia402 import FAULT, FAULT_REACTION_ACTIVE
from ..link.drive import Drive
from .connect import add_hidden_aliases, bus_options

__all__ = [
    "EXIT_CODES",
    "EXIT_INVALID",
    "EXIT_UNSAFE",
    "AddCommand",
    "Failed",
    "Refused",
    "quantity",
]

EXIT_CODES: list[tuple[type[BaseException], int]] = [
    (BusError, 3),
    (NodeNotFound, 4),
    (DriveTimeout, 5),
    (SdoAbort, 6),
    (InvalidValue, 7),
    (UnknownObject, 7),  # an object name or index the dictionary does not have
    (DriveError, 1),
]


EXIT_INVALID = 7


EXIT_UNSAFE = 8


class Refused(DriveError):  # noqa: N818
    """A command refused to act (e.g. unsafe gains without --force)."""


class Failed(DriveError):  # noqa: N818
    """A command ran but its result is a failure (e.g. a failed check)."""


class AddCommand(Protocol):
    """``add(name, fn, help, needs_drive=True, omit_bus=())``: one sub-command with the bus
    options (:func:`drive_link.cli.main.build_parser` hands it to each command group)."""

    def __call__(
        self, name: str, fn: Callable[..., int], help: str, needs_drive: bool = True,
        omit_bus: tuple[str, ...] = (),
    ) -> argparse.ArgumentParser: ...  # fmt: skip


# --------------------------------------------------------------------------- output helpers
def _emit(args: argparse.Namespace, data: Any, text: str | Callable[[], str]) -> None:
    if args.json:
        print(json.dumps(_jsonable(data)))
    else:
        print(text() if callable(text) else text)


def _progress_bar(args: argparse.Namespace) -> Callable[[int, int | None], None] | None:
    """A tqdm bar on stderr for an upload (a terminal, or ``--progress``); None with --json."""
    if args.json or (not sys.stderr.isatty() and not getattr(args, "progress", False)):
        return None
    from tqdm import tqdm

    bars: list[tqdm] = []

    def update(done: int, total: int | None) -> None:
        if not bars:  # made at the first report, when the size is known (or not)
            shape = "[{bar:30}] {percentage:5.1f} % " if total else ""
            bar_format = "{desc} " + shape + "{n_fmt}B"
            bars.append(
                tqdm(
                    desc="upload",
                    total=total or None,
                    unit="B",
                    unit_scale=True,
                    unit_divisor=1024,
                    file=sys.stderr,
                    ascii=" #",
                    mininterval=0.1,
                    bar_format=bar_format,
                )
            )
        bar = bars[0]
        bar.update(done - bar.n)
        if total and done >= total:
            bar.close()

    return update


def _parse_value(text: str) -> float | int | str:
    try:
        return int(text, 0)
    except ValueError:
        pass
    try:
        return float(text)
    except ValueError:
        return text


def _timeout(args: argparse.Namespace, default: float) -> float:
    """``--timeout`` if given, else ``default`` s (a state change under frame loss needs several
    SDO round trips; a scan only listens)."""
    t = getattr(args, "timeout", None)
    return default if t is None else float(t)


def _usable_state(d: Drive) -> str:
    """The CiA 402 state; :class:`StateError` with the fix when the drive is in FAULT."""
    state = d.state
    if state in (FAULT, FAULT_REACTION_ACTIVE):
        raise StateError(f"the drive is in {state}: run `drive-link faults`, then `fault-reset`")
    return state


def _save_outputs(args: argparse.Namespace, obj: Any, out: dict) -> None:
    if getattr(args, "csv", None):
        out["csv"] = str(obj.to_csv(args.csv))
    if getattr(args, "png", None):
        out["png"] = str(obj.to_png(args.png))


# --------------------------------------------------------------------------- parser
#: True while :func:`main` runs with ``--json`` anywhere on the command line: usage errors are
#: then JSON on stdout too.
_JSON_ERRORS = False


class _Parser(argparse.ArgumentParser):
    """argparse with a one-line usage error (exit 2) instead of usage + error lines, and
    negative numbers (``-1e30``, ``-5A``, ``-inf``) taken as values, never as options."""

    def __init__(self, *a: Any, **kw: Any) -> None:
        kw.setdefault("allow_abbrev", False)  # an option is spelled in full (sub-parsers too)
        super().__init__(*a, **kw)
        self._negative_number_matcher = re.compile(r"^-(\.?\d|inf|nan)", re.IGNORECASE)

    def _parse_optional(self, arg_string: str) -> Any:
        # a negative value is never an option, also where a short option shares its first
        # letter (-inf is not "-i nf", -nan not "-n an"): the value parser refuses it in words
        if self._negative_number_matcher.match(arg_string):
            return None
        return super()._parse_optional(arg_string)

    def _get_value(self, action: argparse.Action, arg_string: str) -> Any:
        # a value its type refuses (wrong unit, not a number, nan, not whole) is an invalid
        # value (exit 7, as the same value given to `write`), not a usage error (2)
        try:
            return super()._get_value(action, arg_string)
        except argparse.ArgumentError:
            self._invalid_value = True
            raise

    def error(self, message: str) -> NoReturn:
        code = EXIT_INVALID if getattr(self, "_invalid_value", False) else 2
        self._invalid_value = False  # the shell parses again with the same parser
        text = f"{message} (see {self.prog} --help)"
        if _JSON_ERRORS:
            print(json.dumps({"error": text, "exit_code": code}))
            self.exit(code)
        self.exit(code, f"{self.prog}: error: {text}\n")


def quantity(unit: str, integer: bool = False) -> Callable[[str], float | int]:
    """argparse ``type=`` for a value in ``unit`` typed with or without a unit (``20uH``,
    ``1000rpm``, ``-5A``); a wrong dimension, nan/inf or (``integer``) a non-whole value is a
    one-line usage error. The same parser as the API's
    (:func:`drive_link.link.units.parse_value`)."""

    def parse(text: str) -> float | int:
        try:
            return units.parse_value(text, unit, integer=integer)
        except InvalidValue as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    parse.__name__ = f"value in {unit}" if unit else "number"
    return parse


def _object_value(name: str) -> Callable[[str], float | int]:
    """argparse ``type=`` for a value of the OD object ``name`` (its unit and integer type)."""
    from ..link._objects import default_table

    obj = default_table()[name]
    return quantity(obj.unit, integer=not obj.is_float)


#: Options every command takes, before or after the sub-command: (flags, add_argument keywords
#: without ``default``, default). The default is filled in after parsing (see :func:`_merge_bus`).
def _bus_options() -> list[tuple[tuple[str, ...], dict[str, Any], Any]]:
    return [
        *bus_options(),  # python-can's, --host/--port, --node (drive_link.cli.connect)
        (
            ("--sdo-timeout",),
            {"type": quantity("s"), "help": "SDO response timeout per frame, s (default 0.3)"},
            0.3,
        ),
        (
            ("--timeout",),
            {"type": quantity("s"), "help": "state-change timeout, s (default 10) / scan listen "
             "time, s (default 1)"},
            None,
        ),
        (("--json",), {"action": "store_true", "help": "print one JSON document"}, False),
    ]


_TOP = "top_"  # dest prefix of the options given before the sub-command


def _add_bus_options(p: argparse.ArgumentParser, prefix: str = "", omit: tuple = ()) -> None:
    """The bus options on ``p`` with ``SUPPRESS`` defaults (an option not given leaves no
    attribute, so the sub-command level cannot overwrite what was given before it); ``omit``:
    attribute names left out (see :func:`_bus_option_before_only`)."""
    g = p.add_argument_group("bus (unset = python-can config / CAN_* environment)")
    for flags, kw, _default in _bus_options():
        if flags[0].lstrip("-").replace("-", "_") in omit:
            continue
        dest = prefix + flags[0].lstrip("-").replace("-", "_")
        if kw.get("action") != "store_true":
            kw = {**kw, "metavar": flags[0].lstrip("-").replace("-", "_").upper()}
        g.add_argument(*flags, dest=dest, default=argparse.SUPPRESS, **kw)
    add_hidden_aliases(g, prefix + "node")  # -n/--node-id


def _bus_parent(omit: tuple = ()) -> _Parser:
    p = _Parser(add_help=False)
    _add_bus_options(p, omit=omit)
    return p


def _bus_option_before_only(p: argparse.ArgumentParser, name: str, own: str) -> None:
    """Refuse bus option ``name`` after a sub-command whose own option ``own`` starts with its
    spelling (``trace --channel i_p``, a typo of ``--channels``, must not pick a bus channel):
    there it is a usage error naming both; before the sub-command it is the bus option."""
    flags = next(f for f, _kw, _d in _bus_options() if f[0] == f"--{name}")

    class _BeforeOnly(argparse.Action):
        def __call__(
            self, parser: Any, namespace: Any, values: Any, option_string: Any = None
        ) -> None:
            parser.error(
                f"{option_string} is a bus option: give it before the sub-command "
                f"(drive-link {flags[0]} VALUE {parser.prog.split()[-1]} ...); did you mean {own}?"
            )

    p.add_argument(
        *flags, action=_BeforeOnly, dest=argparse.SUPPRESS, default=argparse.SUPPRESS,
        help=argparse.SUPPRESS,
    )  # fmt: skip


def _merge_bus(args: argparse.Namespace) -> None:
    """Bus options from both sides of the sub-command: the one after it wins; a sub-command
    that defines an option itself with a plain default (e.g. ``design --json``) takes the value
    given before it when its own is still the default; unset options get their defaults."""
    for flags, _kw, default in _bus_options():
        dest = flags[0].lstrip("-").replace("-", "_")
        top = getattr(args, _TOP + dest, argparse.SUPPRESS)
        if hasattr(args, _TOP + dest):
            delattr(args, _TOP + dest)
        mine = getattr(args, dest, argparse.SUPPRESS)
        if top is not argparse.SUPPRESS and (mine is argparse.SUPPRESS or mine == default):
            setattr(args, dest, top)
        elif mine is argparse.SUPPRESS:
            setattr(args, dest, default)


def _outputs(p: argparse.ArgumentParser) -> None:
    p.add_argument("--csv", type=Path, help="save CSV here (t in s, one column per signal)")
    p.add_argument("--png", type=Path, help="save a plot here (PNG, matplotlib)")


_EPILOG = """\
values take units (20uH, 50A, 1000rpm, '-5 A'); a bare number is in the object's unit
(drive-link objects PATTERN lists names, index:sub, type, unit, limits, access).

exit codes: 1 drive refused / failed check, 2 usage, 3 bus error, 4 node not found (scan:
none), 5 timeout, 6 SDO abort, 7 invalid value (wrong unit, not a number, out of limits, unknown
object), 8 unsafe gains refused (use --force), 130 interrupted, 141 output pipe closed.
"""


# --------------------------------------------------------------------------- failures
#: SDO abort "not in the present device state" (CiA 301): the drive refuses the write now.
_ABORT_STATE = abort_codes.DEVICE_STATE


#: The trace recorder's objects: refused while a recording is armed.
_TRACE_OBJECTS = ("trace_config", "trace_channels", "trace_data")


def _state_hint(exc: SdoAbort) -> str:
    """The fix for an object the drive refused in its present state (abort 0x08000022)."""
    from ..link._objects import default_table

    table = default_table()
    obj = table.by_index(exc.index, exc.subindex)
    if obj is not None and obj.name == "modes_of_operation":
        return "the mode changes only with the power stage off: run `drive-link disable` first"
    if obj is not None and obj.entry.config_only:
        return "this object is written only with the power stage off: `drive-link disable` first"
    if exc.index in PDO_PARAMETERS:
        return "PDO settings change only in PRE-OPERATIONAL: `drive-link nmt pre-operational` first"
    if obj is not None and obj.entry.object_name in _TRACE_OBJECTS:
        return "a trace recording is armed: wait for it (or `drive-link trace`) before changing it"
    return "the drive does not accept it in its present state (see `drive-link status`)"


def _fail(args: argparse.Namespace | None, message: str, code: int, prefix: str = "error: ") -> int:
    """Report one failure: one line on stderr, or JSON on stdout with ``--json``."""
    if _JSON_ERRORS or (args is not None and getattr(args, "json", False)):
        print(json.dumps({"error": message, "exit_code": code}))
    else:
        print(f"drive-link: {prefix}{message}", file=sys.stderr)
    return code
