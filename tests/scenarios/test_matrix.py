"""The product's end-to-end scenarios, run once per bench condition (ids: idle, busy, latency,
loss1, loss5, vcan0; see ``conditions.py``), through the public ``drive_link`` API and the
``drive-link`` command as a user would, against a ``virtual-drive run`` child process.

Truths: CiA 301/402 (device type, NMT and 402 states, EMCY 0x8130, quick stop ramp 0x6085,
store 0x1010), the paper's current loop computed here with python-control (deadbeat eq. (15) on
P(z) = Γ/(z(z − Φ)), eq. (8)) and the IP speed loop eq. (27) on b/(z − a). Waiting times scale
with the condition (``slow``); pass criteria never do.
"""

from __future__ import annotations

import json
import math
import os
import re
import time

import control
import numpy as np
import pytest
from conftest import RunQueueProbe

from drive_link import DriveTimeout, SdoAbort, Trigger, scan
from drive_link.link.trace import TS
from drive_link.workflows import steps
from drive_link.workflows.check import ITEMS
from drive_link.workflows.gains import apply_gains

from .conditions import Bench, wait_until

pytestmark = pytest.mark.timeout(900 if os.environ.get("BENCH_CONDITION") == "vcan0" else 240)

DEVICE_TYPE = 0x00020192  # CiA 402 drive, servo (0x0192 in the low word)
A_SPEED, B_SPEED = 0.9999785, 3.33715e-4  # paper eq. (26), independent of drive_link's copy


def _tag(bench: Bench) -> str:
    return f"[{bench.cond.name}]"


def _cli_ok(bench: Bench, *args: str, timeout: float = 60.0):
    r = bench.cli(*args, timeout=timeout)
    last = (r.stderr.strip().splitlines() or [""])[-1]
    cmd = " ".join(args)
    assert r.returncode == 0, f"{_tag(bench)} drive-link {cmd}: exit {r.returncode}: {last}"
    return r


def _at_rest(d) -> None:
    """Setpoints 0, power stage off (SWITCH ON DISABLED), any fault reset."""
    if d.state == "FAULT":
        d.fault_reset()
    d.set_speed(0)
    d.set_current(0.0)
    d.write("controlword", 0)  # disable voltage: SWITCH ON DISABLED from every 402 state


def _wait_speed(bench: Bench, d, target: float, tol: float, timeout: float) -> float:
    """Wait (``timeout`` s × slow) until |speed − target| ≤ tol (rpm); returns the speed."""
    box = [math.nan]

    def near() -> bool:
        box[0] = float(d.read("measurements.speed"))
        return abs(box[0] - target) <= tol

    ok = wait_until(near, timeout * bench.cond.slow, poll_s=0.05)
    assert ok, f"{_tag(bench)} speed {box[0]:.1f} rpm, expected {target:g} ± {tol:g} rpm"
    return box[0]


# ------------------------------------------------------------------------------- scenarios


def test_scan(bench):
    r = _cli_ok(bench, "scan")
    lines = [ln for ln in r.stdout.splitlines() if ln.strip().startswith("node")]
    assert len(lines) == 1, f"{_tag(bench)} scan listed {lines!r}, expected node 1 only"
    assert lines[0].split()[1] == "1:" and f"0x{DEVICE_TYPE:08X}" in lines[0], lines[0]
    with bench.connect(heartbeat_ms=None) as d:
        nodes = scan(d.bus, timeout=0.3 * bench.cond.slow)
    found = {n.node_id: n.device_type for n in nodes}
    assert found == {1: DEVICE_TYPE}, f"{_tag(bench)} scan() found {found}"


