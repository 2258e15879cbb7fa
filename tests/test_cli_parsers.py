"""Every argument parser of the project spells its options in full (issue 23).

argparse's own view is the oracle: each command line's parser is taken at the moment its
``main`` hands it the arguments (``parse_known_args`` is observed, the program goes no further),
then every sub-parser under it is walked. No parser may accept an abbreviation
(``allow_abbrev`` off), and no ``drive-link`` sub-command may have an option that starts with
the spelling of a bus option it also takes after the sub-command (``trace --channel i_p``, a
typo of ``--channels``, once picked a bus channel instead).
"""

from __future__ import annotations

import argparse
import importlib.metadata
import runpy
import sys
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

pytestmark = pytest.mark.unit

ROOT = Path(__file__).resolve().parents[1]
#: ``python -m`` commands and scripts with a command line (each has a ``__main__`` block).
MODULES = ("virtual_drive.bench", "firmware_protocol.generate", "dashboard.screenshot")
SCRIPTS = [*sorted((ROOT / "benchmarks").glob("bench_*.py")), ROOT / "tests/uml/runner.py"]


class _Taken(Exception):  # noqa: N818
    """Raised instead of parsing: the parser has been taken."""


def _parser_of(run: Callable[[], object], monkeypatch: pytest.MonkeyPatch):
    """The first parser that ``run()`` asks to parse its command line."""
    taken: list[argparse.ArgumentParser] = []

    def take(self: argparse.ArgumentParser, args=None, namespace=None):
        taken.append(self)
        raise _Taken

    with monkeypatch.context() as m:
        m.setattr(argparse.ArgumentParser, "parse_known_args", take)
        with pytest.raises(_Taken):
            run()
    return taken[0]


def _walk(p: argparse.ArgumentParser, name: str) -> Iterator[tuple[str, argparse.ArgumentParser]]:
    yield name, p
    for a in p._actions:
        if isinstance(a, argparse._SubParsersAction):
            for sub_name, sp in a.choices.items():
                yield from _walk(sp, f"{name} {sub_name}")


def _console_scripts() -> list[importlib.metadata.EntryPoint]:
    eps = importlib.metadata.entry_points(group="console_scripts")
    return sorted((e for e in eps if e.value.split(".")[0] in
                   ("drive_link", "virtual_drive", "dashboard", "firmware_protocol")),
                  key=lambda e: e.name)  # fmt: skip


def _all_parsers(monkeypatch) -> list[tuple[str, argparse.ArgumentParser]]:
    out = []
    for ep in _console_scripts():
        main = ep.load()
        out += _walk(_parser_of(lambda main=main: main(["--help"]), monkeypatch), ep.name)
    for mod in MODULES:
        monkeypatch.setattr(sys, "argv", [mod, "--help"])
        run = lambda mod=mod: runpy.run_module(mod, run_name="__main__")  # noqa: E731
        out += _walk(_parser_of(run, monkeypatch), f"python -m {mod}")
    for path in SCRIPTS:
        monkeypatch.setattr(sys, "argv", [str(path), "--help"])
        monkeypatch.syspath_prepend(str(path.parent))  # benchmarks import their sibling helper
        run = lambda path=path: runpy.run_path(str(path), run_name="__main__")  # noqa: E731
        out += _walk(_parser_of(run, monkeypatch), str(path.relative_to(ROOT)))
    return out


def test_no_parser_or_sub_parser_accepts_an_abbreviation(monkeypatch):
    # the installed console scripts, as the README names them, are all walked
    scripts = [e.name for e in _console_scripts()]
    assert scripts == ["drive-dashboard", "drive-link", "virtual-drive"]
    parsers = _all_parsers(monkeypatch)
    names = [n for n, _ in parsers]
    # the walk reached the sub-commands (drive-link's design/trace, virtual-drive's run/hub)
    assert {"drive-link design", "drive-link trace", "drive-link shell", "virtual-drive run",
            "virtual-drive hub", "drive-dashboard"} <= set(names)  # fmt: skip
    assert len(parsers) >= 3 + 30 + len(MODULES) + len(SCRIPTS)
    abbreviating = [n for n, p in parsers if p.allow_abbrev]
    assert not abbreviating, abbreviating


def test_no_sub_command_option_extends_a_bus_option_it_takes_after_the_sub_command():
    from drive_link import cli

    top = cli.build_parser()
    bus = {s for a in top._actions for s in a.option_strings if a.dest.startswith("top_")}
    clashes = []
    for name, p in _walk(top, "drive-link"):
        if p is top:
            continue
        own = p._option_string_actions
        for b in bus & own.keys():
            for s, a in own.items():
                if s != b and s.startswith(b) and a is not own[b] and a.dest != own[b].dest:
                    if own[b].help is argparse.SUPPRESS and own[b].dest == argparse.SUPPRESS:
                        continue  # the bus option is refused there (a guard that names both)
                    clashes.append(f"{name}: {b} / {s}")
    assert not clashes, clashes


def test_the_bus_channel_after_trace_is_refused_and_before_it_is_taken():
    from drive_link import cli

    ap = cli.build_parser()
    with pytest.raises(SystemExit) as exc:
        ap.parse_args(["trace", "--channel", "i_p"])
    assert exc.value.code == 2
    args = ap.parse_args(["--channel", "vcan3", "trace", "--channels", "i_p,speed"])
    cli._merge_bus(args)
    assert (args.channel, args.channels) == ("vcan3", "i_p,speed")
