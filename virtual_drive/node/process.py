"""Run ``virtual-drive run`` as a child process (cross-process tests, benchmarks, dashboard)."""

from __future__ import annotations

import atexit
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Sequence
from pathlib import Path

__all__ = ["BLAS_ENV", "PARENT_ENV", "DriveProcess", "child_env", "spawn_virtual_drive"]

#: Environment variable naming the parent PID; ``virtual-drive run`` exits when it is gone.
PARENT_ENV = "VIRTUAL_DRIVE_PARENT_PID"

#: numpy's OpenBLAS starts one thread per core when numpy is imported, and they spin before they
#: sleep: about 0.1 s of CPU at each start of a drive or hub process (2-core host, load 1.4:
#: 0.395 CPU-s from start to ready with the pool, 0.265 without, ``python
#: benchmarks/bench_start.py`` run plain and with the variable set), which does no
#: linear algebra that a thread pool would speed up. Set for the processes started here unless
#: the environment already says otherwise.
BLAS_ENV = {"OPENBLAS_NUM_THREADS": "1"}


def child_env() -> dict[str, str]:
    """The environment for a drive or hub child process: this one's, with :data:`BLAS_ENV`
    where it is unset."""
    return {**BLAS_ENV, **os.environ}


class DriveProcess:
    """A running ``virtual-drive run`` child; stop it with :meth:`stop` (SIGTERM) or
    :meth:`kill` (SIGKILL). ``ready_line`` is the line it printed when it came up."""

    def __init__(self, proc: subprocess.Popen, ready_line: str) -> None:
        self.proc = proc
        self.ready_line = ready_line
        atexit.register(self._at_exit)  # never leave an orphan drive behind
        self._stderr: list[str] = []
        self._reader = threading.Thread(target=self._drain, daemon=True)
        self._reader.start()

    def _drain(self) -> None:
        assert self.proc.stderr is not None
        for line in self.proc.stderr:
            self._stderr.append(line)
            del self._stderr[:-200]

    def _at_exit(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(5)

    @property
    def pid(self) -> int:
        return self.proc.pid

    @property
    def stderr_tail(self) -> str:
        return "".join(self._stderr[-40:])

    def stop(self, timeout: float = 10.0) -> int:
        """SIGTERM and wait (SIGKILL after ``timeout`` s); returns the exit status. Its
        stderr is read to the end before this returns (:attr:`stderr_tail` is complete)."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
        try:
            rc = self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            rc = self.proc.wait(timeout)
        self._reader.join(5.0)
        return rc

    def kill(self) -> int:
        """SIGKILL (no clean-up at all) and wait."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGKILL)
        rc = self.proc.wait(10)
        self._reader.join(5.0)
        return rc

    def __enter__(self) -> DriveProcess:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()


def spawn_virtual_drive(
    args: Sequence[str] = (),
    *,
    interface: str | None = "socketcand",
    host: str = "127.0.0.1",
    port: int | None = None,
    channel: str | None = "vcan0",
    node_id: int = 1,
    nodes: str | None = None,
    store: str | Path | None = None,
    speed: float = 1.0,
    timeout: float = 60.0,
    env: dict | None = None,
) -> DriveProcess:
    """Start ``python -m virtual_drive run ...`` and wait for its ready line.

    :param port: socketcand port of the loopback hub (required for socketcand).
    :param nodes: several drives in the child, e.g. ``"1-4"`` (``--nodes``; replaces
        ``node_id``).
    :param timeout: s to wait for the ready line; the interpreter start and imports took up
        to 40 s on this 2-core machine at load average 20 (about 1 s idle).
    :raises RuntimeError: the child exited or stayed silent for ``timeout`` s (its stderr is
        in the message).
    """
    cmd = [sys.executable, "-m", "virtual_drive.cli", "run"]
    if interface is not None:
        cmd += ["--interface", interface]
        if interface == "socketcand":
            if port is None:
                raise ValueError("socketcand needs the hub's port")
            cmd += ["--host", host, "--port", str(port)]
    if channel is not None:
        cmd += ["--channel", channel]
    if nodes is not None:
        cmd += ["--nodes", nodes]
    else:
        cmd += ["--node-id", str(node_id)]
    cmd += ["--speed", repr(float(speed))]
    if store is not None:
        cmd += ["--store", str(store)]
    cmd += list(args)
    proc = subprocess.Popen(
        cmd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        # the child exits by itself when this process is gone (even after SIGKILL)
        env={**child_env(), PARENT_ENV: str(os.getpid()), **(env or {})},
    )
    stdout = proc.stdout
    assert stdout is not None  # (stdout=PIPE)
    line_box: list[str] = []

    def _read() -> None:
        line_box.append(stdout.readline())

    reader = threading.Thread(target=_read, daemon=True)
    reader.start()
    reader.join(timeout)
    line = line_box[0] if line_box else ""
    if "ready" not in line:
        deadline = time.monotonic() + 2
        while proc.poll() is None and time.monotonic() < deadline and not line:
            time.sleep(0.05)
        if proc.poll() is None:
            proc.kill()
        err = proc.stderr.read() if proc.stderr else ""
        proc.wait(5)
        raise RuntimeError(f"virtual-drive did not come up: {line.strip()} {err.strip()[-2000:]}")
    return DriveProcess(proc, line.strip())
