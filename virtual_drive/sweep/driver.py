"""Run a sweep: expand the spec, skip the runs already in the results, batch the rest, run them
on the local pool or a Dask cluster, write each row as it arrives, then the summary and plots.

The cost of a run is the C core's (one call per chunk between events) plus a fixed part in
Python (building the simulator and its validated parameters, the metrics in numpy): see
``benchmarks/bench_sweep.py``.
"""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from virtual_drive.sim.params import Ts
from virtual_drive.sweep.engine_local import default_workers, iter_local
from virtual_drive.sweep.results import (
    ResultStore,
    summarize,
    summary_markdown,
    write_parquet,
)
from virtual_drive.sweep.spec import RunJob, Spec

__all__ = ["SweepResult", "auto_batch", "run_sweep"]

#: a progress hook: called after each batch with (runs done, runs planned, failures so far)
ProgressHook = Callable[[int, int, int], None]


@dataclass
class SweepResult:
    """What :func:`run_sweep` did: ``rows`` (all, sorted by run), ``summary``, files written,
    ``executed`` (runs computed in this call) and ``skipped`` (already in the results)."""

    rows: list[dict[str, Any]]
    summary: dict[str, Any]
    out: Path
    executed: int
    skipped: int
    files: list[Path] = field(default_factory=list)


def run_cost_estimate(job: RunJob) -> float:
    """Seconds of one run: ~1.5 ms fixed + ~0.25 us per simulated sample (PWM model)."""
    sc = job.scenario
    return 1.5e-3 + (sc.duration + sc.settle) / Ts * 0.25e-6


def auto_batch(jobs: list[RunJob], slots: int, target_s: float = 0.3) -> int:
    """Runs per task: about ``target_s`` of work each, and at least 4 tasks per slot."""
    if not jobs:
        return 1
    est = run_cost_estimate(jobs[0])
    by_time = max(1, int(target_s / est))
    by_spread = max(1, math.ceil(len(jobs) / (4 * slots)))
    return min(by_time, by_spread)


def run_sweep(
    spec: Spec,
    out: str | Path,
    *,
    scheduler: str | None = None,
    workers: int | None = None,
    progress: bool = True,
    on_progress: ProgressHook | None = None,
    plots: bool = True,
    map_axes: tuple[str, str] | None = None,
) -> SweepResult:
    """Run the runs of ``spec`` not yet in ``out`` and write the results there.

    ``scheduler``: a Dask scheduler address (``tcp://127.0.0.1:8786``), else a local process
    pool of ``workers`` processes (default: all cores; 1 runs in this process). Raises
    :class:`~.units.SpecError` for a bad spec / results folder / scheduler; an exception in
    ``on_progress`` (or Ctrl-C) stops the sweep with the rows so far written. The local pool
    starts its processes with ``forkserver``, which imports the calling script's main module
    in each: call this from a script under ``if __name__ == "__main__":``."""
    client = None
    if scheduler:  # first: an unreachable scheduler leaves nothing written
        from virtual_drive.sweep.engine_dask import cluster_threads, connect, iter_dask

        client = connect(scheduler)
        slots = max(cluster_threads(client), 4)  # workers may still be joining
    else:
        slots = workers or default_workers()
    try:
        store = ResultStore(out, spec)
    except BaseException:
        if client is not None:
            client.close()
        raise
    done = store.done()
    todo = [r for r in range(spec.n_runs) if r not in done]
    jobs = [spec.job(r) for r in todo]
    size = spec.batch or auto_batch(jobs, slots)
    batches = [jobs[i : i + size] for i in range(0, len(jobs), size)]
    fails = sum(1 for r in store.rows() if not r["passed"])
    executed = 0
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=spec.n_runs, initial=len(done), unit="run", desc=spec.name,
                   file=sys.stderr, smoothing=0.1)  # fmt: skip
        bar.set_postfix_str(f"failed {fails}")
    try:
        if client is not None:
            it = iter_dask(batches, client, spec.digest)
        else:
            it = iter_local(batches, slots)
        try:
            for rows in it:
                new = store.append(rows)
                executed += len(new)
                fails += sum(1 for r in new if not r["passed"])
                if bar is not None:
                    bar.update(len(new))
                    bar.set_postfix_str(f"failed {fails}")
                if on_progress is not None:
                    on_progress(len(store.done()), spec.n_runs, fails)
        finally:
            close = getattr(it, "close", None)
            if close is not None:
                close()
    finally:
        if bar is not None:
            bar.close()
        if client is not None:
            client.close()
    rows = store.rows()
    summary = summarize(rows, spec)
    outp = Path(out)
    files = [store.csv_path]
    (outp / "summary.json").write_text(json.dumps(summary, indent=1) + "\n", encoding="utf-8")
    (outp / "summary.md").write_text(summary_markdown(summary), encoding="utf-8")
    files += [outp / "summary.json", outp / "summary.md"]
    pq = write_parquet(rows, outp / "runs.parquet")
    if pq is not None:
        files.append(pq)
    if plots and rows:
        from virtual_drive.sweep.plots import write_plots

        files += write_plots(rows, spec, outp, map_axes or spec.map)
    return SweepResult(rows, summary, outp, executed, len(done), files)