def test_nmt_start_and_402_enable(bench):
    with bench.connect() as d:
        _at_rest(d)  # setpoints 0 (whatever mode the drive is in)
        _cli_ok(bench, "nmt", "start")
        _cli_ok(bench, "enable")
        st = wait_until(lambda: d.nmt_state == "OPERATIONAL", 2.0 * bench.cond.slow)
        assert st, f"{_tag(bench)} heartbeats say {d.nmt_state}, expected OPERATIONAL"
        sw = d.statusword
        # CiA 402 Table 30: OPERATION ENABLED = xxxx xxxx x01x 0111
        assert sw & 0x6F == 0x27, f"{_tag(bench)} statusword 0x{sw:04X} is not OPERATION ENABLED"
        r = _cli_ok(bench, "status", "--json")
        status = json.loads(r.stdout)
        assert status["state"] == "OPERATION ENABLED", status["state"]
        assert status["nmt_state"] == "OPERATIONAL", (
            f"{_tag(bench)} drive-link status says nmt_state {status['nmt_state']} for a node "
            "sending OPERATIONAL heartbeats"
        )
        _at_rest(d)
        assert d.state == "SWITCH ON DISABLED"


def _ip_loop_step(kp: float, ki: float, n: int) -> np.ndarray:
    """Unit step response of the IP speed loop eq. (27) on b/(z − a), n loop samples."""
    a, b = A_SPEED, B_SPEED
    T = control.tf([kp * ki * b, 0], [1, kp * b + kp * ki * b - 1 - a, a - kp * b], TS)
    _, y = control.step_response(T, T=np.arange(n) * TS)
    return np.asarray(y).ravel()


def test_speed_step_to_1000_rpm_and_back(bench):
    with bench.connect() as d:
        d.nmt("start")
        _at_rest(d)
        d.set_mode("speed")
        d.set_speed(0)
        d.enable()
        _wait_speed(bench, d, 0.0, 5.0, 5.0)
        g = d.read_gains()
        for w0, w1 in ((0.0, 1000.0), (1000.0, 0.0)):
            res = steps.speed_step(  # the second step starts where the first one ended
                d, w1 - w0, start_rpm=w0, divider=100, length=1000, pre_trigger=20,
                restore=False,
            )
            tr = res.trace
            k0 = tr.trigger_index
            assert tr.signals["measurements.speed_ref"][k0] == w1
            measured = tr.signals["measurements.speed"][k0:].astype(float)
            y = _ip_loop_step(g.speed_k_p, g.speed_k_i, len(measured) * 100)[::100]
            oracle = res.y_from + (w1 - res.y_from) * y
            # b/(z − a) is the paper's first-order fit of the BLDC's torque/speed behaviour
            # (trapezoidal EMF, commutation dips): within 10 % of the 1000 rpm step
            err = np.abs(measured - oracle)
            assert err.max() <= 100.0, (
                f"{_tag(bench)} speed {w0:g}→{w1:g}: off the IP loop eq. (27) by "
                f"{err.max():.0f} rpm at t = {tr.t[k0 + int(err.argmax())]:.3f} s"
            )
            _wait_speed(bench, d, w1, 0.02 * 1000.0, 10.0)
        _at_rest(d)


def _deadbeat_step(R: float, L: float, L_c: float, R_c: float, n: int) -> np.ndarray:
    """I_p/I_p* unit step response for C_db (eq. 15) with estimates L_c, R_c on the plant
    eq. (8) of R (Ω), L (H), n samples."""
    Phi, Gamma = math.exp(-R * TS / L), (1 - math.exp(-R * TS / L)) / (2 * R)
    Phi_c, Gamma_c = math.exp(-R_c * TS / L_c), (1 - math.exp(-R_c * TS / L_c)) / (2 * R_c)
    P = control.tf([Gamma], [1, -Phi, 0], TS)
    C = control.tf([1, -Phi_c, 0], [Gamma_c, 0, -Gamma_c], TS)
    _, y = control.step_response(control.feedback(C * P, 1), T=np.arange(n) * TS)
    return np.asarray(y).ravel()


