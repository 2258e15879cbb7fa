"""Local engine: a process pool on this machine (default: all cores).

Each task is a batch of runs (:func:`~.runner.run_batch`); rows come back to the client, which
alone writes them. The workers are forked from a ``forkserver`` that has the simulator
imported (no threads are forked). A worker that dies breaks the pool: the batches not yet
returned are run again in a new pool (at most three times), so nothing is lost and, as the
client keeps only the first row of a run, nothing is counted twice.
"""

from __future__ import annotations

import multiprocessing as mp
import os
from collections.abc import Iterator
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Any

from virtual_drive.sweep.runner import run_batch
from virtual_drive.sweep.spec import RunJob

__all__ = ["default_workers", "iter_local"]

_MAX_RESTARTS = 3


def default_workers() -> int:
    """Cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover
        return os.cpu_count() or 1


def iter_local(batches: list[list[RunJob]], workers: int) -> Iterator[list[dict[str, Any]]]:
    """Yield the rows of each batch as it completes (any order)."""
    if workers <= 1:
        for b in batches:  # no pool: the same code in this process
            yield run_batch(b)
        return
    ctx = mp.get_context("forkserver")
    ctx.set_forkserver_preload(["virtual_drive.sweep.runner"])
    pending = dict(enumerate(batches))
    restarts = 0
    while pending:
        ex = ProcessPoolExecutor(max_workers=min(workers, len(pending)), mp_context=ctx)
        broken = False
        try:
            futs = {ex.submit(run_batch, b): i for i, b in pending.items()}
            todo = set(futs)
            while todo and not broken:
                done, todo = wait(todo, return_when=FIRST_COMPLETED)
                for f in done:
                    try:
                        rows = f.result()
                    except BrokenProcessPool:
                        broken = True
                        continue
                    del pending[futs[f]]
                    yield rows
        finally:
            ex.shutdown(wait=not broken and not pending, cancel_futures=True)
        if broken:
            restarts += 1
            if restarts > _MAX_RESTARTS:
                first = min(b[0].run for b in pending.values())
                raise RuntimeError(
                    f"worker processes died {restarts} times (runs from {first} not done)"
                )
