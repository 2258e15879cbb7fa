"""Shared by the check items: the verdicts and the result, the exceptions an item raises,
the SDO abort and EMCY codes the items expect, and the waits on the drive's own clock."""

from __future__ import annotations

import struct
import time
from collections.abc import Callable
from dataclasses import dataclass

from firmware_protocol import abort_codes, emcy_codes

from ...errors import SdoAbort
from ...link import cia402
from ...link.drive import Drive

__all__ = [
    "ABORT_HIGH",
    "ABORT_LENGTH",
    "ABORT_LOW",
    "ABORT_NO_OBJECT",
    "ABORT_RANGE",
    "ABORT_READ_ONLY",
    "ABORT_STATE",
    "DATA_SET_LOST",
    "DEVICE_TYPE_402_SERVO",
    "EVIDENCE",
    "FAIL",
    "HEARTBEAT_LOSS",
    "NOT_APPLICABLE",
    "NOT_JUDGED",
    "PASS",
    "SILENCE_RESENDS",
    "SIM_TIME",
    "WALL_CAP",
    "CheckFailed",
    "CheckResult",
    "NotApplicable",
]


DEVICE_TYPE_402_SERVO = 0x00020192


ABORT_RANGE = abort_codes.INVALID_VALUE


ABORT_HIGH = abort_codes.VALUE_TOO_HIGH


ABORT_LOW = abort_codes.VALUE_TOO_LOW


ABORT_READ_ONLY = abort_codes.WRITE_READ_ONLY


ABORT_NO_OBJECT = abort_codes.NO_OBJECT


ABORT_LENGTH = abort_codes.LENGTHS


ABORT_STATE = abort_codes.DEVICE_STATE


HEARTBEAT_LOSS = emcy_codes.HEARTBEAT_LOSS


DATA_SET_LOST = emcy_codes.DATA_SET_LOST


#: resends of an SDO request that must get no answer (NMT STOPPED): a lost request or answer
#: on a 5 % lossy bus passes a silent drive anyway, and a drive that answers does so at once
SILENCE_RESENDS = 1


class CheckFailed(Exception):  # noqa: N818
    """An item's expectation was not met (message = the one-line reason)."""


class NotApplicable(Exception):  # noqa: N818
    """The drive lacks what an item tests, by its own account (message = why and the fix): a
    verdict of its own that does not fail the run."""


#: :attr:`CheckResult.verdict` values.
PASS, FAIL, NOT_APPLICABLE, NOT_JUDGED = "pass", "fail", "not applicable", "not judged"


@dataclass
class CheckResult:
    """``name``, ``ok`` (false only for a failure), ``detail`` (one line), ``seconds`` taken,
    ``verdict`` ("pass", "fail", "not applicable" or "not judged": a timing item the host
    stalled in every window, neither failed nor passed), ``evidence`` (what the item sent and
    what came back, for ``--json``; empty for items that give none)."""

    name: str
    ok: bool
    detail: str
    seconds: float
    verdict: str = PASS
    evidence: dict | None = None


#: opts key under which an item's evidence travels to its CheckResult
EVIDENCE = "_evidence"


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


#: Simulated time of a virtual drive (s); firmware on a DSP runs in real time and has none.
SIM_TIME = "sim_info.sim_time"


#: Wall-time cap of a wait bounded by the drive's own time: this many × the bound, + 30 s.
WALL_CAP = 10.0


class _DriveClock:
    """Time as the drive lives it, for bounds that physics sets (a ramp, a record's length):
    a virtual drive's simulated time (0x5030:1 ``sim_info.sim_time``), which lags the wall clock
    when the host starves the simulation (inside User-Mode Linux, or on a busy host); the wall
    clock where the drive has no such object (firmware on a DSP runs in real time)."""

    def __init__(self, d: Drive) -> None:
        self._d = d
        self.simulated = False
        if SIM_TIME in d.table:
            try:
                d.read(SIM_TIME)
                self.simulated = True
            except SdoAbort:
                pass

    def now(self) -> float:
        """The drive's time, s."""
        return float(self._d.read(SIM_TIME)) if self.simulated else time.monotonic()


def _drive_wait(
    d: Drive, done: Callable[[], bool], bound: float, poll: float = 0.02
) -> tuple[bool, float]:
    """Poll ``done()`` until it is true or ``bound`` s of the drive's own time
    (:class:`_DriveClock`) have passed; at most ``WALL_CAP × bound + 30`` s of wall time (a
    drive whose time does not advance). Returns (done, drive seconds waited)."""
    clock = _DriveClock(d)
    t0 = clock.now()
    wall_end = time.monotonic() + WALL_CAP * bound + 30.0
    while True:
        if done():
            return True, clock.now() - t0
        waited = clock.now() - t0
        if waited > bound or time.monotonic() > wall_end:
            return bool(done()), waited
        time.sleep(poll)


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
