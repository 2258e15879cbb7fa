"""Fixtures of the scenario matrix: ``condition`` (parametrised, ids = condition names) and
``bench`` (one virtual drive per condition, shared by the scenarios of that condition)."""

from __future__ import annotations

import pytest

from .conditions import Bench, Condition, selected

_CONDITIONS = selected()


@pytest.fixture(scope="module", params=_CONDITIONS, ids=[c.name for c in _CONDITIONS])
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
