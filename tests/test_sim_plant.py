"""Plant, inverter, protection and API behaviour of the virtual drive."""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np
import pytest

from virtual_drive.sim import (
    SIGNALS,
    CurrentControllerParams,
    InverterParams,
    LoadParams,
    MotorParams,
    Simulator,
)

pytestmark = [pytest.mark.timeout(60), pytest.mark.unit]

Ts = 20e-6


def _steady_speed_sim(rpm=1000.0):
    sim = Simulator()
    sim.set_load(J=1e4)  # speed held: a steady operating point
    sim.set_speed(rpm)
    sim.set_mode("current")
    sim.set_current_ref(50.0)
    sim.run(1000, record=False)
    return sim


def test_run_returns_every_signal_at_full_rate():
    sim = Simulator.from_defaults()
    r = sim.run(100)
    assert set(SIGNALS) | {"t"} == set(r)
    for name in SIGNALS:
        assert r[name].dtype == np.float32 and r[name].shape == (100,)
    np.testing.assert_allclose(np.diff(r["t"]), Ts, rtol=1e-9)
    assert sim.sample_index == 100 and sim.time == pytest.approx(100 * Ts)
    assert sim.state["t"] == pytest.approx(99 * Ts)


def test_phase_currents_are_rectangular_120_degrees():
    """Fig. 2 / 9: each phase carries +-i_p for 120 deg, zero for 60 deg, per half-turn."""
    sim = _steady_speed_sim(1000.0)
    r = sim.run(int(2 * 60 / 1000 / 4 / Ts))  # two electrical turns
    i_p = r["i_p"].mean()
    assert i_p == pytest.approx(50.0, abs=0.5)
    for ph in ("i_a", "i_b", "i_c"):
        x = r[ph] / i_p
        on_pos = np.mean(x > 0.8)
        on_neg = np.mean(x < -0.8)
        off = np.mean(np.abs(x) < 0.2)
        assert on_pos == pytest.approx(1 / 3, abs=0.03)
        assert on_neg == pytest.approx(1 / 3, abs=0.03)
        assert off == pytest.approx(1 / 3, abs=0.04)
    # the sum of the phase currents is zero (star, no neutral)
    np.testing.assert_allclose(r["i_a"] + r["i_b"] + r["i_c"], 0.0, atol=1e-3)
    # which phase conducts follows the Hall sector (six-step table of plant.h)
    plus = {1: "i_a", 2: "i_a", 3: "i_b", 4: "i_b", 5: "i_c", 6: "i_c"}
    for s, ph in plus.items():
        sel = r["hall_sector"] == s
        assert np.median(r[ph][sel]) > 0.8 * i_p


def test_ripple_is_at_100kHz():
    """Unipolar PWM: each leg switches at 50 kHz, the line voltage and i_p ripple at 100 kHz."""
    sim = Simulator()
    sim.set_load(J=1e4)
    sim.set_motor(emf_rounding=0.0)
    sim.set_speed(1900.0, theta_e=np.deg2rad(58.0))  # mid sector, m ~ 0.5
    sim.set_current_gains(emf_feedforward=True)
    sim.set_mode("current")
    sim.set_current_ref(20.0)
    sim.run(3, record=False)
    n_os = 32
    r = sim.run(8, oversample=n_os)
    x = r["os_i_p"] - r["os_i_p"].mean()
    spec = np.abs(np.fft.rfft(x * np.hanning(len(x))))
    f = np.fft.rfftfreq(len(x), Ts / n_os)
    peak = f[np.argmax(spec[1:]) + 1]
    assert peak == pytest.approx(100e3, rel=0.05)
    assert spec[np.argmin(np.abs(f - 50e3))] < 0.2 * spec.max()


def test_emf_shape_trapezoid_with_rounded_corners():
    sim = Simulator(motor=MotorParams(emf_rounding=np.deg2rad(20.0)))
    sim.set_load(J=1e4)
    sim.set_speed(1000.0)
    r = sim.run(int(60 / 1000 / 4 / Ts))  # one electrical turn, bridge off
    K_rpm = 0.0125
    e_L = r["e_L"]
    # flat top of e_L = K_rpm * n in the middle of each sector, dips at the sector edges
    th = np.rad2deg(r["theta_e"]) % 60.0
    mid = (th < 10) | (th > 50)  # sector middles at 60 k deg, edges at 30 + 60 k deg
    np.testing.assert_allclose(e_L[mid], K_rpm * 1000.0, rtol=0.02)
    edge = np.abs(th - 30.0) < 3.0
    # moving average of width w over a corner: the phase EMF there is 1 - (6/pi) w / 8 (per
    # unit), while the other conducting phase is still flat, so e_L dips by (6/pi) w / 16
    w = np.deg2rad(20.0)
    dip = 1.0 - (6 / np.pi) * w / 16
    assert e_L[edge].min() == pytest.approx(K_rpm * 1000.0 * dip, rel=0.005)
    assert e_L[edge].max() < 0.985 * K_rpm * 1000.0
    assert np.all(np.abs(r["i_a"]) < 1e-9)  # bridge off below the rectifying speed


