"""``drive-dashboard --virtual`` runs the virtual drive as a child process by default and stops
it on every exit path: Ctrl-C (SIGINT), SIGTERM, and an error while the bench opens."""

from __future__ import annotations

import re
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from dashboard.browser import free_port, stop_process
from dashboard.config import BenchConfig

pytestmark = pytest.mark.timeout(90)


def children(pid: int) -> list[int]:
    """PIDs of the direct children of ``pid`` (Linux /proc)."""
    out: list[int] = []
    for task in Path(f"/proc/{pid}/task").iterdir():
        out += [int(c) for c in (task / "children").read_text().split()]
    return out


def alive(pid: int) -> bool:
    """True while ``pid`` exists and is not a zombie."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except FileNotFoundError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"


def cmdline(pid: int) -> str:
    return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["ctrl-c", "sigterm"])
def test_virtual_drive_child_stops_with_the_dashboard(sig):
    cmd = [sys.executable, "-m", "dashboard.cli", "--virtual", "--no-3d"]
    cmd += ["--port", str(free_port()), "--gui-port", "0"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        lines = [proc.stdout.readline(), proc.stdout.readline()]
        assert re.match(r"open http://127\.0\.0\.1:\d+/", lines[0]), lines
        assert "virtual drive, subprocess" in lines[1]
        kids = [k for k in children(proc.pid) if "virtual_drive" in cmdline(k)]
        assert len(kids) == 1, [cmdline(k) for k in children(proc.pid)]
        assert "run" in cmdline(kids[0]).split()
        proc.send_signal(sig)  # to the dashboard only, not to its process group
        # uvicorn re-raises SIGTERM after its graceful shutdown (exit status -15)
        assert proc.wait(timeout=30) in (0, -sig), proc.stderr.read()
        # already reaped by the dashboard (not left to the child's own parent watch)
        assert not alive(kids[0]), "the virtual drive outlived drive-dashboard"
    finally:
        stop_process(proc)


def test_child_stopped_when_opening_the_bench_fails(monkeypatch):
    """An error after the child started (here: the host library cannot connect) stops it."""
    import drive_link
    import virtual_drive.node.process as vp
    from dashboard._virtual import open_bench

    started = []
    real_spawn = vp.spawn_virtual_drive

    def spawn(*args, **kwargs):
        started.append(real_spawn(*args, **kwargs))
        return started[-1]

    def refuse(*args, **kwargs):
        raise OSError("no route to the bus")

    monkeypatch.setattr(vp, "spawn_virtual_drive", spawn)
    monkeypatch.setattr(drive_link.Drive, "connect", refuse)
    with pytest.raises(OSError, match="no route"):
        with open_bench(BenchConfig(virtual=True)):
            pass
    assert len(started) == 1
    assert started[0].proc.poll() is not None, "the virtual drive was left running"
    assert started[0].proc.returncode == 0  # SIGTERM was enough: it shut down cleanly


def test_in_process_drive_is_opt_in():
    """--virtual-in-process keeps the drive in this process: no child, the bench still works."""
    import os

    from dashboard._virtual import open_bench

    before = set(children(os.getpid()))
    with open_bench(BenchConfig(virtual=True, virtual_in_process=True)) as bench:
        assert "virtual drive, in-process" in bench.description
        assert set(children(os.getpid())) == before
        assert bench.drive.nmt_state == "OPERATIONAL"


@pytest.mark.unit
def test_cli_refuses_both_virtual_placements(capsys):
    from dashboard.cli import main

    assert main(["--virtual", "--virtual-in-process", "--virtual-subprocess"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "exclude each other" in err
