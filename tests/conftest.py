"""Shared test helpers.

:class:`RunQueueProbe`: what the machine delivered to a process during a measurement window,
read from the kernel's scheduler statistics (``/proc/PID/task/*/schedstat``: time on a CPU and
time spent runnable but waiting for one). A test that asserts the rate of something driven by
the virtual drive's 1 ms loop (TPDOs at 1 kHz) bounds it by :func:`min_rate`: the full rate on an
idle machine, less in proportion to the time the kernel kept the drive's threads waiting. So the
test holds on a busy host (load 5–25 on 2 cores) and still fails when the product itself is slow
(e.g. an event timer at half rate on an idle machine).
"""

from __future__ import annotations

import os
import re
import time
from pathlib import Path

import canopen
import pytest

from virtual_drive import VirtualDrive

# The tests' canopen masters wake their bus reader every 0.1 s, as drive_link's own does
# (_connection.py): with canopen's default 1 s, every Network.disconnect() waited up to 1 s
# for the reader to notice, about 1 s per test that closes a master.
canopen.Network.NOTIFIER_CYCLE = 0.1
# and the in-process virtual drives stop within 0.05 s instead of 0.2 s (hundreds of them)
VirtualDrive.NOTIFIER_CYCLE = 0.05


def _schedstat(pid: int) -> dict[str, tuple[int, int]]:
    """Thread id → (ns on a CPU, ns waiting on a run queue) of the threads of ``pid`` (empty if
    the kernel has no schedstat)."""
    out: dict[str, tuple[int, int]] = {}
    try:
        tasks = list(Path(f"/proc/{pid}/task").iterdir())
    except OSError:
        return out
    for t in tasks:
        times = _task_schedstat(t)
        if times is not None:  # else: thread gone
            out[t.name] = times
    return out


def _task_schedstat(task: Path) -> tuple[int, int] | None:
    """(ns on a CPU, ns waiting on a run queue) of one /proc/<pid>/task/<tid>; None if gone."""
    try:
        fields = (task / "schedstat").read_text().split()
    except OSError:
        return None
    return int(fields[0]), int(fields[1])


def main_thread_times(pid: int) -> tuple[float, float]:
    """(s on a CPU, s waiting on a run queue) of the main thread of ``pid``; (0, 0) if gone."""
    times = _task_schedstat(Path(f"/proc/{pid}/task/{pid}"))
    return (0.0, 0.0) if times is None else (times[0] / 1e9, times[1] / 1e9)


def _delta(a: dict[str, tuple[int, int]], b: dict[str, tuple[int, int]]) -> tuple[float, float]:
    """(s on a CPU, s waiting) between two readings; a thread that started meanwhile counts
    from zero, one that ended is left out (its totals left with it: summing the totals of
    whatever threads exist gave a negative wait in the busy full run)."""
    cpu = wait = 0
    for tid, (c1, w1) in b.items():
        c0, w0 = a.get(tid, (0, 0))
        cpu += max(0, c1 - c0)
        wait += max(0, w1 - w0)
    return cpu / 1e9, wait / 1e9


class RunQueueProbe:
    """``p = RunQueueProbe(pid)`` … ``p.stop()`` → run-queue wait of ``pid``'s threads over the
    window, in seconds per second (0 = never kept waiting; may exceed 1 with several threads)."""

    def __init__(self, pid: int | None = None) -> None:
        self.pid = os.getpid() if pid is None else pid
        self._t0 = time.monotonic()
        self._start = _schedstat(self.pid)
        self.cpu = self.wait = self.waited = 0.0

    def stop(self) -> float:
        dt = max(time.monotonic() - self._t0, 1e-9)
        cpu, self.waited = _delta(self._start, _schedstat(self.pid))
        self.cpu, self.wait = cpu / dt, self.waited / dt
        return self.wait

    def __repr__(self) -> str:
        return f"run-queue wait {self.wait:.2f} s/s, CPU {self.cpu:.2f} s/s (pid {self.pid})"


