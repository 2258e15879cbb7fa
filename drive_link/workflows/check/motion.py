"""The CiA 402 items: ``cia402`` (the state machine), ``modes``, ``halt``, and the helpers
that spin the motor at a modest speed and wait for it to stop (used by ``nmt_reaction``
and ``config_only`` too)."""

from __future__ import annotations

import time

from ...link import cia402
from ...link.drive import Drive
from ._base import (
    ABORT_RANGE,
    _drive_wait,
    _expect,
    _expect_abort,
    _raw_write,
    _to_switch_on_disabled,
    _wait_state,
)

__all__ = ["HALT_BIT", "SPIN_RPM", "TARGET_REACHED", "item_cia402", "item_halt", "item_modes"]


def item_cia402(d: Drive, opts: dict) -> str:
    _to_switch_on_disabled(d)
    d.set_mode("speed")
    d.set_speed(0)
    steps = [
        (
            cia402.CW_ENABLE_OPERATION,
            cia402.SWITCH_ON_DISABLED,
            "enable operation from SWITCH ON DISABLED",
        ),
        (cia402.CW_SHUTDOWN, cia402.READY_TO_SWITCH_ON, "shutdown (2)"),
        (cia402.CW_SWITCH_ON, cia402.SWITCHED_ON, "switch on (3)"),
        (cia402.CW_ENABLE_OPERATION, cia402.OPERATION_ENABLED, "enable operation (4)"),
        (cia402.CW_DISABLE_OPERATION, cia402.SWITCHED_ON, "disable operation (5)"),
        (cia402.CW_ENABLE_OPERATION, cia402.OPERATION_ENABLED, "enable operation (4)"),
        (cia402.CW_SHUTDOWN, cia402.READY_TO_SWITCH_ON, "shutdown (8)"),
        (cia402.CW_DISABLE_VOLTAGE, cia402.SWITCH_ON_DISABLED, "disable voltage (7)"),
    ]
    for cw, want, what in steps:
        d.write("controlword", cw)
        if cw == cia402.CW_ENABLE_OPERATION and want == cia402.SWITCH_ON_DISABLED:
            time.sleep(0.02)  # an invalid command here: the state must not change
        got = _wait_state(d, want)
        _expect(got == want, f"{what}: drive in {got}, expected {want}")
    d.enable()
    d.write("controlword", cia402.CW_QUICK_STOP)
    got = _wait_state(d, cia402.SWITCH_ON_DISABLED, 2.0)
    _expect(
        got in (cia402.SWITCH_ON_DISABLED, cia402.QUICK_STOP_ACTIVE),
        f"quick stop (11): drive in {got}",
    )
    _to_switch_on_disabled(d)
    return f"transitions 2,3,4,5,8,7,11 as CiA 402; quick stop ends in {got}"


def item_modes(d: Drive, opts: dict) -> str:
    _to_switch_on_disabled(d)  # CiA 402: modes change only while operation is not enabled
    for mode in ("speed", "current", "torque", "speed"):
        d.set_mode(mode)
    code = _expect_abort(
        lambda: _raw_write(d, "modes_of_operation", 1), (ABORT_RANGE,), "mode 1 (profile position)"
    )
    _expect(d.mode == "speed", f"mode changed to {d.mode} after a refused write")
    return f"speed/current/torque confirmed by 0x6061; unsupported mode refused 0x{code:08X}"


HALT_BIT = 1 << 8  #: controlword bit 8 (CiA 402 §6.2.1)


TARGET_REACHED = 1 << 10  #: statusword bit 10


SPIN_RPM = 300  #: modest speed for the motion items (a real vehicle may be on the bench)


def _spin(d: Drive, rpm: int = SPIN_RPM) -> float:
    """NMT start, profile velocity at ``rpm``, OPERATION ENABLED; wait until it turns (bounded
    by the drive's own profile acceleration 0x6083). Returns the speed reached (rpm)."""
    _to_switch_on_disabled(d)
    d.nmt("start")
    d.set_mode("speed")
    rpm = min(rpm, int(d.read("max_motor_speed")))
    d.set_speed(rpm)
    d.enable()
    return _reach_speed(d, rpm, f"motor did not come up to {rpm} rpm")


def _reach_speed(d: Drive, rpm: int, failure: str) -> float:
    """Wait (profile ramp time + 5 s of the drive's time) until the speed reaches 80 % of
    ``rpm``; return it."""
    acc = max(int(d.read("profile_acceleration")), 1)
    bound = 2.0 * rpm / acc + 5.0
    v = [float(d.read("measurements.speed"))]

    def up() -> bool:
        v[0] = float(d.read("measurements.speed"))
        return v[0] >= 0.8 * rpm

    _, waited = _drive_wait(d, up, bound)
    _expect(v[0] >= 0.8 * rpm, f"{failure} (at {v[0]:.0f} rpm after {waited:.1f} s)")
    return v[0]


