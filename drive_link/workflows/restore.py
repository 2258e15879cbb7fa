"""Leave the drive as it was found: :func:`leave_as_found` around a step test or identification.

The snapshot is the CiA 402 state, the mode of operation, the setpoints (target_velocity
rpm, setpoints.i_p_ref A, target_torque ‰), the disable-operation option code (0x605C), any
further objects an experiment names (``settings``: e.g. the virtual load torque) and, when asked,
the controller gains. On the way out — normal end, error or Ctrl-C (KeyboardInterrupt) —
:func:`restore` puts them back in an order the drive accepts (the mode changes only with the
power stage off, CiA 402 / 0x6060 abort 0x08000022 otherwise):

1. a drive that was not enabled, or is enabled in another mode than before, is disabled first
   (power stage off: a drive found off is stopped). A mode switch coasts (:func:`switch_mode`:
   0x605C = 0 for that one transition) instead of braking on the slow-down ramp at the
   current limit, unless ``brake`` is asked;
2. the settings and gains are written back (gains as one set,
:func:`drive_link.workflows.gains.apply_gains`);
3. the setpoints are written back;
4. the mode is selected again;
5. the state is reached again: OPERATION ENABLED (the motor returns to the old setpoint),
   SWITCHED ON, or SWITCH ON DISABLED.

A drive in FAULT is left there (the fault is reported by the caller's error). A second Ctrl-C
while restoring is held back until the restore is done (main thread only).

A quick stop wins over "as found": after a quick stop sent by this host since the snapshot
(:attr:`Drive.stops <drive_link.link.drive.Drive.stops>`), or with the drive in QUICK STOP ACTIVE,
steps 2-4 are still done but step 5 is not: the drive stays stopped (QUICK STOP ACTIVE or
SWITCH ON DISABLED) until the user enables it; and inside :func:`leave_as_found` the block
itself cannot enable the drive again after such a quick stop (:mod:`drive_link.link._stop_guard`).
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from firmware_protocol.enums import ModeOfOperation

from ..errors import DriveError
from ..link import cia402
from ..link.cia402 import (
    FAULT,
    FAULT_REACTION_ACTIVE,
    OPERATION_ENABLED,
    QUICK_STOP_ACTIVE,
    SWITCH_ON_DISABLED,
)

if TYPE_CHECKING:
    from ..link.drive import Drive

__all__ = [
    "DISABLE_OPTION",
    "SETPOINTS",
    "Snapshot",
    "leave_as_found",
    "restore",
    "snapshot",
    "switch_mode",
]

#: CiA 402 disable operation option code (0x605C): 0 coast, 1 slow-down ramp, then off.
DISABLE_OPTION = "disable_operation_option_code"

#: Setpoint objects saved and written back (name → unit, for messages).
SETPOINTS: dict[str, str] = {
    "target_velocity": "rpm",
    "setpoints.i_p_ref": "A",
    "target_torque": "permille",
}


@dataclass(frozen=True)
class Snapshot:
    """What :func:`restore` puts back: ``state`` (CiA 402 name), ``mode`` ("speed",
    "current", "torque") and ``setpoints`` (object name → value in its OD unit)."""

    state: str
    mode: str
    setpoints: dict[str, Any] = field(default_factory=dict)
    settings: dict[str, Any] = field(default_factory=dict)
    gains: dict[str, Any] | None = None
    quick_stops: int = 0  #: the host's quick stops counted when the snapshot was taken

    def describe(self) -> str:
        """One line: what the drive is put back to (state, mode, setpoint in use)."""
        sp = {"speed": "target_velocity", "current": "setpoints.i_p_ref"}.get(self.mode)
        val = ""
        if sp is not None and sp in self.setpoints:
            val = f" at {self.setpoints[sp]:g} {SETPOINTS[sp]}"
        return f"{self.state}, {self.mode} mode{val}"


def snapshot(
    drive: Drive, settings: tuple[str, ...] = (), gains: bool = False
) -> Snapshot:
    """Read the state, mode and setpoints of ``drive``, the disable option code, the objects
    named in ``settings`` and (``gains``) the controller gains; objects it lacks are skipped."""
    values = {n: drive.read(n) for n in SETPOINTS if n in drive.table}
    names = (DISABLE_OPTION, *settings)
    extra = {n: drive.read(n) for n in dict.fromkeys(names) if n in drive.table}
    g = drive.read_gains().to_dict() if gains else None
    return Snapshot(drive.state, drive.mode, values, extra, g, _stop_count(drive))


def _stop_count(drive: Drive) -> int:
    stops = getattr(drive, "stops", None)
    return int(stops.count) if stops is not None else 0


def quick_stopped(drive: Drive, snap: Snapshot, state: str) -> bool:
    """Whether a quick stop came since ``snap`` (this host's, counted; or any, seen as the
    drive's ``state`` QUICK STOP ACTIVE): then :func:`restore` does not enable the drive."""
    stops = getattr(drive, "stops", None)
    if stops is not None and (stops.stopped() or stops.count != snap.quick_stops):
        return True
    return state == QUICK_STOP_ACTIVE


def switch_mode(
    drive: Drive, mode: str | ModeOfOperation, *, brake: bool = False, timeout: float = 3.0
) -> None:
    """Select ``mode`` ("speed", "current", "torque" or a :class:`ModeOfOperation`); an enabled
    drive is disabled for the switch and enabled again.

    The power stage goes off coasting (0x605C set to 0 for that transition and put back), not
    on the drive's slow-down ramp, which brakes at the current limit (-100 A) to standstill;
    ``brake=True`` keeps the drive's own option code."""
    if drive.mode == cia402.mode_name(cia402.mode_value(mode)):
        return
    if drive.state != OPERATION_ENABLED:
        drive.set_mode(mode, timeout=max(0.5, timeout / 3))
        return
    _coast_disable(drive, brake, timeout)
    drive.set_mode(mode, timeout=max(0.5, timeout / 3))
    drive.enable(timeout=timeout)


def _coast_disable(drive: Drive, brake: bool, timeout: float) -> str:
    """Power stage off; coasting unless ``brake`` (see :func:`switch_mode`)."""
    if brake or DISABLE_OPTION not in drive.table:
        return drive.disable(timeout=timeout)
    old = drive.read(DISABLE_OPTION)
    if old == 0:
        return drive.disable(timeout=timeout)
    drive.write(DISABLE_OPTION, 0)
    try:
        return drive.disable(timeout=timeout)
    finally:
        drive.write(DISABLE_OPTION, old)


def restore(drive: Drive, snap: Snapshot, timeout: float = 3.0, brake: bool = False) -> str:
    """Put ``drive`` back into ``snap`` (see the module doc); returns the state reached."""
    _stop_trace(drive)
    state = drive.state
    if state in (FAULT, FAULT_REACTION_ACTIVE):
        return state
    stopped = quick_stopped(drive, snap, state)
    mode_changed = drive.mode != snap.mode
    if state == OPERATION_ENABLED and (snap.state != OPERATION_ENABLED or mode_changed):
        state = _coast_disable(drive, brake, timeout)
    for name, value in snap.settings.items():
        if drive.read(name) != value:
            drive.write(name, value)
    if snap.gains is not None:
        now = drive.read_gains().to_dict()
        diff = {k: v for k, v in snap.gains.items() if now.get(k) != v}
        if diff:
            from .gains import apply_gains

            # the set found on the drive goes back as one set through the one policy path
            # (forced: it was in use, poor margins or not)
            apply_gains(drive, diff, force=True)
    for name, value in snap.setpoints.items():
        if drive.read(name) != value:
            drive.write(name, value)
    if mode_changed:
        drive.set_mode(snap.mode, timeout=max(0.5, timeout / 3))
    if stopped:  # a quick stop wins: the user enables the drive again, nobody else
        return drive.state
    if snap.state == OPERATION_ENABLED:
        if drive.state != OPERATION_ENABLED:
            return drive.enable(timeout=timeout)
        return OPERATION_ENABLED
    if snap.state == SWITCH_ON_DISABLED:
        return drive.sm.disable_voltage(timeout)
    return drive.disable(timeout=timeout)


def _stop_trace(drive: Drive) -> None:
    """Stop a recording left armed by an interrupted capture (best effort)."""
    try:
        tr = drive.trace
        if tr.state in ("armed", "recording"):
            tr.stop()
    except (DriveError, AttributeError):
        pass


@contextlib.contextmanager
def _sigint_held() -> Iterator[None]:
    """Hold SIGINT back until the block ends (then raise KeyboardInterrupt once)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    got: list[int] = []
    try:
        old = signal.signal(signal.SIGINT, lambda signum, frame: got.append(signum))
    except ValueError:  # not the main interpreter
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)
    if got:
        raise KeyboardInterrupt


@contextlib.contextmanager
def leave_as_found(
    drive: Drive,
    timeout: float = 3.0,
    *,
    settings: tuple[str, ...] = (),
    gains: bool = False,
    brake: bool = False,
    found: Snapshot | None = None,
) -> Iterator[Snapshot]:
    """Snapshot ``drive`` (or take ``found``, a snapshot made earlier by the caller), run the
    block, :func:`restore` it on any exit (Ctrl-C included). ``settings``/``gains``: what else
    the block may change (see :func:`snapshot`); ``brake``: see :func:`switch_mode`.

    If the block failed and the restore fails too, one :class:`DriveError` names both.
    """
    snap = found if found is not None else snapshot(drive, settings, gains)
    stops = getattr(drive, "stops", None)
    with stops.watch() if stops is not None else contextlib.nullcontext():
        try:
            yield snap
        except BaseException as exc:
            try:
                with _sigint_held():
                    restore(drive, snap, timeout, brake)
            except (DriveError, KeyboardInterrupt) as rexc:
                what = "interrupted" if isinstance(exc, KeyboardInterrupt) else str(exc)
                raise DriveError(f"{what}; restoring the drive failed too: {rexc}") from exc
            raise
        with _sigint_held():
            restore(drive, snap, timeout, brake)
