"""Cost of robustness sweeps (issue 28): ``python benchmarks/bench_sweep.py``.

For a 1-simulated-second speed step (1000 -> 1200 rpm at 0.1 s, PWM-exact model, Table 2 motor,
the paper's gains) it prints, each with the load average beside it:

1. one run in this process: wall and CPU time, runs/s and runs/hour per core;
2. the fixed part per run: the intercept of the run's CPU time against its simulated length
   (0.1, 0.4, 1 s; least squares): building the validated parameters and the simulator, the
   record's buffers, the metrics in numpy; and, measured directly, its first item (best and
   median of 200 ``build_simulator`` calls);
3. the simulation itself against the lean whole-loop C reference kernel of
   ``python -m virtual_drive.bench`` (``csrc/reference.c``, built with cffi into a temporary
   folder), both over 50,000 samples in alternating chunks, best of each: ``ratio_reference=``;
   and against the LEAN whole-loop kernel ``benchmarks/lean_kernel.c`` (the product's own
   closed loop in the sweep's case -- same deadbeat + IP laws, same PWM-exact switching model
   with the open leg's diode, same shaft -- as one C function with its state in locals),
   started from the simulator's state; its records are checked equal to the product's first,
   then timed the same way: ``ratio=`` (issue 28's goal: within 2x); also the whole 1-s run
   (core + fixed part) over the reference kernel;
4. throughput of the same batch of runs on a local process pool of 1 and of all cores, and on
   a Dask LocalCluster of two worker processes on 127.0.0.1 (dashboards on free ports), warmed
   first so that start-up is not counted (it is printed separately).

The host is shared: read each figure with its load average.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np
from _lean_kernel import build_lean, compare, time_both  # (benchmarks/, this script's folder)

from virtual_drive.bench import _reference_state, build_reference
from virtual_drive.sweep.driver import auto_batch
from virtual_drive.sweep.engine_local import default_workers
from virtual_drive.sweep.runner import build_simulator, run_batch, run_one
from virtual_drive.sweep.spec import parse_spec

N = 50_000  # one simulated second

SPEC = {
    "sweep": {"name": "bench", "seed": 1, "samples": 1},
    "parameters": {"L": {"dist": "uniform", "low": -10, "high": 10, "unit": "%"}},
    "scenarios": [{"kind": "speed_step", "from": 1000, "to": 1200, "at": 0.1,
                   "duration": 1.0, "settle": 0.0}],
}  # fmt: skip


def load() -> str:
    return "load " + " ".join(f"{x:.2f}" for x in os.getloadavg())


def jobs(n: int, duration: float = 1.0) -> list:
    sc = [{**SPEC["scenarios"][0], "duration": duration, "at": 0.1 * duration}]
    spec = parse_spec({**SPEC, "sweep": {**SPEC["sweep"], "samples": n}, "scenarios": sc})
    return [spec.job(i) for i in range(n)]


def fixed_part(repeats: int) -> tuple[float, float]:
    """(intercept s, slope s per simulated s) of the best run CPU time vs the run's length."""
    ds = (0.1, 0.4, 1.0)
    best = [one_run(repeats, d)[1] for d in ds]
    slope, intercept = np.polyfit(ds, best, 1)
    return float(intercept), float(slope)


