"""Browser bench for the BLDC drive: FastAPI (REST, WebSocket, offline docs) and a viser GUI.

Start it with ``drive-dashboard --virtual`` (loopback hub + the virtual drive as a child
process) or ``drive-dashboard --interface socketcan --channel can0 --node 1`` (a real drive),
then open the one URL it prints. Everything goes through :mod:`drive_link`; no CAN details
live here.

Modules (one job each):

- :mod:`dashboard.cli` — the ``drive-dashboard`` command (argument checks, uvicorn).
- :mod:`dashboard.app` — FastAPI app, lifespan (bench + GUI), access/JSON/Origin middleware,
  the self-made ``/docs`` page (renders ``/openapi.json``, no CDN).
- :mod:`dashboard._api` / :mod:`dashboard._stream` — REST routes and the ``/api/stream`` WebSocket.
- :mod:`dashboard._models` — request bodies (pydantic; bad input is a 422, nothing applied).
- :mod:`dashboard._bench` — one drive shared by all clients: commands, setpoints, sequences.
- :mod:`dashboard._security` — control lease (one controller, visible take-over), Origin, token.
- :mod:`dashboard._tuning` — gains read-back, preview and apply through
  :func:`drive_link.gains.apply_gains`, IP design from ξ, ω_n (eqs. 28–31), store, live-vs-stored
  diff; :mod:`dashboard._loop_view` — Bode and pole curves from :mod:`drive_link.design`.
- :mod:`dashboard._experiments` — trace capture, current step test (Fig. 13) and identification
  (Fig. 16): drive_link's (:mod:`drive_link.steps`) run as a long action, turned into plots.
- :mod:`dashboard._export` — captures as CSV and PNG.
- :mod:`dashboard._gui` / :mod:`dashboard._gui_tabs` (one module per tab) /
  :mod:`dashboard._gui_scene` — the viser GUI and the 3D rotor.
- :mod:`dashboard._virtual` — opens the bench (real bus, running hub, or hub + virtual drive).
- :mod:`dashboard.browser` — headless /usr/bin/chromium and a child ``drive-dashboard`` (shared
  by the e2e test, the screenshot command and the benchmark).
- :mod:`dashboard.screenshot` — ``python -m dashboard.screenshot docs/bench.png`` (README picture).

Scripting: ``from dashboard import BenchConfig, create_app`` (imported on first use, so
``import dashboard._fields`` does not load FastAPI and viser). See ``docs/architecture.md``.
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
