"""The status bar's texts and the dropped-frame rate (issue 24), without a browser.

Truths: the CiA 402 state names and their meaning (CiA 402-2: OPERATION ENABLED = power on,
FAULT = fault), the mode in use (a setpoint of another mode is not shown), and the definition
of a rate (frames per second over a window: a counter that steps back is a new window, never a
negative rate).
"""

from __future__ import annotations

import re

import pytest

from dashboard._gui import BenchGui
from dashboard._gui_status import setpoints_text, status_html
from dashboard._gui_statusbar import GREEN, RED, badges_html, fresh_badge

pytestmark = pytest.mark.unit


def _state(**kw):
    s = {
        "bus": "hub",
        "node_id": 1,
        "nmt_state": "OPERATIONAL",
        "state": "OPERATION ENABLED",
        "mode": "speed",
        "speed_setpoint": 1000.0,
        "current_setpoint": 0.0,
        "heartbeat_age_s": 0.05,
        "ages_s": {"live": 0.01, "heartbeat": 0.05, "statusword": 0.01, "mode": 0.2},
        "stale": [],
        "emcy": [],
        "live": {"bus_load": 0.25, "dropped": 0, "tpdo": {}},
    }
    s.update(kw)
    return s


LATEST = {"measurements.speed": 998.0, "measurements.i_p": 65.6}


def test_speed_mode_shows_no_current_setpoint_and_current_mode_no_speed_setpoint():
    speed = setpoints_text(_state(mode="speed"), LATEST)
    assert "(set 1000)" in speed and not re.search(r"i_p [^·]*\(set", speed)
    current = setpoints_text(_state(mode="current", current_setpoint=20.0), LATEST)
    assert "(set 20.0)" in current and "(set 1000)" not in current
    unknown = setpoints_text(_state(mode=None), LATEST)
    assert "(set" not in unknown
    assert "(set 0.0)" not in status_html(_state(mode="speed"), LATEST, 0.0, False, "live")


def test_state_badges_are_coloured_by_meaning():
    enabled = badges_html(_state())
    assert re.search(rf"background:{GREEN}'[^>]*>OPERATION ENABLED<", enabled)
    fault = badges_html(
        _state(state="FAULT", emcy=[{"code": 0x2310, "text": "overcurrent"}])
    )
    assert re.search(rf"background:{RED}'[^>]*>FAULT<", fault)
    assert "FAULT 0x2310 overcurrent" in fault
    # a statusword that stopped arriving is not shown as a live state
    old = badges_html(_state(stale=["statusword"], ages_s={"statusword": 3.2}))
    assert "OPERATION ENABLED (3.2 s old)" in old
    assert not re.search(rf"background:{GREEN}'[^>]*>OPERATION ENABLED<", old)


def test_every_tick_sends_a_different_freshness_badge_with_the_page_side_switch():
    a, b = fresh_badge(False, "live · data 0.01 s old", 1), fresh_badge(False, "x", 2)
    assert a != fresh_badge(False, "live · data 0.01 s old", 2)  # the page re-creates it
    assert "bench-dead" in a and "bench-dead" in b
    assert RED in fresh_badge(True, "STALE · newest data 2.0 s old", 3)


def test_the_dropped_rate_is_never_negative(monkeypatch):
    """drive_link's dropped total is an estimate that can step back (a late frame arrives,
    counters reset): the old rate went to −1.5 frames/s."""
    gui = BenchGui.__new__(BenchGui)
    gui._drops = []
    now = [100.0]
    monkeypatch.setattr("dashboard._gui.time.monotonic", lambda: now[0])
    rates = []
    for total in (10, 12, 14, 9, 9, 11, 11, 0, 0, 3):
        now[0] += 0.6
        rates.append(gui._drop_rate(total))
    assert all(r >= 0.0 for r in rates), rates
    assert rates[2] == pytest.approx(4 / 1.2)  # 10 → 14 in 1.2 s
    assert rates[-1] == pytest.approx(3 / 1.2)  # counted again after the reset to 0