def test_overcurrent_trip_bridge_off_no_nan():
    sim = Simulator(current=CurrentControllerParams(L_c=3 * 14.8e-6))  # unstable (> 2 L)
    sim.set_load(J=1e4)
    sim.set_protection(overcurrent_trip=60.0)
    sim.set_mode("current")
    sim.set_current_ref(40.0)
    r = sim.run(5000)
    for name in SIGNALS:
        assert np.all(np.isfinite(r[name])), name
    f = sim.fault
    assert f is not None and f.code == 0x2310 and "overcurrent" in f.reason
    k = round(f.t / Ts)
    assert np.all(r["m"][k:] == 0.0)
    assert np.abs(r["i_a"][k + 20 :]).max() < 1e-6  # decayed through the diodes
    sim.reset_fault()
    assert sim.fault is None and sim.mode == "off"


@pytest.mark.parametrize(
    ("kind", "code"), [("overcurrent", 0x2310), ("overvoltage", 0x3210), ("undervoltage", 0x3220)]
)
def test_injected_faults(kind, code):
    sim = _steady_speed_sim()
    sim.inject_fault(kind)
    r = sim.run(100)
    assert sim.fault is not None and sim.fault.code == code
    assert np.all(r["m"][1:] == 0.0)
    sim.reset_fault()
    sim.run(10)
    assert sim.fault is None  # one-shot


def test_supply_voltage_limits():
    sim = _steady_speed_sim()
    sim.set_supply_voltage(65.0)
    sim.run(5)
    assert sim.fault.code == 0x3210
    sim.reset_fault()
    sim.run(5)
    assert sim.fault.code == 0x3210  # cause persists
    sim.set_supply_voltage(30.0)
    sim.reset_fault()
    sim.run(5)
    assert sim.fault.code == 0x3220
    sim.set_supply_voltage(48.0)
    sim.reset_fault()
    sim.set_mode("current")
    r = sim.run(200)
    assert sim.fault is None and r["V_dc"][-1] == 48.0
    assert r["i_p"][-1] == pytest.approx(50.0, abs=1.0)


def test_live_tuning_between_chunks():
    sim = Simulator()
    sim.set_load(J=1e4)
    sim.set_mode("current")
    sim.set_current_ref(15.0)
    sim.run(500)
    sim.set_current_gains(L_c=1.5 * 14.8e-6)
    sim.set_current_ref(20.0)
    r = sim.run(50)
    assert r["i_p"].max() > 21.0  # now underdamped, without a restart
    sim.set_current_gains(L_c=14.8e-6)
    sim.set_current_ref(25.0)
    r = sim.run(50)
    np.testing.assert_allclose(r["i_p"][10:], 25.0, atol=0.05)


@pytest.mark.parametrize(
    ("factory", "field"),
    [
        (lambda: MotorParams(L=0.0), "MotorParams.L"),
        (lambda: MotorParams(R=-1.0), "MotorParams.R"),
        (lambda: MotorParams(K_rpm=float("nan")), "MotorParams.K_rpm"),
        (lambda: InverterParams(V_dc=0.0), "InverterParams.V_dc"),
        (lambda: InverterParams(T_BT=-1e-9), "InverterParams.T_BT"),
        (lambda: LoadParams(J=0.0), "LoadParams.J"),
        (lambda: LoadParams(k_gen=-1.0), "LoadParams.k_gen"),
        (lambda: CurrentControllerParams(L_c=float("inf")), "CurrentControllerParams.L_c"),
        (lambda: CurrentControllerParams(type="lqr"), "CurrentControllerParams.type"),
    ],
)
def test_param_validation_names_the_field(factory, field):
    with pytest.raises(ValueError, match=field.replace(".", r"\.")):
        factory()


def test_bad_setter_changes_nothing():
    sim = Simulator()
    before = (sim.current, sim.speed, sim.load, sim.inverter)
    with pytest.raises(ValueError, match="L_c"):
        sim.set_current_gains(L_c=-1.0, R_c=0.01)
    with pytest.raises(ValueError, match="nope"):
        sim.set_current_gains(nope=1.0)
    with pytest.raises(ValueError, match="current_limit"):
        sim.set_speed_gains(current_limit=float("nan"))
    with pytest.raises(ValueError, match="J"):
        sim.set_load(J=-1.0)
    with pytest.raises(ValueError):
        sim.set_mode("turbo")
    with pytest.raises(ValueError):
        sim.set_model("spice")
    with pytest.raises(ValueError):
        sim.set_supply_voltage(float("nan"))
    with pytest.raises(ValueError):
        sim.inject_fault("meteor")
    assert (sim.current, sim.speed, sim.load, sim.inverter) == before
    assert sim.fault is None