def _held_rotor_step(bench: Bench, d, channels, length, pre, quiet, J_free, tries):
    """Record the 15 → 20 A step with the rotor held; redo it (5 tries) until e_L and the Hall
    sector are quiet from ``quiet`` samples before the step. Returns (trace, its re-upload,
    trigger index, clean samples after the step)."""
    slow = bench.cond.slow
    for _ in range(5):
        _at_rest(d)
        d.write("sim_load.J", J_free)  # ConfigOnly: written with the power stage off
        d.set_mode("speed")
        d.set_speed(0)
        d.enable()
        _wait_speed(bench, d, 0.0, 5.0, 10.0)
        _at_rest(d)
        d.write("sim_load.J", 1e4)  # hold the rotor at the speed it has (≤ 5 rpm)
        d.set_mode("current")
        d.set_current(15.0)
        d.trace.configure(channels, 1, length, pre, Trigger("setpoint_step"))
        d.enable()
        for _ in range(3):  # a step while the pre-trigger part fills is not a trigger
            d.trace.arm()
            d.trace.wait_ready(10.0 * slow)  # in the drive's time: it may lag the wall clock
            d.set_current(20.0)
            try:
                d.trace.wait(5.0 * slow)
                break
            except DriveTimeout:
                d.trace.stop()
                d.set_current(15.0)
        else:
            pytest.fail(f"{_tag(bench)} the recorder never triggered on the 15 → 20 A step")
        tr = d.trace.upload()
        k0 = tr.trigger_index
        e_L = tr.signals["measurements.e_L"][k0 - quiet :].astype(float)
        hall = tr.signals["measurements.hall_sector"][k0 - quiet :]
        e_pre = float(np.mean(e_L[:quiet]))
        off = np.flatnonzero((np.abs(e_L - e_pre) > 0.02) | (hall != hall[0]))
        clean = min(50, int(off[0]) - quiet if len(off) else 50)
        if clean >= 20:
            return tr, d.trace.upload(), k0, clean  # re-upload: must be byte-identical
        tries.append(f"e_L {e_pre:.3f} V, {int(off[0]) - quiet if len(off) else 'no'} change")
    pytest.fail(f"{_tag(bench)} no quiet e_L around the step in 5 tries: {tries}")


def test_current_step_with_full_64k_trace(bench):
    """Current step 15 → 20 A recorded in the whole recorder (16,384 REAL32 = 64 KiB).

    The step is made from near standstill with the rotor held (sim_load.J = 1e4 kg m², as the
    paper's current steps at low speed): free, 15 A accelerates the rotor by ~250 rpm/s, and on
    a lossy bus the SDO retries between Enable and the step let e_L reach 2 V. The back-EMF's
    changes (commutations, the trapezoid's rounded corners) disturb i_p by about 1.3 A/V,
    decaying with the plant's own time constant (~2.4 ms); that is not part of the linear loop,
    so the oracle is compared only where the Hall sector is constant and e_L flat (within
    0.02 V: < 0.03 A) from 12 ms (5 time constants) before the step on; a step without such a
    window is redone.
    """
    channels = ["i_p", "i_p_ref", "e_L", "hall_sector"]
    with bench.connect() as d:
        d.nmt("start")
        cap = d.trace.capacity
        assert cap == 16384, f"{_tag(bench)} recorder capacity {cap} REAL32, expected 16384"
        length, pre, quiet = cap // len(channels), 2048, 600
        g = d.read_gains()
        R, L = float(d.read("motor.R")), float(d.read("motor.L"))
        J_free = float(d.read("sim_load.J"))
        tries: list[str] = []  # why a try was redone (e_L before the step, first change)
        try:
            tr, again, k0, clean = _held_rotor_step(
                bench, d, channels, length, pre, quiet, J_free, tries
            )
        finally:
            _at_rest(d)
            d.write("sim_load.J", J_free)  # ConfigOnly: written with the power stage off
    # structure: 4 channels × 4096 samples, finite, trigger where configured
    assert list(tr.signals) == [f"measurements.{c}" for c in channels], list(tr.signals)
    assert sum(v.size for v in tr.signals.values()) == 16384
    for name, v in tr.signals.items():
        assert v.dtype == np.float32 and v.shape == (length,), (name, v.dtype, v.shape)
        assert np.isfinite(v).all(), f"{_tag(bench)} {name} has non-finite samples"
        assert np.array_equal(v, again.signals[name]), f"{_tag(bench)} {name} differs on re-upload"
    assert k0 == pre and tr.t[k0] == 0.0
    assert np.allclose(np.diff(tr.t), TS)
    ref = tr.signals["measurements.i_p_ref"]
    assert (ref[:k0] == 15.0).all() and (ref[k0:] == 20.0).all(), "i_p_ref is not the 15 → 20 step"
    assert set(np.unique(tr.signals["measurements.hall_sector"])) <= {1.0, 2.0, 3.0, 4.0, 5.0, 6.0}
    # the paper's deadbeat loop (python-control) with the drive's own L_c, R_c on R, L
    y = _deadbeat_step(R, L, g.L_c, g.R_c, clean)
    oracle = 15.0 + 5.0 * y
    measured = tr.signals["measurements.i_p"][k0 : k0 + clean].astype(float)
    err = np.abs(measured - oracle)
    assert err.max() <= 0.05, (
        f"{_tag(bench)} i_p off the deadbeat loop by {err.max():.3f} A at sample {err.argmax()}"
    )
    assert abs(float(tr.signals["measurements.i_p"][k0 - 1]) - 15.0) <= 0.05
    assert abs(measured[2] - 20.0) <= 0.05  # deadbeat: there in k = 2 samples (eq. 15)


