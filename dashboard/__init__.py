"""Browser bench for the BLDC drive: FastAPI (REST, WebSocket, offline docs) and a viser GUI.

Start it with ``drive-dashboard --virtual`` (loopback hub + the virtual drive as a child
process) or ``drive-dashboard --interface socketcan --channel can0 --node 1`` (a real drive),
then open the one URL it prints. Everything goes through :mod:`drive_link`; no CAN details
live here.

Public (the package's ``__all__`` and the commands): :func:`create_app` (:mod:`dashboard.app`),
:class:`BenchConfig` (:mod:`dashboard.config`), :mod:`dashboard.cli` (``drive-dashboard``),
:mod:`dashboard.screenshot` (``python -m dashboard.screenshot docs/bench.png``) and
:mod:`dashboard.browser` (headless /usr/bin/chromium + a child ``drive-dashboard``, shared by the
e2e test, the screenshot command and the benchmarks). ``from dashboard import BenchConfig,
create_app`` imports them on first use, so ``import dashboard`` does not load FastAPI and viser.
The REST API (``/openapi.json``) is the interface for other programs.

Private modules (one job each; they may change without notice):
``_api`` / ``_stream`` (REST routes, the ``/api/stream`` WebSocket), ``_models`` (request bodies,
pydantic, limits from the EDS: bad input is a 422, nothing applied), ``_errors`` (errors → HTTP),
``_bench`` (one drive shared by all clients), ``_actions`` (long actions), ``_security`` (control
lease, Origin, token), ``_tuning`` (gains through :func:`drive_link.apply_gains`, IP design
eqs. 28–31) and ``_loop_view`` (Bode and pole curves from :mod:`drive_link.workflows.design`),
``_experiments`` (:mod:`drive_link.workflows.steps` run as a long action, turned into plots),
``_export`` (CSV, PNG), ``_fields`` (number fields with units), ``_live_plot``, ``_virtual`` (opens
the bench: real bus, running hub, or hub + virtual drive), ``_gui`` + ``_gui_panel`` +
``_gui_tabs/`` (one module per tab) + ``_gui_field``, ``_gui_scene`` (3D rotor), ``_gui_guard``,
``_gui_pace`` (updates only as fast as each page applies them), ``_gui_status``.
See ``docs/architecture.md``.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .app import create_app
    from .config import BenchConfig

__all__ = ["BenchConfig", "create_app"]

_HOMES = {"BenchConfig": "dashboard.config", "create_app": "dashboard.app"}


def __getattr__(name: str) -> Any:
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(home), name)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
