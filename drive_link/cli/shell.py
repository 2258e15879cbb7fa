"""``drive-link shell``: the ``drive-link`` commands in one interactive session.

One :class:`~drive_link.link.drive.Drive` stays open for the whole session (one bus connection, one
supervision: the host heartbeat runs and the drive's heartbeat consumer watches it unless
``--no-heartbeat``), and every line is run through the same argparse sub-parsers and handlers as
the one-shot command (``read statusword`` = ``drive-link read statusword``), on that Drive.

On a terminal: readline history (``~/.drive_link_history``) and TAB completion of commands,
options and object names (from the drive's object table). From a pipe or file: one command per
line, no prompt, ``#`` comments; the exit code is the last command's. A failing command prints
one line on stderr and the session goes on; Ctrl-C stops the running command, not the shell;
``exit`` (optionally with a code) or Ctrl-D ends it.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import shlex
import sys
from collections.abc import Iterable
from pathlib import Path
from typing import TextIO

from ..errors import DriveError, InvalidValue, SdoAbort
from ..link.drive import Drive
from . import _common
from ._common import _ABORT_STATE, EXIT_CODES, EXIT_UNSAFE, Refused, _merge_bus, _state_hint
from .experiments import apply_step_defaults
from .main import build_parser
from .tools import bus_settings

__all__ = ["HISTORY_FILE", "Shell", "cmd_shell"]

#: Default history file (only read and written on an interactive terminal).
HISTORY_FILE = Path("~/.drive_link_history")
HISTORY_LENGTH = 2000
#: Words the shell handles itself.
BUILTINS = ("help", "exit", "quit")
#: Bus options that do not name the connection (a line may give its own); every other bus
#: option (interface, channel, bitrate, host, port, node …) must be the shell's.
_PER_LINE_OPTS = ("sdo_timeout", "timeout", "json")
#: Commands that make no sense inside a shell.
_NOT_IN_SHELL = {"shell": "already in a shell"}
#: Positional argument names that take an object name (completion offers the OD's names).
_OBJECT_DESTS = {"name", "names", "pattern", "objects", "object"}


class _ParseExitError(Exception):
    """argparse wanted to exit (usage error or --help) with this code."""

    def __init__(self, code: int):
        super().__init__(code)
        self.code = code


def _defaults() -> dict[str, object]:
    return {f[0].lstrip("-").replace("-", "_"): d for f, _kw, d in _common._bus_options()}


class Shell:
    """Runs drive-link command lines on one open drive.

    ``args``: the ``shell`` command's own parsed arguments (bus options, --json …): a line
    inherits them unless it gives its own; it may not name another bus or node.
    """

    def __init__(self, drive: Drive, args: argparse.Namespace):
        self.drive = drive
        self.args = args
        self.parser = build_parser()
        self.sub: argparse._SubParsersAction[argparse.ArgumentParser] = next(
            a for a in self.parser._actions if isinstance(a, argparse._SubParsersAction)
        )
        self.last_rc = 0

    # ------------------------------------------------------------------ commands
    @property
    def commands(self) -> list[str]:
        """Every command a line may start with."""
        names = [n for n in self.sub.choices if n not in _NOT_IN_SHELL]
        return sorted(names) + list(BUILTINS)

    def help_text(self, topic: str | None = None) -> str:
        """``help``: the commands with their one-line help; ``help CMD``: its full help."""
        if topic:
            p = self.sub.choices.get(topic)
            if p is None or topic in _NOT_IN_SHELL:
                raise InvalidValue(f"no command {topic!r} (try: help)")
            return p.format_help().rstrip()
        helps = {a.dest: a.help or "" for a in self.sub._choices_actions}
        lines = ["commands (drive-link COMMAND without the prefix; CMD --help for options):"]
        for n in self.commands:
            if n in BUILTINS:
                continue
            text = helps.get(n, "")
            if len(text) > 62:  # one line each: the first part (help CMD has the rest)
                text = text[:61].rsplit(" ", 1)[0] + " …"
            lines.append(f"  {n:<16} {text}")
        lines += [
            "  help [CMD]       this list / one command's options",
            "  exit [CODE]      end the session (also quit, Ctrl-D)",
        ]
        return "\n".join(lines)

    def _parse(self, argv: list[str]) -> argparse.Namespace:
        """Parse ``argv`` with the one-shot parser (argparse exits: :class:`_ParseExitError`)."""
        try:
            args = self.parser.parse_args(argv)
        except SystemExit as exc:
            raise _ParseExitError(int(exc.code or 0)) from None
        _merge_bus(args)
        defaults = _defaults()
        for k, default in defaults.items():
            mine = getattr(self.args, k, default)
            given = getattr(args, k, default)
            if k not in _PER_LINE_OPTS:
                if given != default and given != mine:
                    raise InvalidValue(
                        f"--{k.replace('_', '-')} {given}: this shell is connected to node "
                        f"{self.drive.node_id} on its own bus; start another shell for another"
                    )
                setattr(args, k, mine)
            elif given == default:
                setattr(args, k, mine)
        apply_step_defaults(args)
        return args

    def run_line(self, line: str) -> int | None:
        """Run one line; returns its exit code (``None`` = end the session)."""
        try:
            argv = shlex.split(line, comments=True)
        except ValueError as exc:
            return self._fail(None, f"error: cannot split the line: {exc}", 2)
        if not argv:
            return self.last_rc
        cmd = argv[0]
        if cmd in ("exit", "quit"):
            if len(argv) > 1:
                try:
                    self.last_rc = int(argv[1])
                except ValueError:
                    return self._fail(None, f"error: exit code {argv[1]!r} is not a number", 2)
            return None
        if cmd == "help" or cmd == "?":
            try:
                print(self.help_text(argv[1] if len(argv) > 1 else None), flush=True)
            except DriveError as exc:
                return self._fail(None, f"error: {exc}", 2)
            self.last_rc = 0
            return 0
        if cmd in _NOT_IN_SHELL:
            return self._fail(None, f"error: {cmd}: {_NOT_IN_SHELL[cmd]}", 2)
        if cmd not in self.sub.choices:
            close = [c for c in self.commands if c.startswith(cmd[:3])]
            hint = f" (did you mean {', '.join(close[:4])}?)" if close else " (try: help)"
            return self._fail(None, f"error: unknown command {cmd!r}{hint}", 2)
        json_before = _common._JSON_ERRORS
        _common._JSON_ERRORS = json_before or "--json" in argv  # argparse errors as JSON too
        try:
            return self._run_args(argv)
        finally:
            _common._JSON_ERRORS = json_before

    def _run_args(self, argv: list[str]) -> int:
        """Parse and run one command on the shell's Drive; errors as cli.main reports them."""
        args: argparse.Namespace | None = None
        try:
            args = self._parse(argv)
            if getattr(args, "needs_drive", False):
                rc = args.func(args, self.drive)
            else:
                rc = args.func(args)
        except _ParseExitError as exc:
            rc = exc.code
        except Refused as exc:
            rc = self._fail(args, str(exc), EXIT_UNSAFE)
        except DriveError as exc:
            msg = f"error: {exc}"
            if isinstance(exc, SdoAbort) and exc.code == _ABORT_STATE:
                msg += f": {_state_hint(exc)}"
            code = next((c for cls, c in EXIT_CODES if isinstance(exc, cls)), 1)
            rc = self._fail(args, msg, code)
        except KeyboardInterrupt:
            rc = self._fail(args, "interrupted", 130)
        except (ValueError, OSError) as exc:
            rc = self._fail(args, f"error: {exc}", 1)
        except SystemExit as exc:  # a handler that exits
            rc = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
        sys.stdout.flush()
        self.last_rc = int(rc or 0)
        return self.last_rc

    def _fail(self, args: argparse.Namespace | None, message: str, code: int) -> int:
        """One failure as cli.main reports it: ``drive-link: MESSAGE`` on stderr, or with
        --json ``{"error": …, "exit_code": …}`` on stdout."""
        line = message.splitlines()[0] if message else message
        as_json = _common._JSON_ERRORS or bool(getattr(args, "json", False))
        if as_json:
            print(json.dumps({"error": line.removeprefix("error: "), "exit_code": code}))
        else:
            print(f"drive-link: {line}", file=sys.stderr)
        sys.stdout.flush()
        sys.stderr.flush()
        self.last_rc = code
        return code

    def run(self, lines: Iterable[str]) -> int:
        """Run ``lines`` until one says exit; returns the last command's exit code."""
        for line in lines:
            if self.run_line(line) is None:
                break
        return self.last_rc

    # ------------------------------------------------------------------ completion
    def candidates(self, before: str) -> list[str]:
        """Completions of the last word of ``before`` (the line up to the cursor)."""
        try:
            words = shlex.split(before)
        except ValueError:
            words = before.split()
        text = "" if not before or before[-1].isspace() else (words.pop() if words else "")
        if not words:
            pool = self.commands
        elif words[0] == "help":
            pool = self.commands if len(words) == 1 else []
        else:
            p = self.sub.choices.get(words[0])
            if p is None:
                return []
            if text.startswith("-"):
                pool = sorted({s for a in p._actions for s in a.option_strings})
            else:
                pool = self._positional_pool(p, words[1:])
        return sorted(c for c in pool if c.startswith(text))

    def _positional_pool(self, p: argparse.ArgumentParser, done: list[str]) -> list[str]:
        """Choices of the positional argument being typed after ``done`` (words so far)."""
        takes_value = {
            s for a in p._actions if a.option_strings and a.nargs != 0 for s in a.option_strings
        }
        if done and done[-1] in takes_value:
            action = next(a for a in p._actions if done[-1] in a.option_strings)
            return [str(c) for c in action.choices] if action.choices else []
        skip = False
        n_pos = 0
        for w in done:
            if skip:
                skip = False
            elif w in takes_value:
                skip = True
            elif not w.startswith("-"):
                n_pos += 1
        positionals = [a for a in p._actions if not a.option_strings]
        for i, a in enumerate(positionals):
            many = a.nargs in ("+", "*", argparse.REMAINDER)
            if i == n_pos or (many and i <= n_pos and i == len(positionals) - 1):
                if a.choices:
                    return [str(c) for c in a.choices]
                if a.dest in _OBJECT_DESTS:
                    return self.drive.table.names()
                return []
        return []