def _stage_raw(d, field: str, value: float) -> None:
    """Stage one gain in gain_set (0x20F0) without the host's own checks (the drive's job)."""
    obj = d.table[f"gain_set.{field}"]
    d.sdo.download(obj.index, obj.subindex, obj.encode(value), obj.name)


def test_atomic_gain_set_and_read_back(bench):
    with bench.connect() as d:
        _at_rest(d)
        g0 = d.read_gains()
        want = {"L_c": 1.2 * g0.L_c, "R_c": 1.1 * g0.R_c}
        r = _cli_ok(bench, "set-gains", *(f"{k}={v!r}" for k, v in want.items()))
        back = d.read_gains()
        for k, v in want.items():
            assert getattr(back, k) == float(np.float32(v)), (
                f"{_tag(bench)} {k} read back {getattr(back, k)!r}, set {v!r}; "
                f"set-gains printed: {' | '.join(ln.strip() for ln in r.stdout.splitlines())}"
            )
        try:
            # staging alone changes nothing active
            _stage_raw(d, "R_c", 0.5 * g0.R_c)
            assert d.read_gains() == back, f"{_tag(bench)} a staged gain became active"
            # a set the drive refuses (L_c beyond the Jury limit 2·L, eq. 17) changes nothing,
            # not even the valid R_c staged with it
            L = float(d.read("motor.L"))
            try:
                _stage_raw(d, "L_c", 2.5 * L)
            except SdoAbort as exc:  # refused at staging: equally atomic
                assert exc.code in (0x06090030, 0x06090031), hex(exc.code)
            else:
                with pytest.raises(SdoAbort) as exc:
                    apply_obj = d.table["gain_set_apply"]  # raw: the drive's refusal is tested
                    d.sdo.download(apply_obj.index, apply_obj.subindex, bytes([1]))
                assert exc.value.code in (0x06090030, 0x06090031, 0x08000022), hex(exc.value.code)
            assert d.read_gains() == back, f"{_tag(bench)} a refused gain set changed the gains"
        finally:
            restored = apply_gains(d, {"L_c": g0.L_c, "R_c": g0.R_c}, force=True).gains
        assert restored["L_c"] == g0.L_c and restored["R_c"] == g0.R_c  # whole set re-staged


