"""The CiA 301 network-management items: ``identity``, ``nmt_bootup``, ``nmt_stopped``,
``heartbeat``, ``heartbeat_consumer``, ``nmt_reaction`` (the drive's reaction to a lost
heartbeat and to NMT commands while it runs)."""

from __future__ import annotations

import time

import numpy as np

from ...errors import DriveError, DriveTimeout
from ...link import cia402
from ...link._nmt import HeartbeatProducer
from ...link.drive import Drive
from ._base import (
    DEVICE_TYPE_402_SERVO,
    HEARTBEAT_LOSS,
    SILENCE_RESENDS,
    _expect,
    _to_switch_on_disabled,
)
from ._snapshot import _put_back_comm
from .motion import _ramp_bound, _ramp_time, _spin, _wait_standstill

__all__ = [
    "CONSUMER_MS",
    "item_heartbeat",
    "item_heartbeat_consumer",
    "item_identity",
    "item_nmt_bootup",
    "item_nmt_reaction",
    "item_nmt_stopped",
]


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
    # The command and the boot-up are single unconfirmed frames: on a lossy bus either can be
    # lost, so the reset is sent again (up to 3 times) until a boot-up message is seen.
    for attempt in range(1, 4):
        boots = hb.boot_count
        t0 = time.monotonic()
        d.nmt("reset communication")
        try:
            hb.wait_boot(3.0, boots)
            break
        except DriveTimeout:
            if attempt == 3:
                raise
    dt_boot = time.monotonic() - t0
    st = hb.wait_for(("PRE-OPERATIONAL",), 2.0, after=time.monotonic() - 0.001)
    try:
        back = _put_back_comm(d, opts)
    finally:
        t1 = time.monotonic()
        d.nmt("start")
    hb.wait_for(("OPERATIONAL",), 2.0, after=t1)
    again = f" (reset sent {attempt} times)" if attempt > 1 else ""
    kept = f"; {back} communication objects put back as found" if back else ""
    return (
        f"boot-up after {dt_boot * 1e3:.0f} ms{again}, heartbeat {st} then OPERATIONAL after "
        f"start{kept}"
    )


def item_nmt_stopped(d: Drive, opts: dict) -> str:
    hb = d.heartbeat
    t0 = time.monotonic()
    d.nmt("stop")
    try:
        hb.wait_for(("STOPPED",), 2.0, after=t0)
        answered = True
        try:  # two requests, 0.3 + 0.6 s: the channel's five resends would wait 5.7 s
            with d.sdo.patience(d.sdo.client.RESPONSE_TIMEOUT, retries=SILENCE_RESENDS):
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


def _heartbeat_times(d: Drive, window: float) -> np.ndarray:
    """Times (s) of the drive's heartbeats during ``window`` s: the frames' own timestamps
    (stamped by the interface when the frame was received: kernel, hub or virtual bus), which a
    busy host's late notifier thread does not bunch up; arrival times if a bus gives none."""
    stamps: list[float] = []
    arrivals: list[float] = []
    network = d.network
    cob = 0x700 + d.node_id

    def on_frame(can_id: int, data: bytearray, timestamp: float) -> None:
        stamps.append(float(timestamp or 0.0))
        arrivals.append(time.monotonic())

    network.subscribe(cob, on_frame)
    try:
        time.sleep(window)
    finally:
        network.unsubscribe(cob, on_frame)
    ts = np.array(stamps)
    if ts.size >= 2 and np.all(ts > 0) and np.all(np.diff(ts) >= 0):
        return ts
    return np.array(arrivals)


def item_heartbeat(d: Drive, opts: dict) -> str:
    period_ms = int(d.read("producer_heartbeat_time"))
    _expect(period_ms > 0, "producer_heartbeat_time is 0 (heartbeat off)")
    results = []
    for p in (period_ms, 50):
        d.write("producer_heartbeat_time", p)
        try:
            time.sleep(2 * p / 1000)
            window = max(1.0, 20 * p / 1000)
            times = _heartbeat_times(d, window)
        finally:
            d.write("producer_heartbeat_time", period_ms)
        _expect(len(times) >= 3, f"only {len(times)} heartbeats in {window:g} s")
        # mean period over the window (first to last frame): a host or hub that a busy
        # machine stalls delivers frames in bunches, which shrinks a median of the gaps (13.7 ms
        # for a 50 ms producer at load 28) but not the span; a lost frame adds 1/n
        measured = float(times[-1] - times[0]) / (len(times) - 1) * 1000
        tol = opts.get("rate_tolerance", 0.25)
        _expect(
            abs(measured - p) <= tol * p + 2, f"heartbeat period {measured:.1f} ms, expected {p} ms"
        )
        results.append(f"{p} ms → {measured:.1f} ms ({len(times)} frames)")
    return "period " + ", ".join(results) + " (mean over bus time stamps)"


#: Consumer heartbeat time (ms) the heartbeat_consumer item sets for its 50 ms test producer.
CONSUMER_MS = 1000