class HostDelay:
    """What the host, not the product, added to a wait: the run-queue time of the processes
    that must act (a dashboard, a browser's renderers, a drive), each counted at most once per
    second of the window (a process with several threads waiting at once is late by the
    longest wait, not their sum). ``HostDelay(*pids)`` at the start, ``allowance()`` (s) at
    the end."""

    def __init__(self, *pids: int) -> None:
        self.probes = [RunQueueProbe(p) for p in pids]
        self.t0 = time.monotonic()

    def allowance(self) -> float:
        window = time.monotonic() - self.t0
        return sum(window * min(1.0, p.stop()) for p in self.probes)

    def __repr__(self) -> str:
        return "; ".join(repr(p) for p in self.probes)


#: Plot refreshes/s of the benches most browser tests open (``drive-dashboard --plot-rate``):
#: they test what the page does, not how smooth its plots are, and each open page costs CPU in
#: proportion (benchmarks/bench_dashboard.py --plot-rate: see the README's dashboard options).
#: tests/test_dashboard_e2e.py, tests/test_dashboard_freshness.py and
#: tests/test_dashboard_browsers.py (the live plot, its staleness, a starved page's pace) and the
#: README's sessions run at the default.
TEST_PLOT_RATE_HZ = 6.0
PLOT_RATE_ARGS = ["--plot-rate", repr(TEST_PLOT_RATE_HZ)]


@pytest.fixture(scope="module")
def hub_drive(tmp_path_factory):
    """A loopback hub in this process with a ``virtual-drive run`` child on it (node 1, its own
    parameter file), started by the product's launcher; yields the
    :class:`~virtual_drive.hub.Hub` (``.port``, ``.stats``)."""
    from virtual_drive.launch import virtual_bench

    with virtual_bench(nodes=(1,), store_dir=tmp_path_factory.mktemp("store")) as bus:
        yield bus.hub


def cia402_state(sw: int) -> str:
    """CiA 402-2 table 30 (statusword bits 0-3, 5, 6)."""
    if sw & 0x4F == 0x00:
        return "NOT READY TO SWITCH ON"
    if sw & 0x4F == 0x40:
        return "SWITCH ON DISABLED"
    if sw & 0x4F == 0x0F:
        return "FAULT REACTION ACTIVE"
    if sw & 0x4F == 0x08:
        return "FAULT"
    return {0x21: "READY TO SWITCH ON", 0x23: "SWITCHED ON", 0x27: "OPERATION ENABLED",
            0x07: "QUICK STOP ACTIVE"}.get(sw & 0x6F, f"? {sw:#06x}")


def recv_frames(bus, n: int, timeout: float = 10.0) -> list:
    """Up to ``n`` frames (``can.Message``) from python-can ``bus`` within ``timeout`` s."""
    out: list = []
    end = time.monotonic() + timeout
    while len(out) < n and time.monotonic() < end:
        msg = bus.recv(0.5)
        if msg is not None:
            out.append(msg)
    return out


def min_rate(nominal_hz: float, wait: float, margin: float = 0.9) -> float:
    """Lowest acceptable rate of a ``nominal_hz`` stream from a process kept waiting ``wait``
    s/s by the kernel: ``margin × nominal × (1 − wait)`` (Hz)."""
    return margin * nominal_hz * max(0.0, 1.0 - wait)


def heartbeat_explained(detail: str, wait: float) -> bool:
    """True when a failed ``check`` heartbeat item (``"heartbeat period M ms, expected P ms"``)
    is explained by a run-queue wait of ``wait`` s/s: the heartbeat rate 1/M is at least
    :func:`min_rate` of 1/P with margin 0.9 (an idle host explains nothing the check's own
    25 % tolerance did not already accept)."""
    m = re.fullmatch(r"heartbeat period ([\d.]+) ms, expected (\d+) ms", detail)
    return m is not None and 1000.0 / float(m[1]) >= min_rate(1000.0 / int(m[2]), wait, 0.9)


