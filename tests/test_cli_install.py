"""What a new user meets first: the plain install, the README's commands, the help texts, the
console scripts, and a dashboard told to join a hub that is not there.

Oracles: the installed distribution's metadata (importlib.metadata), the README text itself,
argparse's own view of every option, and the real console scripts next to sys.executable."""

from __future__ import annotations

import importlib.metadata
import re
import shlex
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from drive_link import cli

pytestmark = pytest.mark.timeout(120)

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent


@pytest.mark.unit
def test_plain_install_has_what_the_readme_shows():
    """`pip install -e .` (no extras) brings the PNG writer and the units library."""
    req = importlib.metadata.requires("bldc-bench") or []
    plain = {re.split(r"[ <>=!;\[]", r, maxsplit=1)[0].lower() for r in req if "extra ==" not in r}
    assert {"matplotlib", "pint"} <= plain
    readme = (ROOT / "README.md").read_text()
    for name in ("matplotlib", "pint"):  # each runtime dependency has its "why" row
        assert re.search(rf"^\| {name} \|", readme, re.M), name


def _readme_block(title: str) -> list[str]:
    readme = (ROOT / "README.md").read_text()
    section = readme.split(f"## {title}\n", 1)[1]
    block = section.split("```sh\n", 1)[1].split("```", 1)[0]
    return [ln.split("  #", 1)[0].strip() for ln in block.splitlines() if ln.strip()]


@pytest.mark.unit
def test_readme_drive_link_commands_parse_in_order():
    """Every `drive-link` line of the README's session parses (the venv is activated first)."""
    lines = _readme_block("Using drive-link")
    assert lines[0].startswith(". .venv/bin/activate")
    cmds = [c.strip() for ln in lines for c in ln.split("&&") if c.strip().startswith("drive-link")]
    assert len(cmds) >= 10
    ap = cli.build_parser()
    for c in cmds:
        argv = shlex.split(c)[1:]
        args = ap.parse_args(argv)
        assert callable(args.func), c


@pytest.mark.unit
def test_help_has_no_markup_and_every_option_says_what_it_is():
    ap = cli.build_parser()
    top = ap.format_help()
    assert "``" not in top and ":func:" not in top and "exit codes" in top
    sub = next(a for a in ap._actions if a.dest == "cmd")
    missing = []
    for name, p in sub.choices.items():
        if name in ("design", "identify"):  # drive_link.cli.design's offline commands
            continue
        for a in p._actions:
            if a.option_strings and a.dest != "help" and not a.help:
                missing.append(f"{name} {a.option_strings[0]}")
    assert not missing, missing
    # the options issue 12 named carry their unit
    want = {
        ("identify-drive", "--settle"): " s",
        ("identify-drive", "--omega-n"): "rad/s",
        ("step", "--divider"): "20 µs",
        ("step", "--model-b"): "rpm/A",
        ("trace", "--level"): "unit",
        ("trace", "--pre-trigger"): "samples",
        ("live", "--seconds"): " s",
    }
    for (cmd, opt), unit in want.items():
        act = next(a for a in sub.choices[cmd]._actions if opt in a.option_strings)
        assert unit in act.help, (cmd, opt, act.help)


def test_console_script_runs_from_the_venv():
    exe = BIN / "drive-link"
    assert exe.exists(), f"console script missing next to {sys.executable}"
    p = subprocess.run(
        [str(exe), "objects", "0x60FF", "--json"], capture_output=True, text=True, timeout=60
    )
    assert p.returncode == 0, p.stderr
    assert '"unit": "rpm"' in p.stdout and '"index": "0x60FF:00"' in p.stdout


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_dashboard_join_hub_with_nothing_there_is_one_line():
    exe = BIN / "drive-dashboard"
    port = _free_port()
    p = subprocess.run(
        [str(exe), "--join-hub", str(port), "--port", str(_free_port()), "--gui-port", "0"],
        capture_output=True,
        text=True,
        timeout=90,
    )
    assert p.returncode != 0
    assert "Traceback" not in p.stderr and p.stderr.count("\n") == 1, p.stderr
    assert f"no hub at 127.0.0.1:{port}" in p.stderr
