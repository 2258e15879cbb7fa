"""WebSocket /api/stream: live values for scripts and other pages (Host, Origin and token checked).

With an access token configured, the client's first message must be
``{"type": "auth", "token": "<token>"}`` within AUTH_TIMEOUT_S (never in the URL, where it
would land in logs and history); nothing is sent before it.
"""

from __future__ import annotations

import asyncio
import json
import time
from typing import Any

import numpy as np
from fastapi import APIRouter, WebSocket, WebSocketDisconnect
from starlette.concurrency import run_in_threadpool

from dashboard._bench import Bench
from dashboard._security import allowed_hosts, host_ok, origin_ok, token_ok
from drive_link import jsonable

__all__ = ["AUTH_TIMEOUT_S", "router"]

router = APIRouter()

AUTH_TIMEOUT_S = 5.0  #: time for the first (auth) message when a token is configured


async def _authenticate(ws: WebSocket, token: str) -> bool:
    try:
        raw = await asyncio.wait_for(ws.receive_text(), AUTH_TIMEOUT_S)
        msg = json.loads(raw)
        given = msg.get("token") if isinstance(msg, dict) and msg.get("type") == "auth" else None
    except (TimeoutError, asyncio.TimeoutError, ValueError, KeyError, WebSocketDisconnect):
        given = None
    return token_ok(token, given if isinstance(given, str) else None)


@router.websocket("/api/stream")
async def stream(ws: WebSocket) -> None:
    """Every 1/stream_rate_hz s (on a fixed schedule): ``{"type":"live", "t":[s],
    "<signal>":[...]}`` with the samples new since the last message; every second also
    ``{"type":"state", ...}``. Read-only."""
    app = ws.app
    config = app.state.config
    if not host_ok(ws.headers.get("host"), allowed_hosts(config.host)):
        await ws.close(code=1008, reason="host not served here")
        return
    if not origin_ok(ws.headers.get("origin"), app.state.origins):
        await ws.close(code=1008, reason="origin not allowed")
        return
    await ws.accept()
    if config.token is not None and not await _authenticate(ws, config.token):
        await ws.close(code=1008, reason="access token required (first message)")
        return
    bench: Bench = app.state.bench
    node = ws.query_params.get("node")
    if node is not None:  # ?node=N: that drive's stream (opened on first use)
        try:
            bench = await run_in_threadpool(app.state.nodes.get, int(node))
        except Exception as exc:
            await ws.close(code=1008, reason=f"node {node}: {exc}"[:120])
            return
    period = 1.0 / config.stream_rate_hz
    per_state = max(1, round(1.0 / period))
    last_t = -np.inf
    tick = 0
    next_t = time.monotonic()
    try:
        while True:
            try:
                w = await run_in_threadpool(bench.live, 1.0)
            except Exception as exc:  # e.g. a drive whose TPDOs map other objects
                await ws.send_text(json.dumps({"type": "error", "detail": str(exc)}))
                w = {}
            t = np.asarray(w.get("t", []), dtype=np.float64)
            new = t > last_t
            if new.any():
                last_t = float(t[new][-1])
                msg: dict[str, Any] = {"type": "live"}
                msg.update({k: np.asarray(v)[new] for k, v in w.items()})
                await ws.send_text(json.dumps(jsonable(msg)))
            if tick % per_state == 0:
                state = await run_in_threadpool(bench.state)
                await ws.send_text(json.dumps(jsonable({"type": "state", **state})))
            tick += 1
            next_t += period
            now = time.monotonic()
            if now - next_t > 1.0:  # far behind (a stalled host): start a new schedule
                next_t = now
            await asyncio.sleep(max(0.0, next_t - now))
    except (WebSocketDisconnect, RuntimeError):
        return
