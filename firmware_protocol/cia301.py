"""CiA 301 command values the drive checks: the store and restore signatures.

A write of :data:`SAVE_SIGNATURE` ("save" as a little-endian U32) to
``store_parameters.save_all`` (0x1010:1) stores the parameters; :data:`LOAD_SIGNATURE` ("load")
to ``restore_default_parameters.restore_all`` (0x1011:1) restores the defaults at the next reset
node (CiA 301 §7.5.2.13/14). Any other value is refused (the drive: SDO abort 0x08000020).

>>> SAVE_SIGNATURE.to_bytes(4, "little"), LOAD_SIGNATURE.to_bytes(4, "little")
(b'save', b'load')
"""

from __future__ import annotations

__all__ = ["LOAD_SIGNATURE", "SAVE_SIGNATURE"]

SAVE_SIGNATURE = int.from_bytes(b"save", "little")
"""0x65766173: written to 0x1010 sub-indices to store parameters."""
LOAD_SIGNATURE = int.from_bytes(b"load", "little")
"""0x64616F6C: written to 0x1011 sub-indices to restore default parameters."""