def test_averaged_model_and_model_switch():
    sim = Simulator(model="averaged")
    sim.set_load(J=1e4)
    sim.set_mode("current")
    sim.set_current_ref(30.0)
    r = sim.run(100)
    np.testing.assert_allclose(r["i_p"][3:], 30.0, atol=0.05)
    sim.set_model("pwm")
    r = sim.run(100)
    np.testing.assert_allclose(r["i_p"], 30.0, atol=0.05)
    assert sim.model == "pwm"


def test_outgoing_phase_decays_through_diodes_at_commutation():
    """At each commutation the outgoing phase's current decays to zero through its freewheel
    diode within a few samples, without changing sign on the way; afterwards only the small
    open-phase diode currents of unipolar PWM remain (either diode, as the back-EMF says)."""
    sim = _steady_speed_sim(1000.0)
    n_os = 8
    r = sim.run(int(60 / 1000 / 4 / Ts), oversample=n_os)  # one electrical turn
    sec = r["hall_sector"].astype(int)
    changes = np.nonzero(np.diff(sec) != 0)[0] + 1
    assert len(changes) >= 5
    open_phase = {1: "os_i_c", 2: "os_i_b", 3: "os_i_a", 4: "os_i_c", 5: "os_i_b", 6: "os_i_a"}
    for k in changes[:5]:
        out = open_phase[sec[k]]  # was conducting in the previous sector, now open
        seg = r[out][k * n_os : (k + 25) * n_os]
        i0 = seg[0]
        assert abs(i0) > 40.0
        zero_at = int(np.argmax(seg * np.sign(i0) <= 0.0))  # first zero / sign change
        assert 0 < zero_at < 20 * n_os  # decays within a few samples
        assert abs(seg[zero_at - 1]) < 0.2 * abs(i0)  # monotone-ish, no jump through zero
        # (then only the open-phase diode blips of unipolar PWM remain: |i| << i_p)
        assert np.abs(seg[zero_at:]).max() < 0.2 * abs(i0)


def test_reverse_rotation_and_braking_signs():
    """Signed i_p: negative i_p gives negative torque, both when reversing and when braking."""
    sim = Simulator(model="averaged")
    sim.set_mode("speed")
    sim.set_speed_ref(-300.0)
    r = sim.run(150_000)
    assert sim.fault is None
    assert r["speed"][-1] == pytest.approx(-300.0, abs=10.0)
    K_t = 0.0125 * 60 / (2 * np.pi)
    i_p = r["i_p"][-2000:].mean()
    assert i_p < 0.0
    assert r["T_e"][-2000:].mean() == pytest.approx(K_t * i_p, rel=0.05)
    # regenerative braking while turning forwards
    sim = _steady_speed_sim(1000.0)
    sim.set_current_ref(-50.0)
    r = sim.run(2000)
    assert r["i_p"][-500:].mean() == pytest.approx(-50.0, abs=0.5)
    assert r["T_e"][-500:].mean() == pytest.approx(-50.0 * K_t, rel=0.05)


def _chunking_case(case: str) -> Simulator:
    sim = Simulator(model="averaged" if case == "averaged" else "pwm")
    if case == "delay_blanking_drop":
        sim.set_inverter_nonidealities(T_BT=1e-6, T_DD=2e-6, T_SD=1e-6, V_G=1.0)
    elif case == "delay":
        sim.set_inverter_nonidealities(T_DD=3e-6)
    sim.set_speed(900.0)
    sim.set_mode("speed")
    sim.set_speed_ref(1500.0)
    return sim


@pytest.mark.parametrize("case", ["six_step", "delay", "delay_blanking_drop", "averaged"])
def test_chunk_boundaries_and_recording_change_nothing(case):
    """Truth: the simulation is a deterministic function of the sample count, so one chunk and
    the same samples split into recorded and unrecorded chunks of odd sizes give bit-identical
    records and state (the loop's per-chunk constants and the latest values kept for the
    pacing path must not leak into the result)."""
    a, b = _chunking_case(case), _chunking_case(case)
    ra = a.run(2600)
    rb1 = b.run(999)
    b.run(1, record=False)
    b.run(600, record=False)
    rb2 = b.run(1000)
    for name in SIGNALS:
        np.testing.assert_array_equal(ra[name][:999], rb1[name], err_msg=name)
        np.testing.assert_array_equal(ra[name][1600:], rb2[name], err_msg=name)
    assert a.state == b.state  # the latest values (loop->last) after the chunk ...
    for name in SIGNALS:  # ... are the last recorded sample's
        assert a.state[name] == pytest.approx(float(ra[name][-1]), rel=0, abs=0), name
    plant_a, plant_b = a._loop.p, b._loop.p
    for x in range(3):
        assert plant_a.i[x] == plant_b.i[x]
    assert (plant_a.omega, plant_a.theta_e) == (plant_b.omega, plant_b.theta_e)
    assert a.segments == b.segments
