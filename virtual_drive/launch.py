"""One way to start a loopback hub with virtual drives on it: :func:`virtual_bench`.

    with virtual_bench(nodes=(1, 2, 3, 4)) as bus:
        can_bus = can.Bus(**bus)                          # python-can
        drive = Drive.connect(node_id=3, **bus)           # drive_link

The hub (:class:`virtual_drive.hub.Hub`) runs in this process (a thread) or, with
``hub_process=True``, as ``virtual-drive hub`` in a child process so its pacing does not share
this process's GIL. The drives run in a ``virtual-drive run --nodes`` child process (they keep
their TPDO rates whatever this process does and exit by themselves when this process is gone;
``process_per_node=True``: one child per node) or, with ``drives_in_process=True``, as
:class:`~virtual_drive.node.VirtualDrive` objects in this process.
Everything is stopped when the ``with`` block ends, also on errors. The dashboard
(``drive-dashboard --virtual``), ``virtual-drive hub --nodes`` and the benchmarks use it.
"""

from __future__ import annotations

import contextlib
import os
import re
import signal
import subprocess
import sys
import tempfile
import threading
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypedDict

if TYPE_CHECKING:
    from virtual_drive.node import VirtualDrive

__all__ = ["BusSettings", "HubProcess", "parse_nodes", "virtual_bench"]


class BusSettings(dict[str, Any]):
    """python-can bus settings of a started bench (``can.Bus(**settings)``,
    ``Drive.connect(node_id=N, **settings)``), plus what was started:

    ``hub``: the in-process :class:`~virtual_drive.hub.Hub` (None with ``hub_process``; its
    ``set_faults`` changes frame loss and delay at run time); ``hub_process``: the
    :class:`HubProcess` (or None); ``drives``: node-ID → the ``DriveProcess`` child or the
    in-process ``VirtualDrive``; ``stores``: node-ID → its parameter file (0x1010/0x1011).
    """

    hub: Any = None
    hub_process: HubProcess | None = None
    drives: dict[int, Any]
    stores: dict[int, Path]
    _respawn: Any = None

    def set_respawn(self, respawn: Any) -> None:
        """``respawn(node_id) -> DriveProcess``: how :meth:`restart_drive` starts a child
        again (set by :func:`virtual_bench` for child-process drives)."""
        self._respawn = respawn

    def restart_drive(self, node_id: int) -> Any:
        """Stop the ``virtual-drive run`` child serving node ``node_id`` (SIGTERM; with several
        nodes in one child, all of them) and start it again on the same parameter files;
        returns the new ``DriveProcess``. Raises RuntimeError if it does not come up, KeyError
        for a node not started here, TypeError for in-process drives.
        """
        if self._respawn is None:
            raise TypeError("only child-process drives can be restarted")
        self.drives[node_id].stop()
        return self._respawn(node_id)

    @property
    def port(self) -> int:
        """The hub's TCP port on 127.0.0.1."""
        return int(self["port"])

    def cli_args(self) -> list[str]:
        """The bus options of ``drive-link`` / ``drive-dashboard`` for this hub."""
        return ["--host", str(self["host"]), "--port", str(self["port"])]


def parse_nodes(text: str) -> tuple[int, ...]:
    """Node-IDs from ``"1-4"``, ``"1,3"`` or ``"1-2,5"``: ``virtual-drive run --nodes``'s rule
    (:func:`virtual_drive.node.cli_run.parse_nodes`: 1..127, no repeats, at most 16).

    Raises ValueError with a one-line reason.
    """
    from virtual_drive.node.cli_run import parse_nodes as run_parse_nodes

    return tuple(run_parse_nodes(str(text)))


def _check_nodes(ids: Iterable[int]) -> tuple[int, ...]:
    ids = tuple(ids)
    if not ids:
        raise ValueError("no node-ID given")
    for n in ids:
        if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= 127:
            raise ValueError(f"node-ID must be 1..127, got {n!r}")
    if len(set(ids)) != len(ids):
        raise ValueError(f"node-IDs repeat: {ids}")
    return ids


# Runs a command and ends it when its parent is gone (also after SIGKILL of the parent).
_WATCH = (
    "import os, signal, subprocess, sys, time\n"
    "p = subprocess.Popen(sys.argv[2:])\n"
    "signal.signal(signal.SIGTERM, lambda *a: p.terminate())\n"
    "while p.poll() is None and os.getppid() == int(sys.argv[1]):\n"
    "    time.sleep(0.5)\n"
    "if p.poll() is None:\n"
    "    p.terminate()\n"
    "sys.exit(p.wait())\n"
)