# --------------------------------------------------------------------------------------------
# The ``unit`` marker cannot lie: a unit test that opens a socket or starts a process fails
# --------------------------------------------------------------------------------------------


def _refuse(what: str):
    def refuse(*args, **kwargs):
        raise AssertionError(
            f"a test marked 'unit' must not {what} (pytest.mark.unit: no process, "
            "socket or browser)"
        )

    return refuse


@pytest.hookimpl(wrapper=True)
def pytest_runtest_protocol(item, nextitem):
    """While a ``unit`` test runs (its fixtures included), connecting or binding a socket and
    starting a process raise. ``UNIT_GUARD_ALL=1`` guards every test (to find candidates)."""
    if item.get_closest_marker("unit") is None and not os.environ.get("UNIT_GUARD_ALL"):
        return (yield)
    import socket
    import subprocess

    mp = pytest.MonkeyPatch()
    for name in ("connect", "connect_ex", "bind"):
        mp.setattr(socket.socket, name, _refuse(f"{name} a socket"))
    mp.setattr(subprocess.Popen, "__init__", _refuse("start a process"))
    for name in ("fork", "posix_spawn", "posix_spawnp", "execv", "execve"):
        mp.setattr(os, name, _refuse(f"call os.{name}"))
    try:
        return (yield)
    finally:
        mp.undo()


# --------------------------------------------------------------------------------------------
# Bytecode of the checkout, once per run
# --------------------------------------------------------------------------------------------

#: the checkout (the folder above tests/)
ROOT = Path(__file__).resolve().parent.parent
#: its folders whose modules the run's processes import (tests/: its helpers)
COMPILED = ("firmware_protocol", "virtual_drive", "drive_link", "dashboard", "tests")


def pytest_configure(config):
    """Compile the checkout's modules to bytecode once, in the controlling process, before any
    worker starts: what pip does for installed packages (site-packages), an editable install
    does not do for its sources. Where ``PYTHONDONTWRITEBYTECODE`` is set (as on CI hosts)
    nothing else ever writes them, and each of the ~400 Python processes the suite starts
    (virtual drives, hubs, ``drive-link`` commands, benches, workers) compiled every module it
    imports from source: about 0.06-0.09 s of CPU per process and 3 s per worker's collection
    (measured on the 2-core host). Up-to-date files are left alone (``__pycache__`` is ignored
    by git). The test modules get theirs from pytest's assertion rewriting, which writes them
    only while ``sys.dont_write_bytecode`` is false: so it is, in this run's processes (2 s of
    each worker's collection)."""
    import sys

    sys.dont_write_bytecode = False
    # and numpy's OpenBLAS without its thread pool in the processes this run starts (workers,
    # drive-link commands, benches; the drives and hubs get it from virtual_drive's launchers):
    # none does linear algebra that it would speed up, and its threads spin at every start
    # (0.05-0.1 s of CPU per process)
    from virtual_drive.node.process import BLAS_ENV

    for key, value in BLAS_ENV.items():
        os.environ.setdefault(key, value)
    if hasattr(config, "workerinput"):
        return  # an xdist worker: the controller compiled the checkout
    import compileall

    for name in COMPILED:
        folder = ROOT / name
        if folder.is_dir():
            compileall.compile_dir(folder, quiet=2, workers=1)


# --------------------------------------------------------------------------------------------
# How many workers ``pytest -n auto`` starts (pytest-xdist's hook)
# --------------------------------------------------------------------------------------------


def auto_workers(cores: int, load1: float) -> int:
    """Workers for ``-n auto`` on a host with ``cores`` CPUs and 1-minute load ``load1``, like
    ``make -j -l``: most tests wait on a real-time drive, so an idle host runs two workers more
    than it has cores; a host whose CPUs are taken (load ≥ cores) one more. Measured on the
    2-core host: idle, 4 workers took 501-514 s and 3 took 578-720 s; with four CPU hogs, 3
    stayed green (1,065 s, 991 s) and 4 failed two to four timing tests at load 16-17."""
    return cores + (2 if load1 < cores else 1)


