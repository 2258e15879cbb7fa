"""The streaming items: ``pdo_rates`` (the TPDO event timers measured on the bus) and
``trace`` (the recorder armed, triggered and uploaded)."""

from __future__ import annotations

import threading
import time

import numpy as np

from ...errors import DriveError, SdoAbort
from ...link.drive import Drive
from ...link.trace import TS as TRACE_TS
from ._base import _drive_wait, _expect

__all__ = ["item_pdo_rates", "item_trace"]


def _missed_events(d: Drive) -> dict[str, int] | None:
    """TPDO name → the drive's missed event-timer periods (0x2070), or None without 0x2070."""
    out = {}
    for k in range(1, 513):
        name = f"tpdo_missed_events.tpdo{k}"
        if name not in d.table:
            break
        try:
            out[f"TPDO{k}"] = int(d.read(name))
        except SdoAbort:
            return None
    return out or None


def _frame_times(
    d: Drive, cob_ids: list[int], window: float, arrivals_used: set[int] | None = None
) -> dict[int, np.ndarray]:
    """Bus timestamps (s) of the frames of each COB-ID received during ``window`` s (the
    interface's stamps: kernel, hub or adapter; arrival times where a bus gives none)."""
    stamps: dict[int, list[float]] = {c: [] for c in cob_ids}
    arrivals: dict[int, list[float]] = {c: [] for c in cob_ids}
    network = d.network

    def on_frame(can_id: int, data: bytearray, timestamp: float) -> None:
        stamps[can_id].append(float(timestamp or 0.0))
        arrivals[can_id].append(time.monotonic())

    for c in cob_ids:
        network.subscribe(c, on_frame)
    try:
        time.sleep(window)
    finally:
        for c in cob_ids:
            network.unsubscribe(c, on_frame)
    out = {}
    for c in cob_ids:
        ts = np.array(stamps[c])
        ok = ts.size >= 2 and np.all(ts > 0) and np.all(np.diff(ts) >= 0)
        out[c] = ts if ok else np.array(arrivals[c])
        if not ok and arrivals_used is not None:
            arrivals_used.add(c)  # (the verdict says which times it judged)
    return out


def item_pdo_rates(d: Drive, opts: dict) -> str:
    """Each event-timer TPDO is on the bus at 1/event time (± ``rate_tolerance``): the rate
    is taken from the frames' own bus timestamps (frames received − 1 over first-to-last
    stamp), so a host that a busy machine starves, and that therefore reads fewer frames in
    the window, still measures what the drive sent. The bus is the truth: periods the drive
    counts as missed (0x2070) are shown, never added (issue 29: a drive that drops periods
    fails, whatever it counts); a window the host stalled in is measured again
    (:func:`run_checks`)."""
    d.nmt("start")
    live = d.refresh_live()
    window = opts.get("pdo_window", 1.0)
    time.sleep(0.2)
    streams = {name: s for name, s in live.stats["tpdo"].items() if s.get("expected_hz")}
    _expect(bool(streams), "no TPDO with an event timer")
    missed0 = _missed_events(d)
    unstamped: set[int] = set()
    times = _frame_times(d, [int(s["cob_id"]) for s in streams.values()], window, unstamped)
    missed1 = _missed_events(d)
    tol = opts.get("rate_tolerance", 0.25)
    out = []
    for name, s in streams.items():
        exp = s["expected_hz"]
        ts = times[int(s["cob_id"])]
        _expect(
            ts.size >= 3, f"{name}: only {ts.size} frames in {window:g} s, expected {exp:.0f} Hz"
        )
        sent = (ts.size - 1) / max(float(ts[-1] - ts[0]), 1e-9)
        missed = 0
        if missed0 is not None and missed1 is not None and name in missed0:
            missed = (missed1[name] - missed0[name]) % (1 << 32)
        extra = f" ({missed} missed)" if missed else ""  # the drive's own count, shown only
        _expect(
            abs(sent - exp) <= tol * exp, f"{name} at {sent:.0f} Hz, expected {exp:.0f} Hz{extra}"
        )
        got = f", {ts.size} frames read" if ts.size < 0.8 * exp * window else ""
        out.append(f"{name} {sent:.0f}/{exp:.0f} Hz{extra}{got}")
    source = "arrival times: the bus gave no time stamps" if unstamped else "bus time stamps"
    return (
        ", ".join(out)
        + f" over {window:g} s ({source}); bus load {100 * (live.stats.get('bus_load') or 0):.0f} %"
    )


def item_trace(d: Drive, opts: dict) -> str:
    length = 2000
    d.trace.configure(
        ["i_p", "speed"], divider=1, length=length, pre_trigger=0, trigger="immediate"
    )
    d.trace.arm()
    # the record takes length × 20 µs of the drive's time (divider 1, immediate trigger):
    # bounded by that time as the drive delivers it, not by the wall clock
    state = [""]

    def done() -> bool:
        state[0] = d.trace.state
        _expect(state[0] != "idle", "trace recorder went idle before it was done")
        return state[0] == "done"

    ok, waited = _drive_wait(d, done, length * TRACE_TS + 1.0)
    _expect(ok, f"trace not done after {waited:.2f} s of drive time (recorder {state[0]})")
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
