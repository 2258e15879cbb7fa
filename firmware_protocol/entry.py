"""One object of the drive's OD and its value check (CiA 301 SDO abort codes).

:class:`Entry` is built by :func:`firmware_protocol.od.load_od` from the EDS; :meth:`Entry.check`
is what the drive runs before storing a write and what the host runs before sending one.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Mapping
from dataclasses import dataclass

from . import abort_codes

__all__ = [
    "ABORT_INVALID_VALUE",
    "ABORT_VALUE_TOO_HIGH",
    "ABORT_VALUE_TOO_LOW",
    "TYPE_NAMES",
    "Entry",
    "LimitError",
    "Number",
    "f32",
]

#: CiA 301 SDO abort codes used by value checks (aliases of :mod:`firmware_protocol.abort_codes`).
ABORT_INVALID_VALUE = abort_codes.INVALID_VALUE
ABORT_VALUE_TOO_HIGH = abort_codes.VALUE_TOO_HIGH
ABORT_VALUE_TOO_LOW = abort_codes.VALUE_TOO_LOW

#: CiA 301 data type code -> name.
TYPE_NAMES: dict[int, str] = {
    0x01: "BOOLEAN",
    0x02: "INTEGER8",
    0x03: "INTEGER16",
    0x04: "INTEGER32",
    0x05: "UNSIGNED8",
    0x06: "UNSIGNED16",
    0x07: "UNSIGNED32",
    0x08: "REAL32",
    0x09: "VISIBLE_STRING",
    0x0A: "OCTET_STRING",
    0x0F: "DOMAIN",
}

BIT_LENGTH = {0x01: 1, 0x02: 8, 0x03: 16, 0x04: 32, 0x05: 8, 0x06: 16, 0x07: 32, 0x08: 32}
_INT_RANGE = {
    0x01: (0, 1),
    0x02: (-(2**7), 2**7 - 1),
    0x03: (-(2**15), 2**15 - 1),
    0x04: (-(2**31), 2**31 - 1),
    0x05: (0, 2**8 - 1),
    0x06: (0, 2**16 - 1),
    0x07: (0, 2**32 - 1),
}
SIGNED = {0x02, 0x03, 0x04}
REAL32 = 0x08
_FLT_MAX = 3.4028234663852886e38
FLT_MIN_NORMAL = 1.1754943508222875e-38
"""Smallest normal float32: nonzero REAL32 values below it (subnormals, or values that round
to 0 in float32) are refused: the F28335 FPU flushes subnormals to zero, so the DSP would not
compute with the value the master wrote."""
Number = int | float


class LimitError(ValueError):
    """A value an object refuses, with the CiA 301 SDO abort code the drive answers with.

    ``abort_code`` is 0x06090030 (invalid value: NaN, inf, wrong type, not in the enumeration),
    0x06090031 (value too high) or 0x06090032 (value too low).
    """

    def __init__(self, abort_code: int, message: str) -> None:
        super().__init__(f"{message} (SDO abort 0x{abort_code:08X})")
        self.abort_code = abort_code
        self.message = message


def f32(x: float) -> float:
    """Round a Python float to the nearest IEEE-754 binary32 (the DSP's float)."""
    value: float = struct.unpack("<f", struct.pack("<f", x))[0]
    return value


@dataclass(frozen=True)
class Entry:
    """One object or sub-object of the dictionary.

    ``low``/``high`` are the inclusive static limits in the object's unit (``None`` = only the
    data type's range applies); ``default`` is the EDS default with ``$NODEID`` resolved.
    """

    name: str
    index: int
    subindex: int
    data_type: int
    access: str
    unit: str | None
    low: Number | None
    high: Number | None
    default: Number | str | bytes | None
    default_raw: str | None
    pdo_mappable: bool
    description: str
    enum: Mapping[int, str] | None = None
    persistent: bool = False
    obj_flags: int = 0
    object_name: str = ""
    sub_name: str = ""
    min_nonzero: Number | None = None
    config_only: bool = False
    """Custom EDS key ``ConfigOnly=1``: the object defines the plant or its protection and may
    be written only while the power stage is off (abort 0x08000022 in OPERATION ENABLED and
    during stop ramps)."""
    """Custom EDS key ``MinNonZero``: a nonzero value must satisfy ``|value| >= min_nonzero``
    (e.g. R_c is 0 or at least 1e-4 Ohm); values in between are refused as too low."""

    @property
    def type_name(self) -> str:
        """CiA 301 type name, e.g. ``"REAL32"``, ``"UNSIGNED8"``."""
        return TYPE_NAMES.get(self.data_type, f"0x{self.data_type:04X}")

    @property
    def bit_length(self) -> int:
        """Bit length as used in PDO mapping entries; 0 for variable-length types."""
        return BIT_LENGTH.get(self.data_type, 0)

    @property
    def is_real(self) -> bool:
        """True for REAL32 objects."""
        return self.data_type == REAL32

    @property
    def readable(self) -> bool:
        """True unless the object is write-only."""
        return self.access != "wo"

    @property
    def writable(self) -> bool:
        """True for rw/wo/rww/rwr objects."""
        return self.access in ("rw", "wo", "rww", "rwr")

    @property
    def relative(self) -> bool:
        """True when the default depends on the node-ID (``$NODEID`` in the EDS)."""
        return self.default_raw is not None and "$NODEID" in self.default_raw.upper()

    @property
    def od_reference(self) -> int:
        """``index << 16 | subindex << 8 | bit_length`` (PDO mapping / trace channel format)."""
        if not self.bit_length:
            raise ValueError(f"{self.name} ({self.type_name}) has no fixed bit length")
        return (self.index << 16) | (self.subindex << 8) | self.bit_length

    def check(self, value: object) -> Number | str | bytes:
        """Validate ``value`` for a write; return it as the object's Python type.

        Raises :class:`LimitError` with 0x06090030 for NaN/inf, a non-number, a non-integral
        value for an integer type or a value outside the enumeration; 0x06090031 above the
        high limit (or the type's range); 0x06090032 below the low limit. REAL32 values and
        limits are compared after rounding to float32, as the drive stores them; a nonzero
        REAL32 that is subnormal (or 0) in float32 gets 0x06090030, a nonzero value below
        :attr:`min_nonzero` 0x06090032.
        """
        dt = self.data_type
        if dt in (0x09,):
            if not isinstance(value, str):
                raise LimitError(ABORT_INVALID_VALUE, f"{self.name} expects a string")
            return value
        if dt in (0x0A, 0x0F):
            if not isinstance(value, (bytes, bytearray)):
                raise LimitError(ABORT_INVALID_VALUE, f"{self.name} expects bytes")
            return bytes(value)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            try:
                import numpy as np  # numpy scalars are common on the host side

                if isinstance(value, (np.integer, np.floating)):
                    value = value.item()
                else:
                    raise TypeError
            except (ImportError, TypeError):
                raise LimitError(
                    ABORT_INVALID_VALUE, f"{self.name} expects a number, got {value!r}"
                ) from None
        assert isinstance(value, (int, float))
        if isinstance(value, float) and not math.isfinite(value):
            raise LimitError(ABORT_INVALID_VALUE, f"{self.name} = {value} is not a finite number")
        if dt == REAL32:
            try:
                as_float = float(value)
            except OverflowError:  # an int beyond any float
                code = ABORT_VALUE_TOO_HIGH if value > 0 else ABORT_VALUE_TOO_LOW
                raise LimitError(code, f"{self.name} = {value} does not fit in a REAL32") from None
            return self._check_real(as_float)
        return self._check_int(value)

    def _check_real(self, value: float) -> float:
        unit = f" {self.unit}" if self.unit else ""
        if abs(value) > _FLT_MAX:
            code = ABORT_VALUE_TOO_HIGH if value > 0 else ABORT_VALUE_TOO_LOW
            raise LimitError(code, f"{self.name} = {value}{unit} does not fit in a REAL32")
        v32 = f32(value)
        if value != 0.0 and abs(v32) < FLT_MIN_NORMAL:
            raise LimitError(
                ABORT_INVALID_VALUE,
                f"{self.name} = {value:g}{unit} is subnormal in float32 (0 or |x| >= 1.18e-38)",
            )
        if self.min_nonzero is not None and v32 != 0.0 and abs(v32) < f32(self.min_nonzero):
            raise LimitError(
                ABORT_VALUE_TOO_LOW,
                f"{self.name} = {value:g}{unit} must be 0 or at least {self.min_nonzero:g}{unit}",
            )
        if self.high is not None and v32 > f32(float(self.high)):
            raise LimitError(
                ABORT_VALUE_TOO_HIGH, f"{self.name} = {value:g}{unit} above {self.high:g}{unit}"
            )
        if self.low is not None and v32 < f32(float(self.low)):
            raise LimitError(
                ABORT_VALUE_TOO_LOW, f"{self.name} = {value:g}{unit} below {self.low:g}{unit}"
            )
        return v32

    def _check_int(self, value: Number) -> int:
        if isinstance(value, float):
            if not value.is_integer():
                raise LimitError(
                    ABORT_INVALID_VALUE, f"{self.name} ({self.type_name}) = {value} is not integral"
                )
            value = int(value)
        t_low, t_high = _INT_RANGE[self.data_type]
        high = t_high if self.high is None else min(t_high, int(self.high))
        low = t_low if self.low is None else max(t_low, int(self.low))
        unit = f" {self.unit}" if self.unit and self.unit != "1" else ""
        if value > high:
            raise LimitError(
                ABORT_VALUE_TOO_HIGH, f"{self.name} = {value}{unit} above {high}{unit}"
            )
        if value < low:
            raise LimitError(ABORT_VALUE_TOO_LOW, f"{self.name} = {value}{unit} below {low}{unit}")
        if self.enum is not None and value not in self.enum:
            allowed = ", ".join(f"{k} {v}" for k, v in sorted(self.enum.items()))
            raise LimitError(ABORT_INVALID_VALUE, f"{self.name} = {value} is not one of: {allowed}")
        return value