def test_heartbeat_loss_quick_stop(bench):
    """Host heartbeat stops → EMCY 0x8130, quick stop (0x6007 = 3, 0x605A = 2): the speed ramps
    down to standstill, never faster than 0x6085, without reversing, then SWITCH ON DISABLED."""
    with bench.connect(heartbeat_ms=100) as d:
        d.nmt("start")
        _at_rest(d)
        d.clear_error_history()
        d.set_mode("speed")
        d.set_speed(1000)
        d.enable()
        _wait_speed(bench, d, 1000.0, 30.0, 10.0)
        decel = float(d.read("quick_stop_deceleration"))  # rpm/s (0x6085)
        div = 50  # 1 ms per trace sample
        d.trace.configure(
            ["speed", "i_p"],
            divider=div,
            length=1000,
            pre_trigger=50,
            trigger=Trigger("signal", "measurements.speed", 900.0, "falling"),
        )
        d.trace.arm()
        n_emcy = len(d.emcy_history)
        d.configure_heartbeat_consumer()  # max(1000 ms, 3 × 100 ms)
        assert wait_until(lambda: d.trace.state == "armed", 1.0 * bench.cond.slow)
        # CiA 301: the consumer starts watching at the first heartbeat after it was configured
        time.sleep(0.5 * bench.cond.slow)
        assert d.state == "OPERATION ENABLED", (
            f"{_tag(bench)} quick stop with heartbeat alive; EMCY since enable: "
            f"{[hex(e.code) for e in d.emcy_history[n_emcy:]]}, all: "
            f"{[hex(e.code) for e in d.emcy_history]}, status: {d.status()}"
        )
        d.stop_host_heartbeat()
        got = wait_until(
            lambda: [e for e in d.emcy_history[n_emcy:] if e.code == 0x8130], 3.0 * bench.cond.slow
        )
        if not got:  # an EMCY is one unconfirmed frame (lost on a lossy bus): 0x1003 keeps it
            got = [e for e in d.error_history()[:1] if e.code == 0x8130]
        assert got, f"{_tag(bench)} no EMCY 0x8130 (frame or 0x1003) after the heartbeat stopped"
        d.trace.wait(5.0 * bench.cond.slow)
        tr = d.trace.upload()
        state = wait_until(
            lambda: (s := d.state) != "QUICK STOP ACTIVE" and s, 2.0 * bench.cond.slow
        )
        d.write("consumer_heartbeat_time.consumer_1", 0)
        _at_rest(d)
    assert state == "SWITCH ON DISABLED", f"{_tag(bench)} after the quick stop: {state}"
    k0 = tr.trigger_index
    speed = tr.signals["measurements.speed"][k0:].astype(float)
    assert speed.max() <= 900.0 + 5.0 and abs(speed[-1]) <= 15.0, (
        f"{_tag(bench)} speed {speed[-1]:.0f} rpm at the end of the quick stop record"
    )
    assert speed.min() >= -15.0, f"{_tag(bench)} quick stop reversed to {speed.min():.0f} rpm"
    assert np.all(np.diff(speed) <= 2.0), f"{_tag(bench)} speed rose during the quick stop"
    t = np.arange(len(speed)) * div * TS
    ramp = (speed < 800.0) & (speed > 100.0)
    slope = np.polyfit(t[ramp], speed[ramp], 1)[0]  # rpm/s
    assert -1.05 * decel <= slope < 0, f"{_tag(bench)} ramp {slope:.0f} rpm/s, 0x6085 {decel:g}"


