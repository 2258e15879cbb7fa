"""WebSocket /api/stream: live values for scripts and other pages (Origin and token checked)."""

from __future__ import annotations

import asyncio
import json

import numpy as np
from fastapi import APIRouter, WebSocket, WebSocketDisconnect
from starlette.concurrency import run_in_threadpool

from dashboard.bench import Bench, jsonable
from dashboard.security import origin_ok, token_ok

router = APIRouter()


@router.websocket("/api/stream")
async def stream(ws: WebSocket) -> None:
    """Every 1/stream_rate_hz s: ``{"type":"live", "t":[s], "<signal>":[...]}`` with the samples
    new since the last message; every second also ``{"type":"state", ...}``. Read-only."""
    app = ws.app
    if not origin_ok(ws.headers.get("origin"), app.state.origins):
        await ws.close(code=1008, reason="origin not allowed")
        return
    if not token_ok(app.state.config.token, ws.query_params.get("token")):
        await ws.close(code=1008, reason="access token required")
        return
    await ws.accept()
    bench: Bench = app.state.bench
    period = 1.0 / app.state.config.stream_rate_hz
    last_t = -np.inf
    tick = 0
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
                msg = {"type": "live"}
                msg.update({k: np.asarray(v)[new] for k, v in w.items()})
                await ws.send_text(json.dumps(jsonable(msg)))
            if tick % max(1, round(1.0 / period)) == 0:
                state = await run_in_threadpool(bench.state)
                await ws.send_text(json.dumps(jsonable({"type": "state", **state})))
            tick += 1
            await asyncio.sleep(period)
    except (WebSocketDisconnect, RuntimeError):
        return
