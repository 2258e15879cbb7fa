"""``drive-link check``: a conformance run against any node (DSP or virtual drive).

Each item exercises what the object dictionary (docs/contracts.md §1), CiA 301 and CiA 402
promise and reports pass/fail with a one-line detail. Items leave the drive disabled, in
OPERATIONAL, with the parameters they touched restored; "store_restore" rewrites the drive's
stored parameters (skip it with ``--skip store_restore`` on a tuned drive).
"""

from __future__ import annotations

import struct
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from . import cia402
from .drive import Drive
from .errors import DriveError, DriveTimeout, SdoAbort
from .nmt import HeartbeatProducer

DEVICE_TYPE_402_SERVO = 0x00020192

ABORT_RANGE = 0x06090030
ABORT_HIGH = 0x06090031
ABORT_LOW = 0x06090032
ABORT_READ_ONLY = 0x06010002
ABORT_NO_OBJECT = 0x06020000
ABORT_LENGTH = (0x06070010, 0x06070012, 0x06070013)
ABORT_STATE = 0x08000022


class CheckFailed(Exception):  # noqa: N818
    """An item's expectation was not met (message = the one-line reason)."""


@dataclass
class CheckResult:
    """``name``, ``ok``, ``detail`` (one line), ``seconds`` taken."""

    name: str
    ok: bool
    detail: str
    seconds: float


def _expect(cond: bool, msg: str) -> None:
    if not cond:
        raise CheckFailed(msg)


def _expect_abort(fn: Callable[[], object], codes: tuple[int, ...], what: str) -> int:
    try:
        fn()
    except SdoAbort as exc:
        _expect(
            exc.code in codes,
            f"{what}: abort 0x{exc.code:08X} ({exc.meaning}), expected "
            + " or ".join(f"0x{c:08X}" for c in codes),
        )
        return exc.code
    raise CheckFailed(
        f"{what}: accepted, expected SDO abort " + " or ".join(f"0x{c:08X}" for c in codes)
    )


def _raw_write(drive: Drive, name: str, value: float | int) -> None:
    """Write bypassing the client-side limit check (the drive must refuse by itself)."""
    obj = drive.table[name]
    drive.sdo.download(obj.index, obj.subindex, struct.pack(obj.fmt, value), name)


def _f32(x: float) -> float:
    return struct.unpack("<f", struct.pack("<f", x))[0]


def _wait_state(drive: Drive, state: str, timeout: float = 1.0) -> str:
    deadline = time.monotonic() + timeout
    while True:
        s = drive.state
        if s == state or time.monotonic() > deadline:
            return s
        time.sleep(0.005)


def _to_switch_on_disabled(drive: Drive) -> None:
    """Bring the drive to SWITCH ON DISABLED from wherever the bench left it: a running motor is
    first stopped by "disable operation" (ramp per 0x605C), a fault is reset."""
    if drive.state in (cia402.FAULT, cia402.FAULT_REACTION_ACTIVE):
        drive.fault_reset()
    if drive.state == cia402.OPERATION_ENABLED:
        drive.disable(timeout=5.0)
    drive.write("controlword", cia402.CW_DISABLE_VOLTAGE)
    _expect(
        _wait_state(drive, cia402.SWITCH_ON_DISABLED) == cia402.SWITCH_ON_DISABLED,
        f"cannot reach SWITCH ON DISABLED (drive in {drive.state})",
    )


# --------------------------------------------------------------------------- items
def item_identity(d: Drive, opts: dict) -> str:
    dt = int(d.read("device_type"))
    _expect(
        dt == DEVICE_TYPE_402_SERVO,
        f"device_type 0x{dt:08X}, expected 0x{DEVICE_TYPE_402_SERVO:08X}",
    )
    vendor = int(d.read("identity.vendor_id"))
    modes = int(d.read("supported_drive_modes"))
    need = (1 << 2) | (1 << 3) | (1 << 16)
    _expect(modes & need == need, f"supported_drive_modes 0x{modes:08X} lacks pv/tq/mode -1 bits")
    name = d.read("manufacturer_device_name")
    return f"device_type 0x{dt:08X}, vendor 0x{vendor:08X}, modes 0x{modes:08X}, {name!r}"


