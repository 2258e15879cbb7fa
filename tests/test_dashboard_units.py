"""Dashboard parts that need no drive: control lease, Origin check, config and CLI refusals,
request-model validation (each is a rule from the issue, checked against its plain statement)."""

from __future__ import annotations

import numpy as np
import pytest
from pydantic import ValidationError

from dashboard._models import GainsIn, SequenceIn, TraceIn
from dashboard._security import ControlLease, LeaseError, allowed_origins, origin_ok
from dashboard.cli import main
from dashboard.config import BenchConfig

pytestmark = [pytest.mark.timeout(30), pytest.mark.unit]


def test_lease_one_controller_and_visible_take_over():
    lease = ControlLease()
    seen = []
    lease.on_change(lambda old, new: seen.append((old and old.client, new and new.client)))
    a = lease.acquire("alice")
    assert lease.check(a.token).client == "alice"
    with pytest.raises(LeaseError):
        lease.acquire("bob")  # no silent steal
    with pytest.raises(LeaseError):
        lease.check("not-the-token")
    with pytest.raises(LeaseError):
        lease.check(None)
    b = lease.acquire("bob", take_over=True)
    assert seen == [(None, "alice"), ("alice", "bob")]
    assert lease.events[-1]["took_from"] == "alice"
    with pytest.raises(LeaseError):
        lease.check(a.token)  # alice now only watches
    assert lease.check(b.token).client == "bob"
    with pytest.raises(LeaseError):
        lease.release(a.token)
    lease.release(b.token)
    assert lease.holder is None
    with pytest.raises(LeaseError):
        lease.check(b.token)


def test_origin_check():
    allowed = allowed_origins("127.0.0.1", [8000, 8080])
    assert origin_ok("http://127.0.0.1:8080", allowed)
    assert origin_ok("http://localhost:8000", allowed)
    assert not origin_ok("http://evil.example:8080", allowed)
    assert not origin_ok("http://127.0.0.1:9999", allowed)
    assert not origin_ok("null", allowed)
    assert origin_ok(None, allowed)  # non-browser client (browsers always send Origin on WS)


@pytest.mark.parametrize(
    "kw, words",
    [
        ({"host": "0.0.0.0", "virtual": True}, "--allow-remote"),
        ({"host": "0.0.0.0", "virtual": True, "allow_remote": True}, "token"),
        ({"host": "0.0.0.0", "virtual": True, "allow_remote": True, "token": "short"}, "12"),
        ({"virtual": False}, "--interface"),
        ({"virtual": True, "node_id": 0}, "1..127"),
        ({"virtual": True, "speed_factor": 0.0}, "speed-factor"),
        ({"virtual": True, "gui_rate_hz": 0.0}, "plot-rate must be 1..60 Hz"),
        ({"virtual": True, "gui_rate_hz": 61.0}, "plot-rate must be 1..60 Hz"),
        ({"virtual": True, "gui_rate_hz": float("nan")}, "plot-rate must be 1..60 Hz"),
    ],
)
def test_config_refuses_unsafe_or_incomplete(kw, words):
    with pytest.raises(ValueError, match=words):
        BenchConfig(**kw).validate()
    BenchConfig(virtual=True).validate()
    BenchConfig(host="0.0.0.0", virtual=True, allow_remote=True, token="x" * 16).validate()


@pytest.mark.parametrize(
    "argv",
    [
        ["--virtual", "--host", "0.0.0.0"],
        ["--virtual", "--allow-remote", "--host", "0.0.0.0"],
        [],
        ["--virtual", "--node", "200"],
        ["--virtual", "--port", "notanumber"],
        ["--virtual", "--plot-rate", "0"],
        ["--virtual", "--plot-rate", "nan"],
        ["--virtual", "--plot-rate", "fast"],
    ],
)
def test_cli_bad_input_one_line_nonzero(argv, capsys):
    code = None
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse
        code = exc.code
    err = capsys.readouterr().err.strip()
    assert code not in (0, None)
    assert len(err.splitlines()) == 1 and "error" in err


def test_gain_model_validation():
    with pytest.raises(ValidationError):
        GainsIn(L_c=-1e-6)
    with pytest.raises(ValidationError):
        GainsIn(Lc=1e-6)  # unknown field: a typo is an error, not ignored
    with pytest.raises(ValidationError):
        GainsIn(type="bangbang")
    with pytest.raises(ValueError, match="no gain"):
        GainsIn().changes()
    assert GainsIn(type="pi", emf_feedforward=True, L_c=1e-5).changes() == {
        "type": 1,
        "emf_feedforward": 1,
        "L_c": 1e-5,
    }


def test_sequence_and_trace_validation():
    with pytest.raises(ValidationError):
        SequenceIn(steps=[{"at_s": 2, "rpm": 0}, {"at_s": 1, "rpm": 100}])
    with pytest.raises(ValidationError):
        TraceIn(channels=["measurements.i_p"] * 2, length=9000)  # 18000 > 16384 capacity
    with pytest.raises(ValidationError):
        TraceIn(length=100, pre_trigger=100)
    with pytest.raises(ValidationError):
        TraceIn(trigger="signal")  # needs a level


def test_min_span_envelope_widens_only_flat_plots():
    """uPlot auto-scales y to the min/max of all series: the envelope makes that span at least
    min_span around flat data, keeps the data inside, and leaves large swings alone."""
    from dashboard._gui import min_span_envelope

    rng = np.random.default_rng(1)
    speed = 500.0 + 0.01 * rng.standard_normal(200)
    ref = np.full(200, 500.0)
    env = min_span_envelope(200, speed, ref, min_span=50.0)
    lo, hi = min(env.min(), speed.min()), max(env.max(), speed.max())
    assert hi - lo >= 50.0 - 1e-9
    assert lo < speed.min() and speed.max() < hi and lo < 500.0 < hi
    jitter = min_span_envelope(200, speed + 0.02, ref, min_span=50.0)
    assert np.array_equal(env, jitter)  # the axis stays still at steady state
    step = np.linspace(0.0, 500.0, 200)
    env = min_span_envelope(200, step, step, min_span=50.0)
    assert env.min() >= 0.0 and env.max() <= 500.0  # does not widen a 500 rpm swing
    i_p = np.full(200, 32.4)
    env = min_span_envelope(200, i_p, i_p, min_span=5.0)
    assert env.max() - env.min() == pytest.approx(5.0)
