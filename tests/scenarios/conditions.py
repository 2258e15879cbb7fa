"""Bench conditions for the scenario matrix: a loopback hub (with latency or frame loss) or a real
SocketCAN channel, a ``virtual-drive run`` child process on it, and optionally a busy host CPU.

Selection: the environment variable ``BENCH_CONDITION`` (one of :data:`CONDITIONS`) runs only that
condition; unset, every condition that this host can provide runs (``vcan0`` only where an
AF_CAN socket opens and the interface ``vcan0`` exists, i.e. inside the SocketCAN lane).

Used by ``tests/scenarios`` and ``benchmarks/bench_conditions.py``; no test logic here.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

ENV = "BENCH_CONDITION"


@dataclass(frozen=True)
class Condition:
    """One bench condition.

    ``drop_rate``: hub frame-loss probability (0..1, seeded); ``delay_s``/``jitter_s``: hub
    delivery delay and its ± jitter per frame (s); ``busy``: keep every core busy with at least
    two CPU-bound processes; ``channel``: a SocketCAN channel instead of the hub; ``slow``:
    factor applied to the scenario's waiting times (never to a pass criterion).
    """

    name: str
    drop_rate: float = 0.0
    delay_s: float = 0.0
    jitter_s: float = 0.0
    busy: bool = False
    channel: str | None = None
    slow: float = 1.0


CONDITIONS: dict[str, Condition] = {
    c.name: c
    for c in (
        Condition("idle"),
        Condition("busy", busy=True, slow=3.0),
        Condition("latency", delay_s=0.002, jitter_s=0.001, slow=2.0),
        Condition("loss1", drop_rate=0.01, slow=2.0),
        Condition("loss5", drop_rate=0.05, slow=3.0),
        Condition("vcan0", channel="vcan0", slow=10.0),
    )
}


def socketcan_available(channel: str = "vcan0") -> bool:
    """True if this kernel opens AF_CAN raw sockets and ``channel`` exists."""
    af_can = getattr(socket, "AF_CAN", None)
    if af_can is None or not Path(f"/sys/class/net/{channel}").exists():
        return False
    try:
        socket.socket(af_can, socket.SOCK_RAW, socket.CAN_RAW).close()
    except OSError:
        return False
    return True


def selected() -> list[Condition]:
    """The conditions to run here (see the module docstring).

    :raises ValueError: ``BENCH_CONDITION`` names no known condition.
    """
    name = os.environ.get(ENV, "").strip()
    if name:
        if name not in CONDITIONS:
            raise ValueError(f"{ENV}={name!r}: one of {', '.join(CONDITIONS)}")
        return [CONDITIONS[name]]
    return [
        c for c in CONDITIONS.values() if c.channel is None or socketcan_available(c.channel)
    ]


# --------------------------------------------------------------------------------------------
# busy host
# --------------------------------------------------------------------------------------------

_BUSY_PY = (
    "import os, time\n"
    "parent = os.getppid()\n"
    "t = time.monotonic()\n"
    "while os.getppid() == parent and time.monotonic() - t < {guard}:\n"
    "    for _ in range(200000):\n"
    "        pass\n"
)


# Runs a command in this (new) session and ends the whole session when its parent is gone, so
# a SIGKILLed test run never leaves stress-ng behind.
_WATCH = (
    "import os, signal, subprocess, sys, time\n"
    "p = subprocess.Popen(sys.argv[2:])\n"
    "while p.poll() is None and os.getppid() == int(sys.argv[1]):\n"
    "    time.sleep(0.5)\n"
    "os.killpg(0, signal.SIGTERM)\n"
)


class CpuHog:
    """Keeps the host CPU busy: ``per_core`` CPU-bound processes per core (``stress-ng --cpu``
    if installed, else busy Python processes). Each process is in its own session and stops by
    itself after ``guard_s`` even if nobody calls :meth:`stop` (Python ones also when their
    parent is gone).

    A host already that busy (1-minute load average ≥ ``per_core`` × cores: the rest of a test
    run, or other jobs) gets only the processes missing, none at all when the load is there:
    the condition is a busy host, and doubling an already busy one's load only slowed every
    other test of the run (a CI run with four CPU hogs beside it had eight during the busy
    scenarios). :attr:`tool` says what was started and the load found."""

    def __init__(self, per_core: int = 2, guard_s: float = 1800.0) -> None:
        self.target = per_core * (os.cpu_count() or 1)
        self.n = self.target
        self.guard_s = guard_s
        self.tool = ""
        self._procs: list[subprocess.Popen] = []

    def start(self) -> CpuHog:
        load = os.getloadavg()[0]
        self.n = max(0, self.target - int(load))
        if self.n == 0:
            self.tool = f"none (host load {load:.1f} >= {self.target})"
            return self
        stress = shutil.which("stress-ng")
        if stress:
            self.tool = f"stress-ng --cpu {self.n} (host load {load:.1f})"
            cmd = [stress, "--cpu", str(self.n), "--timeout", f"{int(self.guard_s)}s", "-q"]
            cmds = [[sys.executable, "-c", _WATCH, str(os.getpid()), *cmd]]
        else:
            self.tool = f"{self.n} busy Python processes (host load {load:.1f})"
            code = _BUSY_PY.format(guard=self.guard_s)
            cmds = [[sys.executable, "-c", code] for _ in range(self.n)]
        for cmd in cmds:
            self._procs.append(
                subprocess.Popen(
                    cmd,
                    stdin=subprocess.DEVNULL,
                    stdout=subprocess.DEVNULL,
                    stderr=subprocess.DEVNULL,
                    start_new_session=True,
                )
            )
        return self

    def stop(self) -> None:
        """SIGTERM each process group, SIGKILL after 5 s; never raises."""
        for p in self._procs:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(p.pid, signal.SIGTERM)
        for p in self._procs:
            try:
                p.wait(5)
            except subprocess.TimeoutExpired:
                with contextlib.suppress(ProcessLookupError, PermissionError):
                    os.killpg(p.pid, signal.SIGKILL)
                p.wait(5)
        self._procs.clear()


# --------------------------------------------------------------------------------------------
# the bench: bus + virtual drive (+ busy CPU)
# --------------------------------------------------------------------------------------------


class Bench:
    """A virtual drive (its own process) on the condition's bus, as a user meets it.

    ``node_id`` 1; parameters stored in a private temporary file (0x1010/0x1011).
    Use :meth:`connect` for a :class:`drive_link.Drive`, :meth:`cli` for ``drive-link``.
    """

    node_id = 1

    def __init__(self, cond: Condition, hub_in_process: bool = False) -> None:
        self.cond = cond
        self.hub_in_process = hub_in_process
        self.hub = None  #: the in-process :class:`~virtual_drive.hub.Hub` (hub_in_process)
        self.hub_port: int | None = None
        self.hog: CpuHog | None = None
        self.proc = None
        self.settings = None  #: :class:`virtual_drive.launch.BusSettings` (hub conditions)
        self._stack = contextlib.ExitStack()
        self._tmp = tempfile.TemporaryDirectory(prefix=f"bench-{cond.name}-")
        self.store = Path(self._tmp.name) / f"node{self.node_id}.json"
        self.hub_faults: dict = {
            "drop_rate": cond.drop_rate, "delay_s": cond.delay_s, "jitter_s": cond.jitter_s
        }  # fmt: skip

    # ---------------------------------------------------------------- lifecycle
    def start(self) -> Bench:
        try:
            if self.cond.busy:
                self.hog = CpuHog().start()
            if self.cond.channel is None:
                from virtual_drive.launch import virtual_bench

                # the product's one launcher: hub (own process unless hub_in_process) + drive
                self.settings = self._stack.enter_context(
                    virtual_bench(
                        nodes=(self.node_id,),
                        hub_process=not self.hub_in_process,
                        seed=9,
                        store_dir=self._tmp.name,
                        timeout=self._timeout,
                        **self.hub_faults,
                    )
                )
                self.hub, self.hub_port = self.settings.hub, self.settings.port
                self.proc = self.settings.drives[self.node_id]
                apply_tpdo_event_timers(self)
            else:
                self._spawn()
        except BaseException:
            self.stop()
            raise
        return self

    @property
    def _timeout(self) -> float:
        return max(60.0, 20.0 * self.cond.slow)

    def _spawn(self) -> None:
        """The drive on the SocketCAN channel (the hub conditions use the launcher)."""
        from virtual_drive.node.process import spawn_virtual_drive

        self.proc = spawn_virtual_drive(
            interface="socketcan",
            channel=self.cond.channel,
            node_id=self.node_id,
            store=self.store,
            timeout=self._timeout,
        )
        apply_tpdo_event_timers(self)

    def restart(self) -> None:
        """Stop the drive process (SIGTERM) and start it again on the same store file."""
        if self.settings is not None:
            self.proc = self.settings.restart_drive(self.node_id)
            apply_tpdo_event_timers(self)
            return
        if self.proc is not None:
            self.proc.stop()
        self._spawn()

    def stop(self) -> None:
        """Stop drive, hub and CPU hog (each step runs even if an earlier one failed)."""
        try:
            if self.settings is None and self.proc is not None:
                self.proc.stop()
        finally:
            try:
                self._stack.close()  # the launcher: drive, then hub
            finally:
                try:
                    if self.hog is not None:
                        self.hog.stop()
                finally:
                    self._tmp.cleanup()

    def __enter__(self) -> Bench:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    # ---------------------------------------------------------------- use
    @property
    def drive_alive(self) -> bool:
        return self.proc is not None and self.proc.proc.poll() is None

    def bus_args(self) -> list[str]:
        """``drive-link`` bus options for this bench."""
        if self.hub_port is not None:
            return ["--host", "127.0.0.1", "--port", str(self.hub_port)]
        return ["--interface", "socketcan", "--channel", str(self.cond.channel)]

    def bus_kwargs(self) -> dict:
        """:meth:`drive_link.Drive.connect` bus keywords for this bench."""
        if self.hub_port is not None:
            return {"host": "127.0.0.1", "port": self.hub_port}
        return {"interface": "socketcan", "channel": self.cond.channel}

    def connect(self, **kw):
        """A :class:`drive_link.Drive` on node 1 (its own bus connection)."""
        from drive_link import Drive

        kw.setdefault("sdo_timeout", self.sdo_timeout)
        return Drive.connect(node_id=self.node_id, **self.bus_kwargs(), **kw)

    @property
    def sdo_timeout(self) -> float:
        """SDO response timeout per frame (s): drive_link's default 0.3 s, longer where the
        whole bench runs slower (User-Mode Linux, slow 10: 1.0 s; an unanswered initiate then
        fails after 19 s instead of 5.7 s — a starved CI host kept UML silent longer)."""
        return 0.3 * max(1.0, self.cond.slow / 3.0)

    def cli(self, *args: str, timeout: float = 60.0) -> subprocess.CompletedProcess:
        """Run ``drive-link ARGS <bus options>`` as a user would; ``timeout`` in s (× slow).

        :raises subprocess.TimeoutExpired: the command did not finish in time.
        """
        exe = Path(sys.executable).with_name("drive-link")
        cmd: Sequence[str] = (
            [str(exe)] if exe.exists() else [sys.executable, "-m", "drive_link.cli"]
        )
        return subprocess.run(
            [*cmd, *args, *self.bus_args(), "--sdo-timeout", f"{self.sdo_timeout:g}"],
            capture_output=True,
            text=True,
            timeout=timeout * self.cond.slow,
            stdin=subprocess.DEVNULL,
        )


#: Environment variable with TPDO1..n event timers in ms, e.g. "100,50,50,100" (SocketCAN lane).
TPDO_TIMERS_ENV = "BENCH_TPDO_EVENT_TIMERS_MS"


def apply_tpdo_event_timers(b: Bench) -> None:
    """Set the drive's TPDO event timers (0x1800.. sub 5) by SDO from
    ``BENCH_TPDO_EVENT_TIMERS_MS`` when it is set. The SocketCAN lane sets it
    (tests/uml/runner.py): User-Mode Linux moves about 800 frames/s, the default streams are
    2,200 frames/s. No-op when unset."""
    spec = os.environ.get(TPDO_TIMERS_ENV, "").strip()
    if not spec:
        return
    from drive_link import Drive

    kw = b.bus_kwargs()
    with Drive.connect(node_id=b.node_id, heartbeat_ms=None, sdo_timeout=2.0, **kw) as d:
        for k, ms in enumerate(spec.split(","), start=1):
            d.write(f"tpdo{k}_communication.event_timer", int(ms))


@contextlib.contextmanager
def bench(cond: Condition, hub_in_process: bool = False) -> Iterator[Bench]:
    """A started :class:`Bench` for ``cond``, stopped on exit."""
    b = Bench(cond, hub_in_process=hub_in_process).start()
    try:
        yield b
    finally:
        b.stop()


def loadavg() -> str:
    """The 1/5/15-minute load averages as text."""
    try:
        return " ".join(Path("/proc/loadavg").read_text().split()[:3])
    except OSError:
        return "n/a"


def wait_until(pred, timeout: float, poll_s: float = 0.02):
    """Poll ``pred()`` until it returns a truthy value (returned) or ``timeout`` s pass (None)."""
    deadline = time.monotonic() + timeout
    while True:
        v = pred()
        if v:
            return v
        if time.monotonic() >= deadline:
            return None
        time.sleep(poll_s)