def item_nmt_bootup(d: Drive, opts: dict) -> str:
    hb = d.heartbeat
    boots = hb.boot_count
    t0 = time.monotonic()
    d.nmt("reset communication")
    hb.wait_boot(3.0, boots)
    dt_boot = time.monotonic() - t0
    st = hb.wait_for(("PRE-OPERATIONAL",), 2.0, after=time.monotonic() - 0.001)
    t1 = time.monotonic()
    d.nmt("start")
    hb.wait_for(("OPERATIONAL",), 2.0, after=t1)
    return f"boot-up after {dt_boot * 1e3:.0f} ms, heartbeat {st} then OPERATIONAL after start"


def item_nmt_stopped(d: Drive, opts: dict) -> str:
    hb = d.heartbeat
    t0 = time.monotonic()
    d.nmt("stop")
    try:
        hb.wait_for(("STOPPED",), 2.0, after=t0)
        answered = True
        try:
            d.read("device_type")
        except DriveTimeout:
            answered = False
        _expect(not answered, "SDO answered in STOPPED (CiA 301 table 78 forbids it)")
    finally:
        t1 = time.monotonic()
        d.nmt("start")
    hb.wait_for(("OPERATIONAL",), 2.0, after=t1)
    d.read("device_type")
    return "heartbeat STOPPED, no SDO in STOPPED, OPERATIONAL again after start"


def item_heartbeat(d: Drive, opts: dict) -> str:
    period_ms = int(d.read("producer_heartbeat_time"))
    _expect(period_ms > 0, "producer_heartbeat_time is 0 (heartbeat off)")
    results = []
    for p in (period_ms, 50):
        d.write("producer_heartbeat_time", p)
        try:
            time.sleep(2 * p / 1000)
            t0 = time.monotonic()
            time.sleep(max(0.6, 10 * p / 1000))
            times = np.array([t for t in list(d.heartbeat.arrivals) if t >= t0])
        finally:
            d.write("producer_heartbeat_time", period_ms)
        _expect(len(times) >= 3, f"only {len(times)} heartbeats in {max(0.6, 10 * p / 1000):g} s")
        measured = float(np.median(np.diff(times))) * 1000
        tol = opts.get("rate_tolerance", 0.25)
        _expect(
            abs(measured - p) <= tol * p + 2, f"heartbeat period {measured:.1f} ms, expected {p} ms"
        )
        results.append(f"{p} ms → {measured:.1f} ms")
    return "period " + ", ".join(results)


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


def item_limits(d: Drive, opts: dict) -> str:
    L = float(d.read("motor.L"))
    L_c0 = float(d.read("current_controller.L_c"))
    out = []
    cases = [
        ("current_controller.L_c", 2.5 * L, (ABORT_RANGE, ABORT_HIGH), "L_c = 2.5 L"),
        ("current_controller.L_c", 0.0, (ABORT_RANGE, ABORT_LOW), "L_c = 0"),
        ("current_controller.L_c", -L, (ABORT_RANGE, ABORT_LOW), "L_c < 0"),
        ("setpoints.i_p_ref", 500.0, (ABORT_RANGE, ABORT_HIGH), "i_p_ref = 500 A"),
    ]
    vmax = int(d.read("max_motor_speed"))
    cases.append(
        ("target_velocity", vmax + 100, (ABORT_RANGE, ABORT_HIGH), "target_velocity > max")
    )
    for name, value, codes, what in cases:
        code = _expect_abort(lambda n=name, v=value: _raw_write(d, n, v), codes, what)
        out.append(f"{what}: 0x{code:08X}")
    _expect(float(d.read("current_controller.L_c")) == L_c0, "L_c changed by a refused write")
    code = _expect_abort(
        lambda: _raw_write(d, "statusword", 0), (ABORT_READ_ONLY,), "write statusword"
    )
    out.append(f"ro: 0x{code:08X}")
    code = _expect_abort(lambda: d.sdo.upload(0x2FFF, 0), (ABORT_NO_OBJECT,), "read 0x2FFF")
    out.append(f"missing: 0x{code:08X}")
    cw = d.table["controlword"]
    code = _expect_abort(
        lambda: d.sdo.download(cw.index, cw.subindex, b"\x00\x00\x00\x00"),
        ABORT_LENGTH,
        "4 bytes to U16 controlword",
    )
    out.append(f"length: 0x{code:08X}")
    return "; ".join(out)