def build_cost(n: int = 200) -> tuple[float, float]:
    """(best, median) CPU seconds of building one run's validated parameters and simulator
    (``build_simulator``: every value checked against the EDS limits), over ``n`` runs."""
    js = jobs(n)
    build_simulator(js[0].inputs)
    t = []
    for j in js:
        c0 = time.thread_time()
        build_simulator(j.inputs)
        t.append(time.thread_time() - c0)
    t.sort()
    return t[0], t[len(t) // 2]


def one_run(repeats: int, duration: float = 1.0) -> tuple[float, float]:
    js = jobs(repeats, duration)
    run_one(js[0])  # warm-up
    walls, cpus = [], []
    for j in js:
        t0, c0 = time.perf_counter(), time.thread_time()
        run_one(j)
        walls.append(time.perf_counter() - t0)
        cpus.append(time.thread_time() - c0)
    return min(walls), min(cpus)


def core_vs_reference(repeats: int) -> tuple[float, float]:
    """Best CPU seconds per simulated second: the sweep's simulator path, the reference."""
    job = jobs(1)[0]
    sim = build_simulator(job.inputs, "pwm")
    sim.set_speed(1500.0)
    sim.set_mode("speed")
    sim.set_speed_ref(1500.0)
    names = ("i_p", "i_a", "i_b", "i_c", "speed", "i_p_ref")
    rec = {k: np.zeros(N, dtype=np.float32) for k in names}
    sim.run_record(N, rec)
    best_sim = best_ref = float("inf")
    with tempfile.TemporaryDirectory(prefix="vd-bench-sweep-") as tmp:
        mod = build_reference(tmp)
        ref, log = _reference_state(mod, 1500.0)
        ptr = mod.ffi.cast("float *", log.ctypes.data)
        mod.lib.ref_run(ref, N, ptr)
        for _ in range(repeats):
            c0 = time.thread_time()
            sim.run_record(N, rec)
            best_sim = min(best_sim, time.thread_time() - c0)
            c0 = time.thread_time()
            mod.lib.ref_run(ref, N, ptr)
            best_ref = min(best_ref, time.thread_time() - c0)
    return best_sim, best_ref


def core_vs_lean(repeats: int) -> tuple[float, float, float]:
    """(best CPU s per simulated s of the sweep path, of the lean kernel, largest record
    difference): both from the same state at 1500 rpm, the product's 1-s warm-up run first."""
    job = jobs(1)[0]

    def settled() -> object:
        sim = build_simulator(job.inputs, "pwm")
        sim.set_speed(1500.0)
        sim.set_mode("speed")
        sim.set_speed_ref(1500.0)
        sim.run_record(N, {"i_p": np.zeros(N, dtype=np.float32)})
        return sim

    with tempfile.TemporaryDirectory(prefix="vd-bench-lean-") as tmp:
        mod = build_lean(tmp)
        diff = max(compare(mod, settled(), N).values())
        if diff != 0.0:
            raise RuntimeError(f"lean kernel and product differ by {diff} (not the same loop)")
        sim_s, lean_s = time_both(mod, settled(), N, repeats)
    return sim_s, lean_s, diff


def _noop() -> int:
    return os.getpid()


def pool_throughput(workers: int, batches: list) -> tuple[float, float]:
    """(start-up s, runs/s) of a forkserver process pool."""
    ctx = mp.get_context("forkserver")
    ctx.set_forkserver_preload(["virtual_drive.sweep.runner"])
    t0 = time.perf_counter()
    with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as ex:
        list(ex.map(run_batch, [b[:1] for b in batches[:workers]]))  # warm every worker
        start = time.perf_counter() - t0
        t1 = time.perf_counter()
        n = sum(len(r) for r in ex.map(run_batch, batches))
        return start, n / (time.perf_counter() - t1)


def dask_throughput(batches: list) -> tuple[float, float]:
    from distributed import Client, LocalCluster

    t0 = time.perf_counter()
    # every listener on 127.0.0.1 and a free port (dashboard_address=None still binds :8787)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address="127.0.0.1:0", worker_dashboard_address="127.0.0.1:0",
                      ) as cluster, Client(cluster) as client:  # fmt: skip
        client.run(lambda: __import__("virtual_drive.sweep.runner") and None)
        client.gather(client.map(run_batch, [b[:1] for b in batches[:2]], pure=False))
        start = time.perf_counter() - t0
        t1 = time.perf_counter()
        res = client.gather(client.map(run_batch, batches, pure=False))
        return start, sum(len(r) for r in res) / (time.perf_counter() - t1)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0], allow_abbrev=False)
    ap.add_argument("--runs", type=int, default=200, help="runs per throughput figure")
    ap.add_argument("--repeats", type=int, default=7, help="repeats of the single-run figures")
    ap.add_argument("--no-dask", action="store_true", help="skip the Dask figure")
    args = ap.parse_args(argv)
    cores = default_workers()
    print(f"1-simulated-second speed step, PWM-exact; {cores} cores", flush=True)
    wall, cpu = one_run(args.repeats)
    print(f"one run: {wall * 1e3:.1f} ms wall, {cpu * 1e3:.1f} ms CPU -> {1 / cpu:.1f} runs/s "
          f"per core = {3600 / cpu:,.0f} runs/hour per core  ({load()})", flush=True)  # fmt: skip
    sim_s, ref_s = core_vs_reference(args.repeats)
    print(f"C core (sweep path, 6 signals): {sim_s * 1e3:.2f} ms CPU per simulated second; "
          f"lean reference kernel: {ref_s * 1e3:.2f} ms  ({load()})", flush=True)
    lsim_s, lean_s, _ = core_vs_lean(args.repeats)
    print(f"C core (sweep path) {lsim_s * 1e3:.2f} ms vs lean whole-loop kernel (same loop, "
          f"records identical over 50,000 samples) {lean_s * 1e3:.2f} ms CPU per simulated "
          f"second: x{lsim_s / lean_s:.2f}  ({load()})", flush=True)
    fixed, slope = fixed_part(args.repeats)
    print(f"fixed part per run: {fixed * 1e3:.2f} ms CPU ({100 * fixed / cpu:.0f} % of a "
          f"1-s run), then {slope * 1e3:.2f} ms per simulated second  ({load()})", flush=True)
    b_best, b_med = build_cost()
    print(f"of which parameters + simulator (build_simulator): {b_best * 1e3:.3f} ms best, "
          f"{b_med * 1e3:.3f} ms median of 200  ({load()})", flush=True)  # fmt: skip
    js = jobs(args.runs)
    size = auto_batch(js, cores)
    batches = [js[i : i + size] for i in range(0, len(js), size)]
    print(f"{len(js)} runs in {len(batches)} tasks of {size}")
    rates = {}
    for w in sorted({1, cores}):
        start, rate = pool_throughput(w, batches)
        rates[w] = rate
        print(f"local pool, {w} process(es): {rate:.1f} runs/s ({rate / w:.1f} per process), "
              f"start-up {start:.2f} s  ({load()})", flush=True)  # fmt: skip
    if cores > 1:
        print(f"scaling 1 -> {cores}: x{rates[cores] / rates[1]:.2f}  ({load()})")
    if not args.no_dask:
        start, rate = dask_throughput(batches)
        print(f"Dask LocalCluster, 2 worker processes: {rate:.1f} runs/s, start-up {start:.2f} s "
              f"({load()})", flush=True)  # fmt: skip
    per_core = 1 / cpu
    print(f"10,000 runs: {10_000 / per_core / 60:.1f} min on one core, "
          f"{10_000 / rates[cores] / 60:.1f} min on this machine's pool")
    print(f"whole run (C core + fixed part, the speed step) / reference kernel: {cpu / ref_s:.2f}")
    print(f"ratio_reference={sim_s / ref_s:.2f}  (csrc/reference.c; {load()})")
    print(f"ratio={lsim_s / lean_s:.2f}  (lean whole-loop kernel; {load()})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
