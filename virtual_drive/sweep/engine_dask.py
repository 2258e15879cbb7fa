"""Dask engine: the same batches on a Dask distributed cluster (``--scheduler tcp://HOST:PORT``).

Needs the optional extra ``sweep`` (``pip install -e '.[sweep]'``: dask[distributed], pyarrow)
on the client and on every worker, with this package installed (the task is
:func:`virtual_drive.sweep.runner.run_batch`, sent by reference). Results travel back to this
client, which alone writes them. When a worker dies, the scheduler runs its unfinished tasks
again on another worker; each future completes once, and the client keeps only the first row
of a run, so no run is lost or counted twice.

Start a cluster on one machine, every listener on 127.0.0.1 (``--no-dashboard`` alone still
binds a dashboard on 0.0.0.0, so give the dashboards 127.0.0.1 and a free port)::

    dask scheduler --host 127.0.0.1 --port 8786 --dashboard-address 127.0.0.1:0
    dask worker tcp://127.0.0.1:8786 --host 127.0.0.1 --nworkers 2 --nthreads 1 \
        --dashboard-address 127.0.0.1:0
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

from virtual_drive.sweep.runner import run_batch
from virtual_drive.sweep.spec import RunJob
from virtual_drive.sweep.units import SpecError

__all__ = ["connect", "iter_dask"]


def connect(address: str, timeout: float = 10.0) -> Any:
    """A ``distributed.Client`` on ``address`` (SpecError if dask is missing or unreachable)."""
    try:
        from distributed import Client
    except ImportError:
        raise SpecError(
            "--scheduler needs dask.distributed: pip install 'bldc-bench[sweep]'"
        ) from None
    try:
        return Client(address, timeout=timeout, set_as_default=False)
    except (OSError, TimeoutError) as exc:
        raise SpecError(f"cannot reach the Dask scheduler {address}: {exc}") from None


def cluster_threads(client: Any) -> int:
    """Threads of all workers now connected (at least 1)."""
    nthreads: dict[str, int] = client.nthreads()  # (worker address -> threads)
    return max(1, sum(nthreads.values()))


def iter_dask(
    batches: list[list[RunJob]], client: Any, tag: str
) -> Iterator[list[dict[str, Any]]]:
    """Yield the rows of each batch as it completes (any order); ``tag`` makes the task keys
    (``sweep-<tag>-<first run>``) unique to the spec."""
    from distributed import as_completed

    futs = [
        client.submit(run_batch, b, key=f"sweep-{tag}-{b[0].run}", pure=False) for b in batches
    ]
    try:
        for fut in as_completed(futs, loop=client.loop):
            yield fut.result()
    finally:
        client.cancel([f for f in futs if not f.done()])