def item_heartbeat_consumer(d: Drive, opts: dict) -> str:
    period = 50
    prod = HeartbeatProducer(d.bus, 0x7E, period)
    stopped = False
    try:
        d.set_mode("speed")
        d.set_speed(0)
        d.enable()
        n_emcy = len(d.emcy_history)
        # consumer time 1000 ms (the library's default floor, 20 producer periods): a host
        # thread that a busy machine starves for 200 ms must not trip a motor (seen at load 28)
        d.write("consumer_heartbeat_time.consumer_1", (0x7E << 16) | CONSUMER_MS)
        time.sleep(0.3)
        _expect(
            d.state == cia402.OPERATION_ENABLED,
            f"drive left OPERATION ENABLED with heartbeat alive ({d.state})",
        )
        logged = [e.code for e in d.error_history()]  # 0x1003, newest first
        prod.stop()
        stopped = True
        deadline = time.monotonic() + CONSUMER_MS / 1000 + 2.0
        codes: list[int] = []
        while time.monotonic() < deadline:
            codes = [e.code for e in d.emcy_history[n_emcy:]]
            if HEARTBEAT_LOSS in codes and d.state != cia402.OPERATION_ENABLED:
                break
            time.sleep(0.02)
        state = d.state
        if HEARTBEAT_LOSS not in codes:  # the EMCY is one unconfirmed frame: 0x1003 keeps it too
            now = [e.code for e in d.error_history()]
            if now != logged and HEARTBEAT_LOSS in now[: max(1, len(now) - len(logged))]:
                codes.append(HEARTBEAT_LOSS)
        _expect(
            HEARTBEAT_LOSS in codes,
            f"no EMCY 0x{HEARTBEAT_LOSS:04X} after heartbeat loss (got {[hex(c) for c in codes]})",
        )
        _expect(
            state != cia402.OPERATION_ENABLED, "drive still OPERATION ENABLED after heartbeat loss"
        )
    finally:
        if stopped:  # the heartbeat comes back, so the drive clears its 0x8130 error itself
            prod = HeartbeatProducer(d.bus, 0x7E, period)
            _wait_error_cleared(d, HEARTBEAT_LOSS, CONSUMER_MS / 1000 + 2.0)
        prod.stop()
        d.write("consumer_heartbeat_time.consumer_1", 0)
        _to_switch_on_disabled(d)
    return f"EMCY 0x{HEARTBEAT_LOSS:04X} and reaction to {state} after heartbeat loss"


def _wait_error_cleared(d: Drive, code: int, timeout: float) -> None:
    """Wait up to ``timeout`` s until the drive's error code (0x603F) is no longer ``code``
    (a fault it caused is reset as well); the "as_found" item reports what is left."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        try:
            if int(d.read("error_code")) != code:
                return
            if d.state in (cia402.FAULT, cia402.FAULT_REACTION_ACTIVE):
                d.fault_reset()
        except DriveError:
            pass
        time.sleep(0.05)


def item_nmt_reaction(d: Drive, opts: dict) -> str:
    """CiA 402 §6.3.3 / CiA 301 §7.3.2: NMT Stop and Reset Communication while OPERATION
    ENABLED run the abort connection option 0x6007 (here 3 = quick stop): the motor stops and
    the drive leaves OPERATION ENABLED."""
    option0 = int(d.read("abort_connection_option_code"))
    out = []
    try:
        d.write("abort_connection_option_code", 3)
        for command, back in (("stop", "pre-operational"), ("reset communication", None)):
            v0 = _spin(d)
            ramp = _ramp_time(d, v0)
            bound = _ramp_bound(ramp)
            t0 = time.monotonic()
            if back is None:
                d.reset(communication_only=True, timeout=bound + 3.0)
            else:
                d.nmt(command)
                d.heartbeat.wait_for(("STOPPED",), 2.0, after=t0)
                # no SDO in STOPPED: look once it is PRE-OPERATIONAL again, after the ramp's
                # own time (the bound below still gives the ramp its full margin)
                time.sleep(ramp)
                t1 = time.monotonic()
                d.nmt(back)
                d.heartbeat.wait_for(("PRE-OPERATIONAL",), 2.0, after=t1)
            v = _wait_standstill(d, bound)
            state = d.state
            _expect(
                abs(v) <= 15.0,
                f"NMT {command} at {v0:.0f} rpm: motor still at {v:.0f} rpm after {bound:.1f} s",
            )
            _expect(
                state != cia402.OPERATION_ENABLED,
                f"NMT {command}: drive still OPERATION ENABLED (0x6007 reaction missing)",
            )
            out.append(f"{command}: {v0:.0f} → {v:.0f} rpm, {state}")
            if back is None:
                back_n = _put_back_comm(d, opts)  # still PRE-OPERATIONAL after the reset
                if back_n:
                    out[-1] += f", {back_n} communication objects put back"
    finally:
        d.nmt("start")
        _to_switch_on_disabled(d)
        d.write("abort_connection_option_code", option0)
    return "; ".join(out)