def item_gain_set(d: Drive, opts: dict) -> str:
    L = float(d.read("motor.L"))
    g0 = d.read_gains()
    for f in ("type", "L_c", "R_c", "k_p", "k_i", "T_BT", "T_DD", "T_SD", "V_G", "emf_feedforward"):
        obj = d.table[f"gain_set.{f}"]
        d.sdo.download(obj.index, obj.subindex, obj.encode(getattr(g0, f)), obj.name)
    staged_refused = False
    try:
        _raw_write(d, "gain_set.L_c", 2.5 * L)
    except SdoAbort:
        staged_refused = True
    if not staged_refused:
        _expect_abort(
            lambda: d.write("gain_set_apply", 1),
            (ABORT_RANGE, ABORT_HIGH, ABORT_LOW, ABORT_STATE),
            "apply L_c = 2.5 L",
        )
    _expect(d.read_gains() == g0, "active gains changed by a refused gain set")
    try:
        back = d.apply_gains(L_c=0.9 * L, R_c=g0.R_c)
        _expect(back.L_c == _f32(0.9 * L), f"L_c read back {back.L_c}")
    finally:
        d.apply_gains(L_c=g0.L_c)
    how = "at staging" if staged_refused else "at apply"
    return f"invalid set refused {how} with nothing changed; valid set applied and read back"


def item_store_restore(d: Drive, opts: dict) -> str:
    name = "current_controller.R_c"
    orig = float(d.read(name))
    default = float(d.table[name].default or 0)
    v2 = _f32(orig * 0.9 + 1e-4)
    v3 = _f32(orig * 0.8 + 2e-4)
    try:
        d.write(name, v2)
        d.store()
        d.write(name, v3)
        d.reset(timeout=3.0)
        got = float(d.read(name))
        _expect(got == v2, f"after store + reset node R_c = {got}, expected stored {v2}")
        d.restore_defaults(reset=True)
        got = float(d.read(name))
        _expect(
            got == _f32(default),
            f"after restore + reset node R_c = {got}, expected default {default}",
        )
    finally:
        d.write(name, orig)
        d.store()
        d.nmt("start")
    return "stored value survives reset node; restore defaults applies after reset node"


def item_pdo_rates(d: Drive, opts: dict) -> str:
    d.nmt("start")
    live = d.refresh_live()
    window = opts.get("pdo_window", 1.0)
    time.sleep(0.2)
    live.reset_counters()
    time.sleep(window)
    st = live.stats
    tol = opts.get("rate_tolerance", 0.25)
    out = []
    for name, s in st["tpdo"].items():
        exp = s["expected_hz"]
        if not exp:
            continue
        rate = s["frames"] / window
        _expect(abs(rate - exp) <= tol * exp, f"{name} at {rate:.0f} Hz, expected {exp:.0f} Hz")
        out.append(f"{name} {rate:.0f}/{exp:.0f} Hz")
    _expect(bool(out), "no TPDO with an event timer")
    return ", ".join(out) + f"; bus load {100 * (st.get('bus_load') or 0):.0f} %"


