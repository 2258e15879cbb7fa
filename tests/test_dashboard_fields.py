"""Pure parts of the bench GUI: strict parsing of typed numbers, plot decimation, freshness text
and display units. Truths: the typed text itself (no value may differ from what was typed),
numpy's own min/max of the full series, and the SI prefixes (1 µH = 1e-6 H, 1 mΩ = 1e-3 Ω).
"""

from __future__ import annotations

import numpy as np
import pytest

from dashboard._fields import FieldError, NumberSpec, show
from dashboard._gui_panel import parse_sequence
from dashboard._live_plot import decimate, freshness_text
from dashboard._tuning import display, preview_markdown

pytestmark = pytest.mark.unit

RATIO = NumberSpec("L_c / L", 0.0, 3.0, lo_open=True)
LC_UH = NumberSpec("L_c (µH)", 0.0, 2000.0, lo_open=True)


@pytest.mark.parametrize("text", ["-0.5", "−0.5", "0", "3.5", "abc", "", "nan", "inf", "1e400",
                                  "1_0", "1,5", "0x10", "1 2", "--1"])
def test_refused_never_changed(text):
    with pytest.raises(FieldError) as exc:
        RATIO.parse(text)
    assert "L_c / L" in str(exc.value)


def test_negative_inductance_is_refused_not_moved():
    with pytest.raises(FieldError, match="-5 is outside"):
        LC_UH.parse("-5")


@pytest.mark.parametrize("text,value", [("0.5", 0.5), (" 1.5 ", 1.5), ("+2", 2.0), ("1e-3", 1e-3),
                                        (".25", 0.25), ("3", 3.0)])
def test_accepted_exactly_as_typed(text, value):
    assert RATIO.parse(text) == value


def test_integer_fields_and_show():
    n = NumberSpec("Length (samples)", 2, 8192, integer=True)
    assert n.parse("1000") == 1000
    with pytest.raises(FieldError):
        n.parse("10.5")
    assert show(2.9994e-5) == "2.9994e-05" and show(14.8) == "14.8" and show(-0.5) == "-0.5"
    assert float(show(0.9999785)) == 0.9999785


def test_sequence_is_strict():
    assert parse_sequence("0:1000, 3:1500") == [(0.0, 1000.0), (3.0, 1500.0)]
    for bad in ("0:1000, 3", "3:10, 1:20", "0:7000", "x:1", ""):  # 7000 > target_velocity
        with pytest.raises(FieldError):
            parse_sequence(bad)


def test_decimate_keeps_extremes_and_newest():
    rng = np.random.default_rng(1)
    t = np.linspace(0.0, 4.0, 4000)
    a = np.cumsum(rng.normal(size=t.size))
    b = np.where(t > 3.99, 500.0, 0.0)  # a setpoint step in the very last samples
    td, (ad, bd) = decimate(t, [a, b], buckets=100)
    assert len(td) <= 3 * 100 + 2 + 2 * 100  # at most min, max, last per bucket (+ ends)
    assert ad.max() == a.max() and ad.min() == a.min()
    assert td[-1] == t[-1] and bd[-1] == 500.0 and ad[-1] == a[-1]
    assert np.all(np.diff(td) > 0)


def _decimate_by_loops(t, cols, buckets):
    """The oracle: bucket by bucket in Python, the first min and max of each series, each
    bucket's last sample, the first and the last sample."""
    n = len(t)
    edges = np.linspace(t[0], t[-1], buckets + 1)
    b = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, buckets - 1)
    keep = {0, n - 1}
    start = 0
    for i in range(1, n + 1):
        if i == n or b[i] != b[start]:
            keep.add(i - 1)
            for c in cols:
                ok = np.isfinite(c)
                fill = np.nanmean(c) if ok.any() else 0.0
                seg = np.where(ok[start:i], c[start:i], fill)
                keep.update((start + int(np.argmin(seg)), start + int(np.argmax(seg))))
            start = i
    idx = np.array(sorted(keep))
    return t[idx], [c[idx] for c in cols]


@pytest.mark.parametrize("spacing", ["even", "gaps"])  # the 2D path and the segment path
def test_decimate_equals_a_bucket_by_bucket_oracle(spacing):
    rng = np.random.default_rng(4)
    n = 4000
    step = np.full(n, 1e-3) if spacing == "even" else np.where(rng.random(n) < 0.02, 0.3, 1e-3)
    t = np.cumsum(step)
    cols = [np.round(rng.normal(size=n), 1), np.where(t > t[-1] / 2, 5.0, 0.0), rng.normal(size=n)]
    cols[2][rng.random(n) < 0.05] = np.nan
    td, cd = decimate(t, cols, buckets=80)
    to, co = _decimate_by_loops(t, cols, 80)
    np.testing.assert_array_equal(td, to)
    for got, want in zip(cd, co, strict=True):
        np.testing.assert_array_equal(got, want)


def test_freshness_text():
    assert freshness_text(0.04) == (False, "live · data 0.04 s old")
    stale, txt = freshness_text(3.2)
    assert stale and "3.2 s" in txt
    assert freshness_text(None)[0] is True
    assert freshness_text(0.01, push_age_s=2.0)[0] is True


def test_display_units_and_unstable_preview():
    assert display("L_c", 14.8e-6) == "14.8 µH"
    assert display("R_c", 6.2e-3) == "6.2 mΩ"
    m = {"stable": False, "gain_margin_dB": 3.0, "phase_margin_deg": 20.0, "S_inf": 4.0,
         "max_pole_radius": 1.2}
    s = {**m, "stable": True, "max_pole_radius": 0.99995, "a": 0.99, "b": 1e-4}
    md = preview_markdown({"current": {**m, "controller": "pi", "L_c_over_L": 1.9}, "speed": s})
    first, second = md.split("  \n")[1:3]
    assert "UNSTABLE" in first and "‖S‖∞" not in first  # no margins for an unstable loop
    assert "0.99995" in second
