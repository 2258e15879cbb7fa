"""Fixtures of the scenario matrix: ``condition`` (parametrised, ids = condition names) and
``bench`` (one virtual drive per condition, shared by the scenarios of that condition)."""

from __future__ import annotations

import pytest

from .conditions import Bench, Condition, selected

_CONDITIONS = selected()


def _time_limit(c: Condition) -> float:
    """Per-test limit (s): 240 s × the condition's slowness (a 64 KiB upload at 5 % loss on a
    busy host took over 240 s with its retries), 900 s on SocketCAN in UML."""
    return 900.0 if c.channel else 240.0 * max(1.0, c.slow)


@pytest.fixture(
    scope="module",
    params=[
        pytest.param(c, id=c.name, marks=pytest.mark.timeout(_time_limit(c))) for c in _CONDITIONS
    ],
)
def condition(request) -> Condition:
    return request.param


@pytest.fixture(scope="module")
def bench(condition: Condition):
    """Bus + ``virtual-drive run`` child (+ busy CPU) for one condition; always cleaned up."""
    b = Bench(condition).start()
    try:
        yield b
    finally:
        alive = b.drive_alive
        tail = b.proc.stderr_tail if b.proc is not None else ""
        b.stop()
        if not alive:
            pytest.fail(f"[{condition.name}] virtual drive died during the run: {tail[-300:]}")
