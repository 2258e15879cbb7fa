"""``Simulator.run_points``: one C call for a pacing tick that keeps the values of chosen
instants. Truth: running the same samples as separate chunks gives the values at the chunk
ends (the simulation is deterministic and a chunk boundary changes nothing), and the recorded
arrays of ``run`` hold every sample's values."""

from __future__ import annotations

import numpy as np
import pytest

from virtual_drive.sim import Simulator
from virtual_drive.sim.signals import SIGNALS

pytestmark = pytest.mark.unit


def _driven() -> Simulator:
    sim = Simulator()
    sim.set_mode("current")
    sim.set_current_ref(20.0)
    return sim


def test_rows_are_the_values_after_each_count_and_at_the_end():
    a, b = _driven(), _driven()
    at = [0, 1, 50, 50, 137, 250]
    rows = np.array(a.run_points(300, at), dtype=np.float32)
    rec = b.run(300, record=True)
    assert rows.shape == (len(at) + 1, len(SIGNALS))
    for j, k in enumerate([*at, 300]):
        if k == 0:
            continue  # (nothing run yet: the values before the call)
        expected = np.array([rec[name][k - 1] for name in SIGNALS], dtype=np.float32)
        np.testing.assert_array_equal(rows[j], expected)
    assert a.time == pytest.approx(b.time)
    assert a.speed_rpm == b.speed_rpm  # same state after the call


def test_a_count_beyond_the_chunk_is_the_chunk_end():
    sim = _driven()
    rows = sim.run_points(100, [40, 400])
    assert rows[1] == rows[2]
    assert sim.sample_index == 100


@pytest.mark.parametrize("at", [[5, 3], [-1], list(range(65))])
def test_bad_counts_are_refused_and_nothing_runs(at):
    sim = _driven()
    with pytest.raises(ValueError):
        sim.run_points(100, at)
    assert sim.sample_index == 0
