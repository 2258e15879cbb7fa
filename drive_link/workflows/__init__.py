"""Workflows: what a user does with a drive, built on :mod:`drive_link.link`.

:mod:`.gains` (the one path for a gain change), :mod:`.design` (pure numpy loop design),
:mod:`.steps` (step tests, on-drive identification; :mod:`._step_record`, :mod:`._speed_steps`),
:mod:`.identify`, :mod:`.metrics`, :mod:`.restore` (leave as found), :mod:`.report` (the
commissioning report), :mod:`.check` (the conformance run), :mod:`.config_dcf` (CiA 306 DCF
save/diff/load). Imports nothing from :mod:`drive_link.cli`.
"""

from __future__ import annotations

import importlib
from types import ModuleType

#: The public modules.
__all__ = [
    "check",
    "config_dcf",
    "design",
    "gains",
    "identify",
    "metrics",
    "report",
    "restore",
    "steps",
]


def __getattr__(name: str) -> ModuleType:
    """The public modules, imported on first use (``import drive_link.workflows`` stays light)."""
    if name not in __all__:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return importlib.import_module(f"{__name__}.{name}")