class HubProcess:
    """``virtual-drive hub`` in a child process (watched: it ends with this process).

    ``faults``: ``drop_rate`` (0..1), ``delay_s``, ``jitter_s`` (s), ``seed``; ``bitrate`` bit/s.
    Raises RuntimeError if it did not print its join line within ``timeout`` s.
    """

    def __init__(
        self, bitrate: int = 1_000_000, port: int = 0, timeout: float = 60.0, **faults: Any
    ) -> None:
        from virtual_drive.node import process

        cmd = [sys.executable, "-m", "virtual_drive.cli", "hub", "--port", str(port)]
        cmd += ["--bitrate", str(int(bitrate))]
        cmd += ["--drop-rate", repr(float(faults.get("drop_rate", 0.0)))]
        cmd += ["--delay-ms", repr(1e3 * float(faults.get("delay_s", 0.0)))]
        cmd += ["--jitter-ms", repr(1e3 * float(faults.get("jitter_s", 0.0)))]
        cmd += ["--seed", str(int(faults.get("seed", 0)))]
        self._err = tempfile.TemporaryFile(mode="w+")  # a pipe nobody reads could fill up
        self.proc = subprocess.Popen(
            [sys.executable, "-c", _WATCH, str(os.getpid()), *cmd],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=self._err,
            text=True,
            start_new_session=True,
            env=process.child_env(),
        )
        box: list[str] = []
        out = self.proc.stdout
        assert out is not None  # stdout=PIPE
        reader = threading.Thread(target=lambda: box.append(out.readline()))
        reader.daemon = True
        reader.start()
        reader.join(timeout)
        m = re.search(r"port=(\d+)", box[0] if box else "")
        if not m:
            self.stop()
            self._err.seek(0)
            err = self._err.read()
            raise RuntimeError(f"virtual-drive hub did not come up: {err.strip()[-500:]}")
        self.port = int(m.group(1))

    @property
    def pid(self) -> int:
        """PID of the hub itself (the watcher's only child), else of the watcher."""
        try:
            kids = Path(f"/proc/{self.proc.pid}/task/{self.proc.pid}/children").read_text()
            return int(kids.split()[0])
        except (OSError, IndexError, ValueError):
            return self.proc.pid

    def stop(self, timeout: float = 5.0) -> None:
        """SIGTERM its session (SIGKILL after ``timeout`` s)."""
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(self.proc.pid, signal.SIGTERM)
        try:
            self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc.wait(timeout)
        if self.proc.stdout is not None:
            self.proc.stdout.close()
        self._err.close()


class _Faults(TypedDict):
    """The hub's fault injection, as :class:`~virtual_drive.hub.Hub` takes it."""

    drop_rate: float
    delay_s: float
    jitter_s: float
    seed: int


@contextlib.contextmanager
def virtual_bench(
    nodes: Iterable[int] = (1,),
    *,
    bitrate: int = 1_000_000,
    drop_rate: float = 0.0,
    delay_s: float = 0.0,
    jitter_s: float = 0.0,
    seed: int = 0,
    hub_port: int = 0,
    channel: str = "vcan0",
    speed: float = 1.0,
    store_dir: str | Path | None = None,
    hub_process: bool = False,
    drives_in_process: bool = False,
    process_per_node: bool = False,
    timeout: float = 60.0,
    drive_args: Iterable[str] = (),
) -> Iterator[BusSettings]:
    """Start a loopback hub and one virtual drive per node-ID; yield the bus settings.

    nodes: node-IDs (1..127) of the drives (empty: the hub alone). bitrate: emulated bit rate,
    bit/s. drop_rate (0..1), delay_s, jitter_s (s), seed: the hub's fault injection (see
    :class:`~virtual_drive.hub.Hub`). hub_port: TCP port on 127.0.0.1 (0 = any free).
    speed: simulated seconds per wall-clock second. store_dir: folder of the parameter files
    ``node<N>.json`` (default: a temporary folder removed at the end). timeout: s to wait for each
    child to come up (interpreter start took up to 40 s at load 20). drive_args: extra
    ``virtual-drive run`` options. The drives run in one ``virtual-drive run --nodes`` child
    (up to 16 per child) or, with ``process_per_node``, one child each; with
    ``drives_in_process`` in this process.

    Raises ValueError (bad node-IDs or hub settings, nothing started), OSError (port busy) or
    RuntimeError (a child did not come up; everything started is stopped again).
    """
    ids = _check_nodes(nodes) if tuple(nodes) else ()
    with contextlib.ExitStack() as stack:
        if store_dir is None:
            store_dir = stack.enter_context(tempfile.TemporaryDirectory(prefix="virtual-bench-"))
        elif ids:
            Path(store_dir).mkdir(parents=True, exist_ok=True)
        settings = BusSettings()
        settings.drives = {}
        settings.stores = {n: Path(store_dir) / f"node{n}.json" for n in ids}
        faults: _Faults = {
            "drop_rate": drop_rate,
            "delay_s": delay_s,
            "jitter_s": jitter_s,
            "seed": seed,
        }
        if hub_process:
            from virtual_drive.hub import Hub

            Hub(bitrate=bitrate, **faults)  # validates: a clear ValueError before any child
            hp = HubProcess(bitrate=bitrate, port=hub_port, timeout=timeout, **faults)
            stack.callback(hp.stop)
            settings.hub_process, port = hp, hp.port
        else:
            from virtual_drive.hub import Hub

            hub = Hub(port=hub_port, bitrate=bitrate, **faults).start()
            stack.callback(hub.stop)
            settings.hub, port = hub, hub.port
        settings.update(
            interface="socketcand", host="127.0.0.1", port=port, channel=channel, tcp_tune=True
        )
        if drives_in_process:
            for n in ids:
                settings.drives[n] = stack.enter_context(
                    _drive_in_process(settings, n, settings.stores[n], speed)
                )
        elif ids:
            _spawn_all(stack, settings, ids, speed, timeout, tuple(drive_args), process_per_node)
        yield settings