def _readline_lines(shell: Shell, history: Path, prompt: str) -> Iterable[str]:
    """Lines typed at the terminal, with readline history and completion."""
    import readline

    readline.set_completer_delims(" \t\n")
    matches: list[str] = []

    def complete(text: str, state: int) -> str | None:
        nonlocal matches
        if state == 0:
            buf = readline.get_line_buffer()[: readline.get_endidx()]
            matches = shell.candidates(buf)
            if len(matches) == 1:  # a whole word: go on typing the next one
                matches = [matches[0] + " "]
        return matches[state] if state < len(matches) else None

    readline.set_completer(complete)
    if "libedit" in (readline.__doc__ or ""):
        readline.parse_and_bind("bind ^I rl_complete")
    else:
        readline.parse_and_bind("tab: complete")
    readline.set_history_length(HISTORY_LENGTH)
    with contextlib.suppress(OSError):
        readline.read_history_file(history)
    try:
        while True:
            try:
                yield input(prompt)
            except KeyboardInterrupt:  # Ctrl-C at the prompt: a fresh line, like a shell
                print()
                continue
            except EOFError:  # Ctrl-D
                print()
                return
    finally:
        with contextlib.suppress(OSError):
            history.parent.mkdir(parents=True, exist_ok=True)
            readline.write_history_file(history)