def item_trace(d: Drive, opts: dict) -> str:
    length = 2000
    d.trace.configure(
        ["i_p", "speed"], divider=1, length=length, pre_trigger=0, trigger="immediate"
    )
    d.trace.arm()
    d.trace.wait(5.0)
    reads = [0]
    stop = threading.Event()

    def status_reader() -> None:
        while not stop.is_set():
            try:
                d.read("statusword")
                reads[0] += 1
            except DriveError:
                pass

    th = threading.Thread(target=status_reader, daemon=True)
    th.start()
    t0 = time.monotonic()
    try:
        tr = d.trace.upload()
    finally:
        stop.set()
        th.join(2.0)
    dt = time.monotonic() - t0
    _expect(len(tr.t) == length, f"{len(tr.t)} samples, expected {length}")
    _expect(
        0 <= tr.trigger_index < length, f"trigger position {tr.trigger_index} outside [0, {length})"
    )
    parallel = d.sdo_trace is not d.sdo
    _expect(parallel, "no second SDO server (0x1201): uploads would block status reads")
    _expect(reads[0] > 0, "no status read completed during the upload")
    kbps = length * 2 * 4 / dt / 1e3
    return (
        f"{length}×2 samples by block upload in {dt * 1e3:.0f} ms ({kbps:.1f} kB/s), "
        f"{reads[0]} status reads meanwhile"
    )


def item_heartbeat_consumer(d: Drive, opts: dict) -> str:
    period = 50
    prod = HeartbeatProducer(d.bus, 0x7E, period)
    stopped = False
    try:
        d.set_mode("speed")
        d.set_speed(0)
        d.enable()
        n_emcy = len(d.emcy_history)
        d.write("consumer_heartbeat_time.consumer_1", (0x7E << 16) | (4 * period))
        time.sleep(0.3)
        _expect(
            d.state == cia402.OPERATION_ENABLED,
            f"drive left OPERATION ENABLED with heartbeat alive ({d.state})",
        )
        prod.stop()
        stopped = True
        deadline = time.monotonic() + 2.0
        codes: list[int] = []
        while time.monotonic() < deadline:
            codes = [e.code for e in d.emcy_history[n_emcy:]]
            if 0x8130 in codes and d.state != cia402.OPERATION_ENABLED:
                break
            time.sleep(0.02)
        state = d.state
        _expect(
            0x8130 in codes, f"no EMCY 0x8130 after heartbeat loss (got {[hex(c) for c in codes]})"
        )
        _expect(
            state != cia402.OPERATION_ENABLED, "drive still OPERATION ENABLED after heartbeat loss"
        )
    finally:
        if not stopped:
            prod.stop()
        d.write("consumer_heartbeat_time.consumer_1", 0)
        _to_switch_on_disabled(d)
    return f"EMCY 0x8130 and reaction to {state} after heartbeat loss"


ITEMS: dict[str, Callable[[Drive, dict], str]] = {
    "identity": item_identity,
    "nmt_bootup": item_nmt_bootup,
    "nmt_stopped": item_nmt_stopped,
    "heartbeat": item_heartbeat,
    "cia402": item_cia402,
    "modes": item_modes,
    "limits": item_limits,
    "gain_set": item_gain_set,
    "store_restore": item_store_restore,
    "pdo_rates": item_pdo_rates,
    "trace": item_trace,
    "heartbeat_consumer": item_heartbeat_consumer,
}


def run_checks(
    drive: Drive,
    only: list[str] | None = None,
    skip: list[str] | None = None,
    on_result: Callable[[CheckResult], None] | None = None,
    **opts: float,
) -> list[CheckResult]:
    """Run the items (all, or ``only``, minus ``skip``) in order; never raises for an item."""
    names = [n for n in ITEMS if (not only or n in only) and n not in (skip or [])]
    unknown = [n for n in (only or []) + (skip or []) if n not in ITEMS]
    if unknown:
        raise ValueError(f"unknown check item(s) {', '.join(unknown)}; items: {', '.join(ITEMS)}")
    results = []
    for n in names:
        t0 = time.monotonic()
        try:
            detail = ITEMS[n](drive, opts)
            ok = True
        except (CheckFailed, DriveError) as exc:
            ok, detail = False, str(exc)
        except Exception as exc:  # an item must not stop the run
            ok, detail = False, f"{type(exc).__name__}: {exc}"
        r = CheckResult(n, ok, detail, time.monotonic() - t0)
        results.append(r)
        if on_result:
            on_result(r)
    try:
        drive.write("controlword", cia402.CW_DISABLE_VOLTAGE)
    except DriveError:
        pass
    return results
