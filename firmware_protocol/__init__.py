"""The drive's CANopen object dictionary: EDS (source of truth), Python view, generated C header.

>>> from firmware_protocol import load_od
>>> od = load_od()
>>> od.entry("current_controller.L_c").unit
'H'
"""

from .od import (
    CONSTRAINTS,
    EDS_PATH,
    Constraint,
    Entry,
    LimitError,
    ObjectDictionaryView,
    load_od,
)

__all__ = [
    "CONSTRAINTS",
    "EDS_PATH",
    "Constraint",
    "Entry",
    "LimitError",
    "ObjectDictionaryView",
    "load_od",
]
