"""Issue 28: a seeded Monte-Carlo sweep (500 short runs) gives identical rows run in this
process, on the local process pool with one worker process killed (SIGKILL) mid-sweep, and on
a Dask scheduler with two workers started as separate processes on 127.0.0.1, one of which is
killed mid-sweep: every run is present exactly once.

The truth is the other engine and the sweep's own contract (per-run seeds from the spec seed and
the run index, never from scheduling): the rows are compared as the CSV text each client wrote.
"""

from __future__ import annotations

import contextlib
import csv
import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from virtual_drive.sweep import load_spec, run_sweep

pytestmark = pytest.mark.timeout(180)

SPEC = """
[sweep]
name = "montecarlo"
seed = 2028
samples = 500
batch = 10
[parameters]
L = { dist = "uniform", low = -30, high = 30, unit = "%" }
R = { dist = "uniform", low = -40, high = 60, unit = "%" }
V_dc = { dist = "uniform", low = 40, high = 56, unit = "V" }
J = { dist = "normal", mean = 0, std = 10, clip = [-25, 25], unit = "%" }
"L_c/L" = { dist = "uniform", low = 0.5, high = 2.3 }
[limits]
overshoot = 30
settling = "1 ms"
[[scenarios]]
kind = "current_step"
from = "10 A"
to = "15 A"
at = "0.2 ms"
duration = "3 ms"
settle = "0.4 ms"
"""

_DASK = str(Path(sys.executable).with_name("dask"))


def _lines(out: Path) -> list[str]:
    """The data lines of runs.csv (without header), sorted by run id."""
    text = (out / "runs.csv").read_text().splitlines()
    return sorted(text[1:], key=lambda s: int(s.split(",", 1)[0]))


def _start(args: list[str], log: Path) -> subprocess.Popen:
    return subprocess.Popen(
        args, stdout=subprocess.DEVNULL, stderr=log.open("w"), start_new_session=True,
        env={**os.environ, "OPENBLAS_NUM_THREADS": "1"},
    )  # fmt: skip


def _stop(p: subprocess.Popen) -> None:
    if p.poll() is None:
        p.terminate()
        try:
            p.wait(10)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait(5)


def _kill_a_pool_worker(killed: dict) -> None:
    """SIGKILL one process of the local pool (forked by the forkserver: a grandchild)."""
    import psutil

    me = os.getpid()
    pool = [p for p in psutil.Process(me).children(recursive=True) if p.ppid() != me]
    assert pool, "no pool worker found"
    os.kill(pool[0].pid, signal.SIGKILL)
    killed["pid"] = pool[0].pid


def test_local_and_dask_give_identical_rows_and_survive_a_killed_worker(tmp_path):
    from distributed import Client

    spec_path = tmp_path / "mc.toml"
    spec_path.write_text(SPEC)
    spec = load_spec(spec_path)
    assert spec.n_runs == 500
    one = run_sweep(spec, tmp_path / "one", workers=1, progress=False, plots=False)
    assert one.executed == 500
    # the local pool (2 processes), one of them killed mid-sweep
    pool_killed: dict = {}

    def pool_hook(done: int, total: int, failures: int) -> None:
        if not pool_killed and done >= 100:
            pool_killed["done"] = done
            _kill_a_pool_worker(pool_killed)

    local = run_sweep(spec, tmp_path / "local", workers=2, progress=False, plots=False,
                      on_progress=pool_hook)  # fmt: skip
    assert pool_killed and pool_killed["done"] < 500
    assert local.executed == 500
    assert _lines(tmp_path / "local") == _lines(tmp_path / "one")
    procs: list[subprocess.Popen] = []
    try:
        sched_file = tmp_path / "scheduler.json"
        procs.append(_start([_DASK, "scheduler", "--host", "127.0.0.1", "--port", "0",
                             "--dashboard-address", "127.0.0.1:0",
                             "--scheduler-file", str(sched_file)],
                            tmp_path / "scheduler.log"))  # fmt: skip
        deadline = time.monotonic() + 60
        while not sched_file.exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        address = json.loads(sched_file.read_text())["address"]
        assert address.startswith("tcp://127.0.0.1:")
        workers = {}
        for name in ("wa", "wb"):
            workers[name] = _start([_DASK, "worker", address, "--host", "127.0.0.1",
                                    "--nthreads", "1", "--no-nanny",
                                    "--dashboard-address", "127.0.0.1:0",
                                    "--memory-limit", "0", "--name", name],
                                   tmp_path / f"{name}.log")  # fmt: skip
            procs.append(workers[name])
        with Client(address, set_as_default=False, timeout=60) as watch:
            watch.wait_for_workers(2, timeout=90)
            # every listener of the scheduler and the workers is on 127.0.0.1
            # (--no-dashboard alone still binds the dashboard on 0.0.0.0)
            import psutil

            mine = [c.laddr for p in procs for c in psutil.Process(p.pid).net_connections("tcp")
                    if c.status == psutil.CONN_LISTEN]  # fmt: skip
            assert len(mine) >= 6 and all(a.ip == "127.0.0.1" for a in mine), mine
            # warm both workers (import of the simulator) so the kill falls mid-sweep
            watch.run(lambda: __import__("virtual_drive.sweep.runner") and None)
            names = {a: w["name"] for a, w in watch.scheduler_info()["workers"].items()}
            killed: dict[str, object] = {}
            progress = {"done": 0}
            finished = threading.Event()

            def hook(done: int, total: int, failures: int) -> None:
                progress["done"] = done

            def killer() -> None:
                # from its own thread, once 100 runs are done: the first worker the scheduler
                # shows with a task in flight. (Asking from the progress hook waited on the
                # client's thread, which holds up the next submissions: on an idle host every
                # one of 400 asks found both workers between two tasks, ci47.)
                while not finished.is_set() and not killed:
                    if progress["done"] >= 100:
                        busy = [a for a, keys in watch.processing().items() if keys]
                        if busy:
                            done = progress["done"]
                            victim = names[busy[0]]
                            os.kill(workers[victim].pid, signal.SIGKILL)
                            killed.update(name=victim, done=done, busy=True)
                            return
                    time.sleep(0.005)

            kill_thread = threading.Thread(target=killer, daemon=True)
            kill_thread.start()
            try:
                dask = run_sweep(spec, tmp_path / "dask", scheduler=address, progress=False,
                                 on_progress=hook, plots=False)  # fmt: skip
            finally:
                finished.set()
                kill_thread.join(30)
            assert killed and killed["done"] < 500, killed  # the kill fell mid-sweep
            assert killed["busy"], "the killed worker had no task in flight"
            assert workers[str(killed["name"])].wait(10) == -signal.SIGKILL
            survivors = [w["name"] for w in watch.scheduler_info()["workers"].values()]
            assert survivors == [n for n in ("wa", "wb") if n != killed["name"]]
        assert dask.executed == 500
        # every run once in the file the client wrote, and the same rows as the local pool
        with (tmp_path / "dask" / "runs.csv").open() as fh:
            ids = [int(r["run"]) for r in csv.DictReader(fh)]
        assert sorted(ids) == list(range(500))
        assert _lines(tmp_path / "dask") == _lines(tmp_path / "local")
        assert [r["seed"] for r in dask.rows] == [spec.point_seed(i) for i in range(500)]
        assert 0 < dask.summary["passed"] < 500  # the spread reaches the limits
    finally:
        for p in reversed(procs):
            with contextlib.suppress(Exception):
                _stop(p)
