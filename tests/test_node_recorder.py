"""Trace recorder logic on synthetic chunk streams, against a per-sample reference written
here from the definitions in docs/contracts.md §1 (0x2100): decimation from the arm instant,
pre-trigger part, rising/falling/either crossings, setpoint steps, forced trigger; chunk sizes
vary at random so every boundary case is crossed."""

from __future__ import annotations

import numpy as np
import pytest

from virtual_drive.node.recorder import (
    DONE,
    EDGE_EITHER,
    EDGE_FALLING,
    EDGE_RISING,
    MODE_CROSSING,
    MODE_IMMEDIATE,
    MODE_STEP,
    TraceConfigError,
    TraceRecorder,
)

pytestmark = [pytest.mark.timeout(60), pytest.mark.unit]


def signals(n: int, seed: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 20e-6
    x = (10 * np.sin(2 * np.pi * 37 * t) + rng.normal(0, 0.5, n)).astype(np.float32)
    ref = np.repeat(rng.integers(0, 4, n // 700 + 1) * 5.0, 700)[:n].astype(np.float32)
    return {"t": t, "x": x, "y": -x, "ref": ref}


def feed_in_chunks(rec: TraceRecorder, sig: dict, seed: int) -> None:
    rng = np.random.default_rng(seed)
    pos, n = 0, len(sig["t"])
    while pos < n and rec.state != DONE:
        k = int(rng.integers(1, 400))
        rec.feed({name: a[pos : pos + k] for name, a in sig.items()}, setpoint="ref")
        pos += k


def reference(sig, channels, divider, length, pre, mode, level=0.0, edge=EDGE_RISING):
    """Per-sample reading of the contract (armed at sample 0)."""
    idx = list(range(0, len(sig["t"]), divider))
    src = sig["x"] if mode == MODE_CROSSING else sig["ref"]
    trig = None
    if mode == MODE_IMMEDIATE:
        trig = 0
    for j in range(1, len(idx)):
        if trig is not None or j < pre:
            continue
        a, b = src[idx[j - 1]], src[idx[j]]
        if mode == MODE_CROSSING:
            up = a < level <= b
            down = a > level >= b
            hit = {EDGE_RISING: up, EDGE_FALLING: down, EDGE_EITHER: up or down}[edge]
        else:
            hit = a != b
        if hit:
            trig = j
    if trig is None:
        return None, None
    start = trig - min(pre, trig)
    rows = idx[start : start + length]
    data = np.stack([sig[c][rows] for c in channels], axis=1)
    return data, trig - start


@pytest.mark.parametrize(
    "divider, length, pre, mode, edge, level",
    [
        (1, 600, 100, MODE_CROSSING, EDGE_RISING, 5.0),
        (3, 500, 0, MODE_CROSSING, EDGE_FALLING, -2.0),
        (7, 300, 299, MODE_CROSSING, EDGE_EITHER, 0.0),
        (1, 1000, 250, MODE_STEP, EDGE_RISING, 0.0),
        (5, 200, 50, MODE_STEP, EDGE_RISING, 0.0),
        (2, 700, 0, MODE_IMMEDIATE, EDGE_RISING, 0.0),
    ],
)
@pytest.mark.parametrize("seed", [1, 2])
def test_capture_matches_per_sample_reference(divider, length, pre, mode, edge, level, seed):
    sig = signals(60_000, seed)
    rec = TraceRecorder()
    rec.channels, rec.divider, rec.length, rec.pre_trigger = ["x", "y"], divider, length, pre
    rec.trigger_mode, rec.trigger_edge, rec.trigger_level = mode, edge, level
    rec.trigger_source = "x"
    rec.arm()
    feed_in_chunks(rec, sig, seed + 10)
    expected, position = reference(sig, ["x", "y"], divider, length, pre, mode, level, edge)
    assert rec.state == DONE
    assert rec.trigger_position == position
    np.testing.assert_array_equal(rec.data_array(), expected)
    raw = np.frombuffer(rec.data_bytes(), "<f4").reshape(-1, 2)
    np.testing.assert_array_equal(raw, expected)


def test_forced_trigger_takes_what_the_ring_holds():
    sig = signals(5000, 3)
    rec = TraceRecorder()
    rec.channels, rec.length, rec.pre_trigger = ["x"], 100, 80
    rec.trigger_mode, rec.trigger_level, rec.trigger_source = MODE_CROSSING, 1e9, "x"
    rec.arm()
    rec.feed({k: v[:30] for k, v in sig.items()})
    rec.force()
    rec.feed({k: v[30:300] for k, v in sig.items()})
    assert rec.state == DONE and rec.trigger_position == 30
    np.testing.assert_array_equal(rec.data_array()[:, 0], sig["x"][:100])


def test_configuration_checks():
    rec = TraceRecorder()
    with pytest.raises(TraceConfigError):
        rec.check(["x"] * 2, 9000, 0, 1)  # 18000 > 16384 samples
    with pytest.raises(TraceConfigError):
        rec.check(["x"], 100, 100, 1)  # pre_trigger must be < length
    with pytest.raises(TraceConfigError):
        rec.check([], 100, 0, 1)
    assert rec.data_bytes() == b""  # nothing before a capture completes