def _spawn_all(
    stack: contextlib.ExitStack,
    settings: BusSettings,
    ids: tuple[int, ...],
    speed: float,
    timeout: float,
    drive_args: tuple[str, ...],
    process_per_node: bool,
) -> None:
    """The ``virtual-drive run`` children: one serving all nodes (``--nodes``: one pacing loop
    and one hub connection, the cheapest) or, with ``process_per_node``, one per node; started
    side by side (each start costs an interpreter and imports: about 1 s idle, tens of s on a
    busy host)."""
    from virtual_drive.node.cli_run import MAX_NODES
    from virtual_drive.node.process import spawn_virtual_drive

    step = 1 if process_per_node else MAX_NODES
    groups = [ids[k : k + step] for k in range(0, len(ids), step)]
    store_dir = next(iter(settings.stores.values())).parent

    def spawn(group: tuple[int, ...]) -> Any:
        if len(group) == 1:
            return spawn_virtual_drive(
                drive_args,
                port=settings.port,
                channel=settings["channel"],
                node_id=group[0],
                store=settings.stores[group[0]],
                speed=speed,
                timeout=timeout,
            )
        return spawn_virtual_drive(
            drive_args,
            port=settings.port,
            channel=settings["channel"],
            nodes=",".join(map(str, group)),
            store=store_dir / "node{node}.json",
            speed=speed,
            timeout=timeout,
        )

    def respawn(n: int) -> Any:
        group = next(g for g in groups if n in g)
        proc = spawn(group)
        for m in group:
            settings.drives[m] = proc
        return proc

    settings.set_respawn(respawn)
    stack.callback(_stop_drives, settings)  # SIGTERM each, then SIGKILL after 10 s
    results: dict[int, Any] = {}

    def start(k: int) -> None:
        try:
            results[k] = spawn(groups[k])
        except BaseException as exc:  # reported below, after every start has finished
            results[k] = exc

    threads = [threading.Thread(target=start, args=(k,), daemon=True) for k in range(len(groups))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    failures = []
    for k, group in enumerate(groups):
        r = results.get(k, RuntimeError("no result"))
        if isinstance(r, BaseException):
            failures.append(f"node {','.join(map(str, group))}: {r}")
        else:
            for n in group:
                settings.drives[n] = r
    if failures:
        raise RuntimeError("; ".join(failures))


def _stop_drives(settings: BusSettings) -> None:
    """Stop every child drive (each even if stopping another one failed)."""
    errors = []
    for proc in {id(p): p for p in settings.drives.values()}.values():
        try:
            proc.stop()
        except Exception as exc:
            errors.append(exc)
    if errors:
        raise errors[0]


@contextlib.contextmanager
def _drive_in_process(
    settings: BusSettings, node_id: int, store: Path, speed: float
) -> Iterator[VirtualDrive]:
    import can

    from virtual_drive.node import VirtualDrive

    bus = can.Bus(**settings)
    try:
        vd = VirtualDrive(bus, node_id, store_path=str(store), speed=speed)
        vd.start()
        try:
            yield vd
        finally:
            vd.stop()
    finally:
        bus.shutdown()
