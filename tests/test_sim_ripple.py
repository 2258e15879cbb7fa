"""The edge-sampled ripple signals of the simulator (i_p_min, i_p_max, i_p_peaks, 0x2040:15-17).

Truths: the unipolar PWM pattern (two pulses of v_L per 20 µs period: two ripple maxima, paper
Sec. IV-B) and the exact switching model's own waveform sampled on a fine grid (64 points per
period, ``run(oversample=64)``): the extremes recorded at the switching edges bound every grid
point and the grid comes within one grid step's change of them. The averaged model has no
ripple.
"""

from __future__ import annotations

import numpy as np
import pytest

from virtual_drive.sim.simulator import Simulator

pytestmark = pytest.mark.unit

OS = 64


def _running(model: str = "pwm") -> Simulator:
    s = Simulator.from_defaults(model)
    s.set_speed(1000.0)
    s.set_mode("current")
    s.set_current_ref(20.0)
    s.run(300)
    return s


def test_extremes_bound_the_fine_waveform_and_two_peaks_per_period():
    r = _running().run(300, oversample=OS)
    t, ip_os = r["os_t"], r["os_i_p"]
    lo, hi, peaks, sec = r["i_p_min"], r["i_p_max"], r["i_p_peaks"], r["hall_sector"]
    checked = 0
    for k in range(2, len(r["t"])):
        if sec[k] != sec[k - 1] or sec[k - 1] != sec[k - 2]:
            continue  # commutation: the pseudo current's definition changes
        sel = (t >= r["t"][k - 1] - 1e-12) & (t <= r["t"][k] + 1e-12)
        w = ip_os[sel]
        assert w.size >= OS
        assert w.max() <= hi[k] + 1e-3 and w.min() >= lo[k] - 1e-3, k
        step = np.max(np.abs(np.diff(w)))  # the most the grid can miss an edge by
        assert hi[k] - lo[k] <= w.max() - w.min() + 2 * step, k
        assert peaks[k] == 2, k
        checked += 1
    assert checked > 250


def test_fast_path_records_the_same_ripple_as_the_general_path():
    """Without oversampling the loop takes its six-step fast path; with it, the general one:
    the same exact model, so the same extremes."""
    a, b = _running(), _running()
    ra, rb = a.run(200), b.run(200, oversample=OS)
    for name in ("i_p_min", "i_p_max", "i_p_peaks", "i_p"):
        np.testing.assert_allclose(ra[name], rb[name], atol=1e-4, err_msg=name)


def test_averaged_model_has_no_pwm_ripple():
    pwm = _running().run(200)
    avg = _running("averaged").run(200)
    pp_pwm = np.median(pwm["i_p_max"] - pwm["i_p_min"])
    pp_avg = np.median(avg["i_p_max"] - avg["i_p_min"])
    assert pp_pwm > 1.0 and pp_avg < 0.05 * pp_pwm
