"""Trace recorder 0x2100–0x2102 and SDO block upload with canopen's own block client.

Truth: the simulator's own full-rate record of the same samples (a tap on the drive's chunk
stream), and the trigger definitions of docs/contracts.md §1."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest
from canopen.sdo import SdoAbortedError
from test_node_support import Bench

pytestmark = [pytest.mark.timeout(60), pytest.mark.unit]

REF_I_P = 0x20400120
REF_I_P_REF = 0x20400A20
REF_SPEED = 0x20400520


class Tap:
    """Collects every chunk the simulator produced (the core's own record)."""

    def __init__(self) -> None:
        self.chunks: list[dict] = []
        self.lock = threading.Lock()

    def __call__(self, rec: dict) -> None:
        with self.lock:
            self.chunks.append({k: np.array(rec[k]) for k in ("t", "i_p", "i_p_ref", "speed")})

    def record(self) -> dict[str, np.ndarray]:
        with self.lock:
            return {k: np.concatenate([c[k] for c in self.chunks]) for k in self.chunks[0]}


@pytest.fixture(scope="module")
def bench():
    b = Bench(speed=1.0, sdo2=True)
    b.tap = Tap()
    b.drive.taps.append(b.tap)
    b.enable(-1)
    b.write("setpoints.i_p_ref", 15.0)
    assert b.wait(lambda: abs(b.read("measurements.i_p") - 15.0) < 1.0)
    yield b
    b.close()


def configure(bench, channels, length, pre, divider=1, mode=2, source=REF_I_P, level=0.0):
    bench.write("trace_config.pre_trigger", 0)
    bench.write("trace_config.length", 1)
    bench.write("trace_config.channel_count", len(channels))
    for k, ref in enumerate(channels, 1):
        bench.write(f"trace_channels.channel_{k}", ref)
    bench.write("trace_config.length", length)
    bench.write("trace_config.pre_trigger", pre)
    bench.write("trace_config.divider", divider)
    bench.write("trace_config.trigger_mode", mode)
    bench.write("trace_config.trigger_source", source)
    bench.write("trace_config.trigger_level", level)
    bench.write("trace_config.trigger_edge", 0)


def block_upload(bench) -> bytes:
    with bench.node.sdo.open(0x2102, 0, "rb", block_transfer=True) as f:
        return f.read()


def as_samples(data: bytes, n_channels: int) -> np.ndarray:
    return np.frombuffer(data, dtype="<f4").reshape(-1, n_channels)



def wait_samples(bench, n: int) -> None:
    """Wait until the drive's loop has run ``n`` more samples (e.g. a pre-trigger part), however
    long a busy host keeps it from running (a fixed sleep assumed an idle machine)."""
    s0 = bench.drive.runner.stats.samples
    assert bench.wait(lambda: bench.drive.runner.stats.samples - s0 >= n, 10.0), "loop stalled"

def test_step_capture_equals_the_core_record(bench):
    configure(bench, [REF_I_P, REF_I_P_REF], length=2000, pre=200, mode=2)
    bench.write("trace_config.command", 1)
    assert bench.read("trace_config.state") == 1
    wait_samples(bench, 2 * 200)  # let the pre-trigger part fill (200 samples = 4 ms)
    bench.write("setpoints.i_p_ref", 20.0)
    assert bench.wait(lambda: bench.read("trace_config.state") == 3, 2.0)
    data = block_upload(bench)
    assert len(data) == 2000 * 2 * 4
    trace = as_samples(data, 2)
    pos = bench.read("trace_config.trigger_position")
    assert pos == 200
    rec = bench.tap.record()
    steps = np.flatnonzero((rec["i_p_ref"][1:] == 20.0) & (rec["i_p_ref"][:-1] == 15.0)) + 1
    k = int(steps[-1])  # the core's first sample at the new reference
    expected = np.stack([rec["i_p"][k - 200 : k + 1800], rec["i_p_ref"][k - 200 : k + 1800]], 1)
    np.testing.assert_array_equal(trace, expected)
    # the step itself is in the data: 15 A before, deadbeat response reaches 20 A after
    assert trace[199, 1] == 15.0 and trace[200, 1] == 20.0
    assert abs(trace[-1, 0] - 20.0) < 1.0
    # segmented upload (fallback) gives the same bytes
    assert bench.node.sdo.upload(0x2102, 0) == data
    bench.write("setpoints.i_p_ref", 15.0)


def test_crossing_trigger_with_divider(bench):
    configure(bench, [REF_I_P], length=400, pre=100, divider=5, mode=1, level=17.5)
    bench.write("setpoints.i_p_ref", 15.0)
    wait_samples(bench, 1000)
    bench.write("trace_config.command", 1)
    wait_samples(bench, 2 * 100 * 5)  # pre-trigger: 100 samples at divider 5
    bench.write("setpoints.i_p_ref", 20.0)
    assert bench.wait(lambda: bench.read("trace_config.state") == 3, 2.0)
    trace = as_samples(block_upload(bench), 1)[:, 0]
    pos = bench.read("trace_config.trigger_position")
    assert pos == 100
    assert trace[pos - 1] < 17.5 <= trace[pos]
    full = bench.tap.record()["i_p"]
    # the data is every 5th loop sample of the core's record, consecutive
    hits = [o for o in range(len(full) - 5 * 400) if full[o] == trace[0]]
    assert any(np.array_equal(full[o : o + 5 * 400 : 5], trace) for o in hits)
    bench.write("setpoints.i_p_ref", 15.0)


def test_pre_trigger_filled_follows_the_drive_samples(bench):
    """0x2100:13 counts the pre-trigger samples the drive holds: 0 when idle, rising to
    pre_trigger no sooner than (pre_trigger − 1) × divider + 1 loop samples after arm; a step
    made as soon as it is full is the trigger (at trigger_position = pre_trigger)."""
    bench.write("trace_config.command", 0)
    configure(bench, [REF_I_P, REF_I_P_REF], length=400, pre=150, divider=4, mode=2)
    bench.write("setpoints.i_p_ref", 15.0)
    held = bench.read("trace_config.pre_trigger_filled")  # idle: 0; done: the last capture's
    last = bench.read("trace_config.trigger_position")
    assert held == (0 if bench.read("trace_config.state") == 0 else last), (held, last)
    s0 = bench.drive.runner.stats.samples
    bench.write("trace_config.command", 1)
    seen = []
    assert bench.wait(
        lambda: seen.append(bench.read("trace_config.pre_trigger_filled")) or seen[-1] == 150,
        10.0,
    ), f"pre_trigger_filled went {seen[:5]} … {seen[-5:]}"
    ran = bench.drive.runner.stats.samples - s0
    # the first sample is taken at the arm instant, the 150th 149 × 4 loop samples later
    assert ran >= 149 * 4 + 1, f"full after only {ran} loop samples (149 × divider 4 + 1)"
    assert all(0 <= v <= 150 for v in seen) and seen == sorted(seen), seen
    assert bench.read("trace_config.state") == 1  # still armed: no step yet
    bench.write("setpoints.i_p_ref", 20.0)
    assert bench.wait(lambda: bench.read("trace_config.state") == 3, 2.0)
    assert bench.read("trace_config.trigger_position") == 150
    assert bench.read("trace_config.pre_trigger_filled") == 150
    bench.write("trace_config.command", 0)
    bench.write("setpoints.i_p_ref", 15.0)


def test_forced_trigger_and_no_data_before_done(bench):
    configure(bench, [REF_I_P, REF_SPEED], length=3000, pre=10, mode=1, level=1e5)
    bench.write("trace_config.command", 1)
    with pytest.raises(SdoAbortedError) as exc:  # nothing recorded yet
        bench.node.sdo.upload(0x2102, 0)
    assert exc.value.code == 0x08000024
    with pytest.raises(SdoAbortedError) as exc:  # configuration frozen while armed
        bench.write("trace_config.length", 100)
    assert exc.value.code == 0x08000022
    time.sleep(0.02)
    assert bench.read("trace_config.state") == 1  # level never crossed
    bench.write("trace_config.command", 2)  # force
    assert bench.wait(lambda: bench.read("trace_config.state") == 3, 2.0)
    assert len(block_upload(bench)) == 3000 * 2 * 4


def test_capacity_limit(bench):
    bench.write("trace_config.channel_count", 1)
    bench.write("trace_config.length", 16384)
    with pytest.raises(SdoAbortedError) as exc:
        bench.write("trace_config.channel_count", 2)  # 2 x 16384 > 16384 samples
    assert exc.value.code == 0x06090031
    with pytest.raises(SdoAbortedError) as exc:
        bench.write("trace_channels.channel_1", 0x60410010)  # not a measurement
    assert exc.value.code == 0x06090030


def test_full_64k_trace_upload_while_status_reads_on_second_sdo(bench):
    configure(bench, [REF_I_P, REF_I_P_REF, REF_SPEED, REF_I_P], length=4096, pre=0, mode=0)
    bench.write("trace_config.command", 1)
    assert bench.wait(lambda: bench.read("trace_config.state") == 3, 2.0)
    result = {}

    def upload():
        result["data"] = block_upload(bench)

    th = threading.Thread(target=upload)
    th.start()
    reads = 0
    while th.is_alive():
        sw = bench.sdo2[0x6041].raw  # second SDO server 0x1201 (0x681/0x6B1)
        assert sw & 0x6F == 0x27
        reads += 1
    th.join()
    assert len(result["data"]) == 65536
    assert reads >= 3
    trace = as_samples(result["data"], 4)
    np.testing.assert_array_equal(trace[:, 0], trace[:, 3])


def test_fault_trigger_captures_the_trip(bench):
    """Trigger mode 3: the trigger sample is the first sample at or after the trip instant."""
    configure(bench, [REF_I_P, REF_I_P_REF], length=500, pre=100, mode=3)
    bench.write("trace_config.command", 1)
    wait_samples(bench, 2 * 100)
    bench.write("sim_fault.inject", 2)  # DC-link overvoltage trip
    assert bench.wait(lambda: bench.read("statusword") & 0x4F == 0x08)
    assert bench.wait(lambda: bench.read("trace_config.state") == 3, 2.0)
    assert bench.read("error_code") == 0x3210
    trace = as_samples(block_upload(bench), 2)
    assert bench.read("trace_config.trigger_position") == 100
    t_trip = bench.drive.sim.fault.t  # the core's own trip instant (s)
    rec = bench.tap.record()
    k = int(np.flatnonzero(rec["t"] >= t_trip - 1e-9)[0])
    np.testing.assert_array_equal(trace[:, 0], rec["i_p"][k - 100 : k + 400])
    assert abs(trace[99, 0] - 15.0) < 1.5  # regulating before the trip
    # recover for any later test
    bench.write("controlword", 0x80)
    bench.enable(-1)