def _ramp_time(d: Drive, rpm: float, name: str = "quick_stop_deceleration") -> float:
    """Time (s) of a ramp from ``rpm`` to 0 on deceleration object ``name`` (rpm/s)."""
    return abs(rpm) / max(int(d.read(name)), 1)


def _ramp_bound(ramp: float) -> float:
    """Bound (s) for a ramp of ``ramp`` s: twice its time plus 2 s (a busy host, a slow bus)."""
    return 2.0 * ramp + 2.0


def _stop_time(d: Drive, rpm: float, name: str = "quick_stop_deceleration") -> float:
    """Bound (s) for a ramp from ``rpm`` to 0 on deceleration object ``name`` (rpm/s)."""
    return _ramp_bound(_ramp_time(d, rpm, name))


def _wait_standstill(d: Drive, timeout: float, window: float = 15.0) -> float:
    """The speed (rpm) once |speed| ≤ ``window``, or after ``timeout`` s of the drive's time."""
    v = [float(d.read("measurements.speed"))]

    def still() -> bool:
        v[0] = float(d.read("measurements.speed"))
        return abs(v[0]) <= window

    _drive_wait(d, still, timeout)
    return v[0]


def item_halt(d: Drive, opts: dict) -> str:
    """CiA 402 §10.3: in profile velocity controlword bit 8 (halt) brakes the axis (0x605D) and
    holds it at 0 while OPERATION ENABLED; statusword bit 10 is 0 while the speed is away from
    the target and 1 once the axis stands (halt) or turns at the target; in QUICK STOP ACTIVE
    with 0x605A = 6 bit 10 is 1 at standstill."""
    qs0 = int(d.read("quick_stop_option_code"))
    out = []
    try:
        _to_switch_on_disabled(d)
        d.nmt("start")
        d.set_mode("speed")
        d.set_speed(SPIN_RPM)
        d.enable()
        sw = d.statusword
        v = float(d.read("measurements.speed"))
        if abs(v - SPIN_RPM) > 0.5 * SPIN_RPM:
            _expect(not sw & TARGET_REACHED, f"bit 10 set at {v:.0f} rpm (target {SPIN_RPM})")
            out.append(f"bit 10 = 0 at {v:.0f} rpm")
        v = _spin(d)
        deadline = time.monotonic() + 5.0
        while not d.statusword & TARGET_REACHED and time.monotonic() < deadline:
            time.sleep(0.02)
        _expect(bool(d.statusword & TARGET_REACHED), f"bit 10 not set at the target ({v:.0f} rpm)")
        d.write("controlword", cia402.CW_ENABLE_OPERATION | HALT_BIT)
        sw = d.statusword
        v = float(d.read("measurements.speed"))
        if abs(v) > 0.5 * SPIN_RPM:
            _expect(not sw & TARGET_REACHED, f"halt: bit 10 set while braking at {v:.0f} rpm")
        v = _wait_standstill(d, _stop_time(d, SPIN_RPM, "profile_deceleration"))
        _expect(abs(v) <= 15.0, f"halt: motor still at {v:.0f} rpm")
        time.sleep(0.5)
        v = float(d.read("measurements.speed"))
        sw = d.statusword
        _expect(abs(v) <= 15.0, f"halt: speed not held at 0 ({v:.0f} rpm after 0.5 s)")
        _expect(d.state == cia402.OPERATION_ENABLED, f"halt left OPERATION ENABLED ({d.state})")
        _expect(bool(sw & TARGET_REACHED), "halt: bit 10 not set at standstill")
        out.append(f"halt holds {v:.0f} rpm with bit 10")
        d.write("controlword", cia402.CW_ENABLE_OPERATION)
        v = _spin_back(d)
        out.append(f"resumes to {v:.0f} rpm")
        d.write("quick_stop_option_code", 6)  # stop on the quick-stop ramp, stay in QUICK STOP
        d.write("controlword", cia402.CW_QUICK_STOP)
        v = _wait_standstill(d, _stop_time(d, SPIN_RPM))
        state = d.state
        _expect(state == cia402.QUICK_STOP_ACTIVE, f"0x605A = 6: drive in {state}")
        deadline = time.monotonic() + 2.0
        while not d.statusword & TARGET_REACHED and time.monotonic() < deadline:
            time.sleep(0.02)
        _expect(
            bool(d.statusword & TARGET_REACHED), "quick stop (0x605A = 6): bit 10 not set at rest"
        )
        out.append("quick stop 6: bit 10 at rest")
    finally:
        _to_switch_on_disabled(d)
        d.write("quick_stop_option_code", qs0)
    return "; ".join(out)


def _spin_back(d: Drive) -> float:
    return _reach_speed(d, SPIN_RPM, "halt released: motor did not turn again")
