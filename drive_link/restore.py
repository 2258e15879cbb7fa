"""Leave the drive as it was found: :func:`leave_as_found` around a step test or identification.

The snapshot is the CiA 402 state, the mode of operation and the setpoints (target_velocity
rpm, setpoints.i_p_ref A, target_torque ‰). On the way out — normal end, error or Ctrl-C
(KeyboardInterrupt) — :func:`restore` puts them back in an order the drive accepts (the mode
changes only with the power stage off, CiA 402 / 0x6060 abort 0x08000022 otherwise):

1. a drive that was not enabled, or is enabled in another mode than before, is disabled first
   (power stage off: a drive found off is stopped);
2. the setpoints are written back;
3. the mode is selected again;
4. the state is reached again: OPERATION ENABLED (the motor returns to the old setpoint),
   SWITCHED ON, or SWITCH ON DISABLED.

A drive in FAULT is left there (the fault is reported by the caller's error). A second Ctrl-C
while restoring is held back until the restore is done (main thread only).
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from .cia402 import (
    FAULT,
    FAULT_REACTION_ACTIVE,
    OPERATION_ENABLED,
    SWITCH_ON_DISABLED,
)
from .errors import DriveError

if TYPE_CHECKING:
    from .drive import Drive

__all__ = ["SETPOINTS", "Snapshot", "leave_as_found", "restore", "snapshot"]

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


def snapshot(drive: Drive) -> Snapshot:
    """Read the state, mode and setpoints of ``drive`` (objects it lacks are skipped)."""
    values = {n: drive.read(n) for n in SETPOINTS if n in drive.table}
    return Snapshot(drive.state, drive.mode, values)


def restore(drive: Drive, snap: Snapshot, timeout: float = 3.0) -> str:
    """Put ``drive`` back into ``snap`` (see the module doc); returns the state reached."""
    _stop_trace(drive)
    state = drive.state
    if state in (FAULT, FAULT_REACTION_ACTIVE):
        return state
    mode_changed = drive.mode != snap.mode
    if state == OPERATION_ENABLED and (snap.state != OPERATION_ENABLED or mode_changed):
        state = drive.disable(timeout=timeout)
    for name, value in snap.setpoints.items():
        if drive.read(name) != value:
            drive.write(name, value)
    if mode_changed:
        drive.set_mode(snap.mode, timeout=max(0.5, timeout / 3))
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
def leave_as_found(drive: Drive, timeout: float = 3.0) -> Iterator[Snapshot]:
    """Snapshot ``drive``, run the block, :func:`restore` it on any exit (Ctrl-C included).

    If the block failed and the restore fails too, one :class:`DriveError` names both.
    """
    snap = snapshot(drive)
    try:
        yield snap
    except BaseException as exc:
        try:
            with _sigint_held():
                restore(drive, snap, timeout)
        except (DriveError, KeyboardInterrupt) as rexc:
            what = "interrupted" if isinstance(exc, KeyboardInterrupt) else str(exc)
            raise DriveError(f"{what}; restoring the drive failed too: {rexc}") from exc
        raise
    with _sigint_held():
        restore(drive, snap, timeout)
