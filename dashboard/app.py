"""The FastAPI application: lifespan (bench + viser GUI), middleware, docs page, routes."""

from __future__ import annotations

import contextlib
import math
from collections.abc import AsyncIterator, Awaitable, Callable
from importlib import resources
from typing import Any

from fastapi import FastAPI, Request, Response
from fastapi.exceptions import RequestValidationError
from fastapi.responses import HTMLResponse, JSONResponse, RedirectResponse
from starlette.concurrency import run_in_threadpool

from dashboard import _api as api
from dashboard import _stream as stream
from dashboard._bench import Bench
from dashboard._nodes import Nodes
from dashboard._security import allowed_hosts, allowed_origins, bearer, host_ok, token_ok
from dashboard.config import BenchConfig
from drive_link import jsonable

__all__ = ["STATE_CHANGING", "BenchOpener", "create_app"]

BenchOpener = Callable[[BenchConfig], contextlib.AbstractContextManager[Bench]]

STATE_CHANGING = {"POST", "PUT", "PATCH", "DELETE"}


def create_app(
    config: BenchConfig,
    *,
    open_bench: BenchOpener | None = None,
    gui: bool = True,
    on_ready: Callable[[FastAPI], None] | None = None,
) -> FastAPI:
    """Build the app. The lifespan opens the bench (``open_bench``, default
    :func:`dashboard._virtual.open_bench`) and starts the viser GUI on ``config.gui_port``."""
    config.validate()
    if open_bench is None:
        from dashboard._virtual import open_bench as default_open

        open_bench = default_open

    @contextlib.asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        with contextlib.ExitStack() as stack:
            try:
                bench = await run_in_threadpool(lambda: stack.enter_context(open_bench(config)))
            except Exception as exc:
                app.state.startup_error = f"cannot open the bench: {exc}"
                raise
            stack.callback(bench.close)
            app.state.bench = bench
            app.state.nodes = Nodes(bench)  # the other nodes' benches, opened on first use
            stack.callback(app.state.nodes.close)
            app.state.gui = None
            if gui:
                from dashboard._gui import BenchGui

                g = BenchGui(bench, config, nodes=app.state.nodes)
                await run_in_threadpool(g.start)
                stack.callback(g.stop)
                app.state.gui = g
            ports = [config.api_port] + ([app.state.gui.port] if app.state.gui else [])
            app.state.origins = allowed_origins(config.host, ports, config.extra_origins)
            if app.state.gui is not None:
                app.state.gui.origins = app.state.origins
            if on_ready is not None:
                on_ready(app)
            yield

    app = FastAPI(
        title="drive-dashboard",
        version="0.1.0",
        description=(
            "Browser bench for the 14.8 µH BLDC drive (Valle et al. 2020): REST mirror of the GUI."
        ),
        lifespan=lifespan,
        docs_url=None,
        redoc_url=None,
    )
    app.state.config = config
    app.state.origins = allowed_origins(config.host, [config.api_port], config.extra_origins)

    hosts = allowed_hosts(config.host)

    @app.exception_handler(RequestValidationError)
    async def invalid_body(request: Request, exc: RequestValidationError) -> JSONResponse:
        """422 with JSON-safe details (a NaN or 1e400 in the body must not turn into a 500
        while the error itself is serialised)."""
        return JSONResponse({"detail": jsonable(_safe_errors(exc.errors()))}, status_code=422)

    @app.middleware("http")
    async def guard(
        request: Request, call_next: Callable[[Request], Awaitable[Response]]
    ) -> Response:
        path = request.url.path
        host = request.headers.get("host")
        if not host:
            return JSONResponse({"detail": "Host header required"}, status_code=400)
        if not host_ok(host, hosts):
            return JSONResponse({"detail": f"host {host!r} not served here"}, status_code=421)
        if config.token is not None:
            # the token only in the Authorization header: never in URLs (logs, history)
            if not token_ok(config.token, bearer(request.headers.get("authorization"))):
                return JSONResponse(
                    {"detail": "access token required (Authorization: Bearer <token>)"},
                    status_code=401,
                    headers={"WWW-Authenticate": "Bearer"},
                )
        if request.method in STATE_CHANGING and path.startswith("/api/"):
            origin = request.headers.get("origin")
            if origin is not None and origin.rstrip("/") not in app.state.origins:
                return JSONResponse({"detail": f"origin {origin} not allowed"}, status_code=403)
            if _has_body(request):
                ctype = request.headers.get("content-type", "").split(";")[0].strip().lower()
                if ctype != "application/json":
                    return JSONResponse(
                        {"detail": "a request body must be JSON (Content-Type: application/json)"},
                        status_code=415,
                    )
        return await call_next(request)

    @app.get("/", include_in_schema=False)
    def index(request: Request) -> Any:
        g = getattr(request.app.state, "gui", None)
        if g is None:
            return RedirectResponse("/docs")
        host = request.url.hostname or config.host
        return RedirectResponse(f"http://{host}:{g.port}/")

    @app.get("/docs", include_in_schema=False)
    def docs() -> HTMLResponse:
        page = resources.files("dashboard").joinpath("static/docs.html").read_text("utf-8")
        return HTMLResponse(page)

    app.include_router(api.router)
    app.include_router(stream.router)
    return app


def _has_body(request: Request) -> bool:
    """True when the request carries a body (Content-Length > 0 or chunked)."""
    if request.headers.get("transfer-encoding"):
        return True
    try:
        return int(request.headers.get("content-length", "0") or 0) > 0
    except ValueError:
        return True


def _safe_errors(errors: Any) -> Any:
    """pydantic's error list without unserialisable inputs (NaN, inf, bytes, exceptions)."""
    out = []
    for e in errors:
        e = dict(e)
        e.pop("ctx", None)
        if "input" in e:
            e["input"] = _plain(e["input"])
        out.append(e)
    return out


def _plain(x: Any) -> Any:
    if isinstance(x, float):
        return x if math.isfinite(x) else str(x)
    if isinstance(x, (str, int, bool)) or x is None:
        return x
    if isinstance(x, dict):
        return {str(k): _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    return repr(x)
