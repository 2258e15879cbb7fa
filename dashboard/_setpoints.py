"""Setpoints to the drive without reading anything first: by RPDO where the drive maps them,
by SDO otherwise.

The drive's RPDO layouts (0x1400+k cob_id and transmission type, 0x1600+k mapping; the EDS maps
RPDO1 = controlword + target_velocity, RPDO2 = setpoints.i_p_ref, both event-driven) are read
once per drive, on the first setpoint (9 reads with the EDS defaults), and kept. A setpoint
then goes:

- by RPDO when an enabled RPDO maps the object, every other object it maps has a known value
  (the controlword is known only in OPERATION ENABLED: 0x000F, "enable operation", which keeps
  the state) and the node is OPERATIONAL (a PDO is processed only there): one frame, no reply;
- by SDO otherwise (one expedited download).

Either way the value is checked first, on the host, without a read: its object's range, and the
OD's cross-object rules it triggers (|target_velocity| ≤ max_motor_speed,
|i_p_ref| ≤ speed_controller.current_limit) on the other operands as last known (each read
once, then kept; :meth:`SetpointLink.note` updates one, :meth:`SetpointLink.forget` drops them
after something rewrote the configuration). The drive checks again: an SDO write is aborted, a
refused RPDO is dropped whole with an EMCY (0x8200).

Units: the objects' (rpm, A).
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import Any

import can

from drive_link.errors import InvalidValue
from firmware_protocol.constraints import CONSTRAINTS

__all__ = ["CW_ENABLE_OPERATION", "RpdoLayout", "SetpointLink"]

CW_ENABLE_OPERATION = 0x000F  #: the controlword that holds OPERATION ENABLED (CiA 402 Table 4)
_N_RPDO_MAX = 4  #: RPDOs looked for (the predefined connection set has four)


@dataclass(frozen=True)
class RpdoLayout:
    """One enabled RPDO: its COB-ID and mapped objects as (OD name, bits), in frame order."""

    cob_id: int
    objects: tuple[tuple[str, int], ...]


class SetpointLink:
    """How one drive (``drive_link.Drive``) is sent its setpoints."""

    def __init__(self, drive: Any) -> None:
        self.drive = drive
        self._layouts: list[RpdoLayout] | None = None
        self._known: dict[str, float | int] = {}
        self._lock = threading.Lock()

    # ------------------------------------------------------------------ what is known
    def note(self, name: str, value: float | int) -> None:
        """Record an object's value known without reading it (e.g. a gain set just applied)."""
        with self._lock:
            self._known[name] = value

    def forget(self) -> None:
        """Drop the kept operands and layouts (the configuration was rewritten, e.g. a DCF)."""
        with self._lock:
            self._known.clear()
            self._layouts = None

    def _operand(self, name: str) -> float | int:
        with self._lock:
            if name in self._known:
                return self._known[name]
        value: float | int = self.drive.read(name)  # once; then kept (a numeric operand)
        self.note(name, value)
        return value

    def layouts(self) -> list[RpdoLayout]:
        """The drive's enabled, event-driven RPDOs (read once: cob_id, transmission type, count
    and entries of each)."""
        with self._lock:
            if self._layouts is not None:
                return self._layouts
        found: list[RpdoLayout] = []
        table = self.drive.table
        for k in range(1, _N_RPDO_MAX + 1):
            try:
                self.drive.info(f"rpdo{k}_communication.cob_id")
            except Exception:
                break  # the OD has no more RPDOs
            cob = int(self.drive.read(f"rpdo{k}_communication.cob_id"))
            if cob & 0x8000_0000:
                continue  # disabled
            if int(self.drive.read(f"rpdo{k}_communication.transmission_type")) < 0xFE:
                continue  # synchronous: it would apply only at a SYNC the host may never send
            n = int(self.drive.read(f"rpdo{k}_mapping.number_of_mapped_objects"))
            objects = []
            for i in range(1, n + 1):
                entry = int(self.drive.read(f"rpdo{k}_mapping.mapped_object_{i}"))
                info = table.by_index(entry >> 16, (entry >> 8) & 0xFF)
                objects.append((info.name if info is not None else "", entry & 0xFF))
            found.append(RpdoLayout(cob & 0x7FF, tuple(objects)))
        with self._lock:
            self._layouts = found
        return found

    # ------------------------------------------------------------------ sending
    def check(self, name: str, value: float | int) -> None:
        """Range of ``name``'s object and the cross-object rules it triggers (no read of what
        is known); :class:`InvalidValue` otherwise."""
        self.drive.info(name).check(value)
        for c in CONSTRAINTS:
            if name not in c.triggers:
                continue
            values = {n: value if n == name else self._operand(n) for n in c.names}
            if not c.holds(values):
                shown = ", ".join(f"{n} = {values[n]:.6g}" for n in c.names)
                raise InvalidValue(
                    f"refused before sending: {c} does not hold ({shown}): {c.reason}"
                )

    def send(self, name: str, value: float | int, *, state: str | None, nmt: str | None) -> str:
        """Check and send ``name`` := ``value``; ``state`` (CiA 402) and ``nmt`` as known.
        Returns "rpdo" or "sdo" (how it went)."""
        self.check(name, value)
        if nmt == "OPERATIONAL":
            known: dict[str, float | int] = {name: value}
            if state == "OPERATION ENABLED":
                known["controlword"] = CW_ENABLE_OPERATION
            for layout in self.layouts():
                names = [n for n, _bits in layout.objects]
                if name not in names or not all(n in known for n in names):
                    continue
                parts = [self.drive.info(n).encode(known[n]) for n in names]
                sizes = [bits for _n, bits in layout.objects]
                if [len(p) * 8 for p in parts] == sizes:
                    data = b"".join(parts)
                    msg = can.Message(arbitration_id=layout.cob_id, data=data, is_extended_id=False)
                    self.drive.bus.send(msg)
                    return "rpdo"
        obj = self.drive.info(name)
        self.drive.sdo.download(obj.index, obj.subindex, obj.encode(value), name)
        return "sdo"