def test_store_restart_restores(bench):
    with bench.connect(heartbeat_ms=None) as d:
        _at_rest(d)
        g0 = d.read_gains()
        stored = {
            "current_controller.R_c": 0.9 * g0.R_c,
            "speed_controller.k_p": 0.9 * g0.speed_k_p,
        }
        # gains change through the one gain path (Drive.write refuses them)
        apply_gains(d, {"R_c": stored["current_controller.R_c"],
                        "speed_k_p": stored["speed_controller.k_p"]})
        d.store()
        apply_gains(d, {"R_c": 0.8 * g0.R_c})  # changed after the store: not kept
    bench.restart()
    with bench.connect(heartbeat_ms=None) as d:
        for k, v in stored.items():
            got = float(d.read(k))
            want = float(np.float32(v))
            assert got == want, f"{_tag(bench)} {k} = {got} after restart, stored {want}"
        if "store_status" in d.table:
            assert int(d.read("store_status")) == 0, "store_status is not 0 (ok) after restart"
        apply_gains(d, {"R_c": g0.R_c, "speed_k_p": g0.speed_k_p})
        d.store()


def _late_heartbeat_explained(detail: str, wait: float) -> bool:
    """A heartbeat period measured longer than set is accepted only when the kernel kept the
    drive's threads waiting enough to explain it: a producer that gets the CPU a fraction
    (1 − wait) of the time sends at most that fraction of its heartbeats (25 % margin)."""
    m = re.fullmatch(r"heartbeat period ([\d.]+) ms, expected (\d+) ms", detail)
    if not m:
        return False
    measured, expected = float(m[1]), float(m[2])
    return expected < measured <= 1.25 * expected / max(0.1, 1.0 - wait)


def _pdo_rate_explained(detail: str, wait: float) -> bool:
    """A TPDO rate off its event time is accepted only when the drive's run-queue wait explains
    it: a producer that gets the CPU a fraction (1 − wait) of the time sends at least that
    fraction (the drive counts what it could not send, 0x2070), and a late timer catches up by
    at most as much again (25 % margin each way). A drive that silently drops every other frame
    on a host that lets it run (wait ≈ 0) still fails."""
    items = re.findall(
        r"TPDO\d+ at (\d+) Hz(?: \+ (\d+) Hz missed periods counted by the drive)?, "
        r"expected (\d+) Hz",
        detail,
    )
    if not items or len(items) != detail.count("expected"):
        return False
    for sent, missed, expected in items:
        rate, exp = float(sent) + float(missed or 0), float(expected)
        if not (0.75 * exp * max(0.0, 1.0 - wait) <= rate <= 1.25 * exp * (1.0 + wait)):
            return False
    return True


def _sdo_silence_explained(detail: str, wait: float) -> bool:
    """An item that got no SDO answer after all its resends (about 6 s) is accepted only when
    the kernel kept the drive waiting most of the time (run-queue wait ≥ 0.5 s/s: at load 18
    with 5 % loss, 0.72 s/s, the drive was silent through six requests)."""
    return "did not answer SDO" in detail and wait >= 0.5


def _explained(name: str, detail: str, wait: float) -> bool:
    return (
        (name == "heartbeat" and _late_heartbeat_explained(detail, wait))
        or (name == "pdo_rates" and _pdo_rate_explained(detail, wait))
        or _sdo_silence_explained(detail, wait)
    )


def test_drive_link_check_all_items(bench):
    probe = RunQueueProbe(bench.proc.proc.pid)  # what the machine gave the drive meanwhile
    # (the pre-certification items of issue 29 take ~20 s more under 5 % loss: 115 s in all)
    r = bench.cli("check", "--json", timeout=200.0)
    wait = probe.stop()
    try:
        results = json.loads(r.stdout)
    except json.JSONDecodeError:
        last = (r.stderr.strip().splitlines() or [""])[-1]
        pytest.fail(f"{_tag(bench)} drive-link check exit {r.returncode}: {last}")
    failed = [
        f"{x['name']}: {x['detail']}"
        for x in results
        if not x["ok"] and not _explained(x["name"], x["detail"], wait)
    ]
    assert not failed, f"{_tag(bench)} check failed: {'; '.join(failed)} ({probe!r})"
    assert r.returncode in (0, 1), f"{_tag(bench)} drive-link check exit {r.returncode}"
    assert [x["name"] for x in results] == list(ITEMS)