_AUTO: list[str] = []  # what -n auto chose, for the run's header (and so the CI log)


def pytest_xdist_auto_num_workers(config):
    cores, load1 = os.cpu_count() or 1, os.getloadavg()[0]
    n = auto_workers(cores, load1)
    _AUTO.append(f"-n auto: {n} workers ({cores} cores, load {load1:.2f})")
    return n


def pytest_report_header(config):
    return _AUTO[-1:] or None


# --------------------------------------------------------------------------------------------
# Order and grouping of the run (serial or pytest-xdist ``-n N --dist loadgroup``)
# --------------------------------------------------------------------------------------------

#: Groups that take longest start first, so that parallel workers finish together (files, or
#: ``test_matrix.py[condition]`` for the scenario matrix's rows); everything else follows in
#: collection order, and the SocketCAN lane test (which waits for the background lane) is last.
SLOW_FIRST = (
    "tests/scenarios/test_matrix.py[loss5]",
    "tests/scenarios/test_matrix.py[busy]",
    "tests/scenarios/test_matrix.py[loss1]",
    "tests/scenarios/test_matrix.py[latency]",
    "tests/scenarios/test_matrix.py[idle]",
    "tests/test_dashboard_browsers.py",
    "tests/test_sdo_hub_loss.py",
    "tests/test_dashboard_e2e.py",
    "tests/test_cli_link.py",
    "tests/test_link_check.py",
    "tests/test_sdo_client_recovery.py",
    "tests/test_fuzz_sdo.py",
    "tests/test_readme_setup.py",
    "tests/test_readme_using.py",
    "tests/test_readme_commands.py",
    "tests/test_readme_nodes.py",
    "tests/test_readme_sweeps.py",
)
LANE_TEST = "tests/test_socketcan_lane.py::test_socketcan_lane"


def _group(item) -> str:
    """The item's work unit: its file, and for the scenario matrix its condition too (each
    condition has its own module-scoped bench, so a unit never starts a drive twice)."""
    path = item.nodeid.split("::", 1)[0]
    callspec = getattr(item, "callspec", None)
    if callspec is not None and "condition" in callspec.params:
        return f"{path}[{callspec.params['condition'].name}]"
    return path


@pytest.hookimpl(tryfirst=True)  # before xdist's own hook turns the marks into node-id suffixes
def pytest_collection_modifyitems(config, items):
    rank = {g: i for i, g in enumerate(SLOW_FIRST)}
    order = {id(it): n for n, it in enumerate(items)}

    def key(it) -> tuple[int, int, int]:
        last = it.nodeid.startswith(LANE_TEST)
        return (int(last), rank.get(_group(it), len(rank)), order[id(it)])

    items.sort(key=key)
    for it in items:
        it.add_marker(pytest.mark.xdist_group(name=_group(it)))


def pytest_collection_finish(session):
    """Boot the SocketCAN lane in the background when its test is part of this run."""
    if any(it.nodeid.startswith(LANE_TEST) for it in session.items):
        import importlib.util
        import sys

        mod = sys.modules.get("test_socketcan_lane")
        if mod is None:
            path = Path(__file__).resolve().parent / "test_socketcan_lane.py"
            spec = importlib.util.spec_from_file_location("socketcan_lane_start", path)
            assert spec and spec.loader
            mod = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(mod)
        mod.start_lane()


def pytest_terminal_summary(terminalreporter):
    """The SocketCAN lane's own line (kernel, result, time, load: tests/test_socketcan_lane.py)
    in the run's summary, so a CI log shows which kernel the lane ran, also when it passed."""
    for reports in list(terminalreporter.stats.values()):
        for rep in reports:
            for name, value in getattr(rep, "user_properties", None) or ():
                if name == "socketcan_lane" and getattr(rep, "when", "") == "call":
                    terminalreporter.write_line(str(value))