def _stream_lines(stream: TextIO) -> Iterable[str]:
    """Lines from a pipe or file."""
    for line in stream:
        yield line.rstrip("\n")


def connect_session(args: argparse.Namespace) -> Drive:
    """The shell's Drive: cli's bus options, with the host heartbeat (100 ms) and the drive's
    consumer set (so a dead shell stops the motor) unless ``--no-heartbeat``."""
    sdo_timeout = getattr(args, "sdo_timeout", None)
    d = Drive.connect(
        **bus_settings(args),
        node_id=args.node,
        heartbeat_ms=None if args.no_heartbeat else 100,
        **({} if sdo_timeout is None else {"sdo_timeout": sdo_timeout}),
    )
    if not args.no_heartbeat:
        try:
            d.configure_heartbeat_consumer()
        except BaseException:
            d.close()
            raise
    return d


def cmd_shell(args: argparse.Namespace) -> int:
    """``drive-link shell`` (see the module docstring)."""
    d = connect_session(args)
    try:
        shell = Shell(d, args)
        if sys.stdin.isatty():
            history = Path(args.history or os.environ.get("DRIVE_LINK_HISTORY") or HISTORY_FILE)
            print(
                f"drive-link shell: node {d.node_id}, {d.state}; "
                "TAB completes, 'help' lists the commands, Ctrl-D ends",
                flush=True,
            )
            lines = _readline_lines(shell, history.expanduser(), f"drive-link[{d.node_id}]> ")
        else:
            lines = _stream_lines(sys.stdin)
        return shell.run(lines)
    finally:
        d.close()
