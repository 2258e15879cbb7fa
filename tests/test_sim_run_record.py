"""Simulator.run_record (the sweep's path): the chosen signals of chunked calls equal the full
record of one ``run`` call of an identical simulator; bad arguments change nothing."""

from __future__ import annotations

import numpy as np
import pytest

from virtual_drive.sim import Simulator

pytestmark = pytest.mark.unit


def _sim() -> Simulator:
    s = Simulator()
    s.set_speed(1200.0)
    s.set_mode("speed")
    s.set_speed_ref(1300.0)
    return s


def test_chunks_into_preallocated_arrays_equal_one_run():
    ref = _sim().run(3000)
    sim = _sim()
    out = {k: np.full(3000, np.nan, dtype=np.float32) for k in ("i_p", "speed", "i_a")}
    sim.run_record(1000, out)
    sim.run_record(2000, out, start=1000)
    for k, v in out.items():
        assert np.array_equal(v, ref[k]), k
    assert sim.sample_index == 3000


@pytest.mark.parametrize(
    "out",
    [
        {"nope": np.zeros(10, dtype=np.float32)},
        {"i_p": np.zeros(10, dtype=np.float64)},
        {"i_p": np.zeros(5, dtype=np.float32)},
        {"i_p": np.zeros(20, dtype=np.float32)[::2]},
    ],
)
def test_bad_buffers_are_refused_and_nothing_runs(out):
    sim = _sim()
    with pytest.raises(ValueError):
        sim.run_record(10, out)
    assert sim.sample_index == 0
