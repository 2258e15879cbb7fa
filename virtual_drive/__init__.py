"""The device side: the virtual BLDC drive (C core + simulator + CANopen node) and its hub.

Rooms: ``virtual_drive/csrc`` (the portable C controllers, plant and sample loop, built into
``virtual_drive._core``), :mod:`virtual_drive.sim` (the simulator around the C core),
:mod:`virtual_drive.node` (the CANopen CiA 402 node), :mod:`virtual_drive.hub` (the loopback CAN
hub) and :mod:`virtual_drive.launch` (one way to start a hub with drives). See
``docs/architecture.md``.

    from virtual_drive import virtual_bench
    with virtual_bench(nodes=(1, 2)) as bus:      # python-can bus settings
        ...

The names below are imported on first use, so ``import virtual_drive.hub`` stays light.
"""

from __future__ import annotations

import importlib
from typing import Any

# (no import of them here, not even for the type checker: the simulator imports this package's
# C core, so the package must not depend on the node that depends on the simulator)
__all__ = ["BusSettings", "VirtualDrive", "virtual_bench"]

_HOMES = {
    "BusSettings": "virtual_drive.launch",
    "VirtualDrive": "virtual_drive.node",
    "virtual_bench": "virtual_drive.launch",
}


def __getattr__(name: str) -> Any:
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(home), name)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
