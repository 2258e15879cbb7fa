"""REST routes (/api/...): the GUI's functions for scripts. Drive calls run in the threadpool."""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Annotated, Any, TypeVar

from fastapi import APIRouter, Depends, Header, HTTPException, Query, Request, Response

from dashboard import _experiments as experiments
from dashboard import _tuning as tuning
from dashboard._bench import Bench, Capture
from dashboard._errors import http_error
from dashboard._export import capture_csv, capture_png
from dashboard._models import (
    CommandIn,
    ControlIn,
    ControlOut,
    CurrentIn,
    CurrentStepIn,
    GainsIn,
    IdentifyIn,
    IPDesignIn,
    LoadIn,
    ModeIn,
    SequenceIn,
    SpeedIn,
    SpeedStepIn,
    TraceIn,
)
from dashboard._nodes import Nodes
from dashboard._security import LeaseError
from drive_link import jsonable
from drive_link.errors import NodeNotFound

__all__ = ["router"]

T = TypeVar("T")


def _refuse_duplicates(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """json.loads object hook: a key given twice is refused (json keeps the last silently)."""
    out: dict[str, Any] = {}
    for k, v in pairs:
        if k in out:
            raise HTTPException(422, f"duplicate key {k!r} in the JSON body: give it once")
        out[k] = v
    return out


async def unique_keys(request: Request) -> None:
    """Refuse (422) a JSON body with a key given twice at any depth, before FastAPI parses it
    (with json, where the last one wins): ``{"rpm": 100, "rpm": 3000}`` is ambiguous."""
    if request.method not in ("POST", "PUT", "PATCH", "DELETE"):
        return
    raw = await request.body()  # cached: the route's body parsing reads the same bytes
    if not raw.strip():
        return
    try:
        json.loads(raw, object_pairs_hook=_refuse_duplicates)
    except ValueError:
        return  # not JSON at all: FastAPI's own 422 says so


router = APIRouter(prefix="/api", dependencies=[Depends(unique_keys)])


def get_bench(
    request: Request,
    node: Annotated[
        int | None,
        Query(ge=1, le=127, description="node-ID of the drive (default: the bench's --node)"),
    ] = None,
) -> Bench:
    """The bench of ``?node=N`` (opened on first use; 404 for a node not seen on the bus or
    that does not answer), else the bench's own node."""
    nodes: Nodes | None = getattr(request.app.state, "nodes", None)
    if nodes is None or node is None:
        bench: Bench = request.app.state.bench
        return bench
    try:
        return nodes.get(node)
    except NodeNotFound as exc:
        raise HTTPException(404, str(exc)) from exc
    except Exception as exc:
        raise http_error(exc) from exc


BenchDep = Annotated[Bench, Depends(get_bench)]


def require_control(
    bench: BenchDep,
    x_control_token: Annotated[
        str | None, Header(description="token from POST /api/control")
    ] = None,
) -> Bench:
    """Only the client in control may change the drive; the others watch (409)."""
    try:
        bench.lease.check(x_control_token)
    except LeaseError as exc:
        raise HTTPException(409, str(exc)) from exc
    return bench


ControlDep = Annotated[Bench, Depends(require_control)]


async def no_body(request: Request) -> None:
    """Body-less actions take no body: an empty one (no Content-Type needed) or ``{}``."""
    raw = (await request.body()).strip()
    if raw and raw != b"{}":
        raise HTTPException(422, "this action takes no request body")


NoBody = Depends(no_body)


def run(fn: Callable[[], T]) -> T:
    """Run a bench operation; map its failure onto an HTTP error."""
    try:
        return fn()
    except HTTPException:
        raise
    except Exception as exc:
        raise http_error(exc) from exc


# ------------------------------------------------------------------ nodes
@router.get("/nodes", tags=["nodes"], summary="The nodes seen on the bus (heartbeat, scan)")
def get_nodes(request: Request) -> list[dict[str, Any]]:
    """Every other route takes ``?node=N`` (default: the bench's own node); each node has its
    own state, captures and control lease."""
    return jsonable(_nodes(request).listing())


@router.post(
    "/nodes/scan",
    tags=["nodes"],
    summary="Probe every node-ID by SDO (0x1000), then list the nodes",
    dependencies=[NoBody],
)
def post_nodes_scan(request: Request) -> list[dict[str, Any]]:
    nodes = _nodes(request)
    return jsonable(run(lambda: nodes.scan()))


# ------------------------------------------------------------------ state and control
@router.get("/state", tags=["state"], summary="Connection and drive state")
def get_state(bench: BenchDep) -> dict[str, Any]:
    return jsonable(bench.state())


@router.get("/control", tags=["control"], summary="Who controls the bench")
def get_control(bench: BenchDep) -> ControlOut:
    h = bench.lease.holder
    return ControlOut(client=h.client if h else None, since=h.since if h else None)


@router.post(
    "/control", tags=["control"], summary="Take control (take_over=true steals it, visibly)"
)
def post_control(body: ControlIn, bench: BenchDep) -> ControlOut:
    h = run(lambda: bench.lease.acquire(body.client, take_over=body.take_over))
    return ControlOut(token=h.token, client=h.client, since=h.since)


@router.delete("/control", tags=["control"], summary="Give control back", dependencies=[NoBody])
def delete_control(
    bench: BenchDep, x_control_token: Annotated[str | None, Header()] = None
) -> ControlOut:
    run(lambda: bench.lease.release(x_control_token))
    return ControlOut(client=None)


@router.post(
    "/command",
    tags=["drive"],
    summary="enable / disable / quick_stop / fault_reset (quick_stop: any client, at once)",
)
def post_command(
    body: CommandIn,
    bench: BenchDep,
    x_control_token: Annotated[
        str | None, Header(description="token from POST /api/control (not for quick_stop)")
    ] = None,
) -> dict[str, Any]:
    if body.command == "quick_stop":  # a safety control: never lease-gated, never waits
        return {"state": run(bench.quick_stop)}
    require_control(bench, x_control_token)
    run(lambda: bench.command(body.command))
    return {"state": bench.drive.state}


@router.post(
    "/quick_stop",
    tags=["drive"],
    summary="Quick stop at once, from any client (no control lease needed): cancels the long "
    "action under way, which does not enable the drive again",
    dependencies=[NoBody],
)
def post_quick_stop(bench: BenchDep) -> dict[str, Any]:
    return {"state": run(bench.quick_stop)}


@router.put("/mode", tags=["drive"], summary="Operating mode: speed (IP loop) or current (i_p*)")
def put_mode(body: ModeIn, bench: ControlDep) -> dict[str, Any]:
    run(lambda: bench.set_mode(body.mode))
    return {"mode": bench.drive.mode}


@router.post(
    "/action/cancel",
    tags=["drive"],
    summary="Cancel the long action under way (identification, step test, capture); the "
    "drive is put back as the action found it",
    dependencies=[NoBody],
)
def post_cancel(bench: ControlDep) -> dict[str, Any]:
    return {"cancelled": bench.cancel_action()}


# ------------------------------------------------------------------ setpoints and steps
@router.put("/setpoints/speed", tags=["setpoints"], summary="Speed setpoint, rpm")
def put_speed(body: SpeedIn, bench: ControlDep) -> dict[str, float]:
    run(lambda: bench.set_speed(body.rpm))
    return {"rpm": bench.speed_setpoint}


@router.put("/setpoints/current", tags=["setpoints"], summary="Pseudo-current setpoint i_p*, A")
def put_current(body: CurrentIn, bench: ControlDep) -> dict[str, float]:
    run(lambda: bench.set_current(body.i_p_ref))
    return {"i_p_ref": bench.current_setpoint}


@router.post("/steps/speed", tags=["steps"], summary="Speed step: setpoint += delta_rpm")
def post_speed_step(body: SpeedStepIn, bench: ControlDep) -> dict[str, float]:
    rpm = run(lambda: bench.step_speed(body.delta_rpm))
    return {"rpm": rpm}


@router.post("/steps/sequence", tags=["steps"], summary="Scripted speed setpoint sequence")
def post_sequence(body: SequenceIn, bench: ControlDep) -> dict[str, Any]:
    steps = [(s.at_s, s.rpm) for s in body.steps]
    run(lambda: bench.start_sequence(steps))
    return {"started": True, "steps": len(steps)}


@router.delete(
    "/steps/sequence", tags=["steps"], summary="Stop a running sequence", dependencies=[NoBody]
)
def delete_sequence(bench: ControlDep) -> dict[str, Any]:
    bench.stop_sequence()
    return {"stopped": True}


@router.post("/steps/load", tags=["steps"], summary="Load torque step (virtual drive), N·m")
def post_load(body: LoadIn, bench: ControlDep) -> dict[str, float]:
    run(lambda: bench.set_load(body.T_load))
    return {"T_load": bench.T_load}


@router.post("/steps/current", tags=["steps"], summary="Current step test with metrics and model")
def post_current_step(body: CurrentStepIn, bench: ControlDep) -> dict[str, Any]:
    return jsonable(run(lambda: experiments.current_step(bench, body)))


# ------------------------------------------------------------------ gains
@router.get("/gains", tags=["gains"], summary="Live gains read back from the drive")
def get_gains(bench: BenchDep) -> dict[str, Any]:
    return jsonable(run(lambda: tuning.read_gains(bench)))


@router.put("/gains", tags=["gains"], summary="Apply a gain set atomically; returns the read-back")
def put_gains(body: GainsIn, bench: ControlDep) -> dict[str, Any]:
    return jsonable(run(lambda: tuning.apply(bench, body.changes(), force=body.force)))


@router.post("/gains/preview", tags=["gains"], summary="Stability, margins and ‖S‖∞ of a gain set")
def post_gains_preview(body: GainsIn, bench: BenchDep) -> dict[str, Any]:
    return jsonable(run(lambda: tuning.preview(bench, body.changes())))


@router.post(
    "/gains/response",
    tags=["gains"],
    summary="Bode data and z-plane poles of both loops for a gain set (Figs. 4, 5, 12)",
)
def post_gains_response(body: GainsIn, bench: BenchDep) -> dict[str, Any]:
    return jsonable(run(lambda: tuning.response(bench, body.changes())))


@router.post("/gains/ip_design", tags=["gains"], summary="IP gains from ξ, ω_n, a, b (eqs. 28–31)")
def post_ip_design(body: IPDesignIn, bench: BenchDep) -> dict[str, Any]:
    return jsonable(run(lambda: tuning.design_ip(bench, body.xi, body.omega_n, body.a, body.b)))


@router.post(
    "/gains/store",
    tags=["gains"],
    summary="Store the live gains in the drive (0x1010)",
    dependencies=[NoBody],
)
def post_store(bench: ControlDep) -> dict[str, Any]:
    run(lambda: tuning.store(bench))
    return {"stored": True}


@router.get("/gains/diff", tags=["gains"], summary="Live vs stored gains")
def get_gains_diff(bench: BenchDep) -> dict[str, Any]:
    return jsonable(run(lambda: tuning.stored_diff(bench, fresh=True)))


# ------------------------------------------------------------------ traces and identification
@router.get("/trace/config", tags=["trace"], summary="The trace configuration used by default")
def get_trace_config(bench: BenchDep) -> TraceIn:
    return bench.trace_config


@router.put("/trace/config", tags=["trace"], summary="Set the default trace configuration")
def put_trace_config(body: TraceIn, bench: ControlDep) -> TraceIn:
    bench.trace_config = run(lambda: body.checked(bench.drive.trace.resolve))
    return bench.trace_config


@router.post(
    "/trace/capture",
    tags=["trace"],
    summary="Arm, trigger and upload one trace (50 kHz); body overrides the stored config",
)
def post_capture(bench: ControlDep, body: TraceIn | None = None) -> dict[str, Any]:
    cfg = run(lambda: (body or bench.trace_config).checked(bench.drive.trace.resolve))
    cap = run(lambda: experiments.capture(bench, cfg))
    return jsonable(cap.summary())


@router.get("/trace", tags=["trace"], summary="Captures kept for download")
def list_captures(bench: BenchDep) -> list[dict[str, Any]]:
    return [jsonable(c.summary()) for c in bench.captures.values()]


@router.get("/trace/{cap_id}", tags=["trace"], summary="One capture's columns as JSON")
def get_capture(cap_id: int, bench: BenchDep) -> dict[str, Any]:
    cap = _capture(bench, cap_id)
    return jsonable({**cap.summary(), "data": cap.columns})


@router.get("/trace/{cap_id}/csv", tags=["trace"], summary="Download a capture as CSV")
def get_capture_csv(cap_id: int, bench: BenchDep) -> Response:
    cap = _capture(bench, cap_id)
    return Response(
        capture_csv(cap),
        media_type="text/csv",
        headers={"Content-Disposition": f'attachment; filename="capture_{cap.id}.csv"'},
    )


@router.get("/trace/{cap_id}/png", tags=["trace"], summary="Download a capture as PNG")
def get_capture_png(cap_id: int, bench: BenchDep) -> Response:
    cap = _capture(bench, cap_id)
    return Response(
        capture_png(cap),
        media_type="image/png",
        headers={"Content-Disposition": f'attachment; filename="capture_{cap.id}.png"'},
    )


@router.post(
    "/identify", tags=["identify"], summary="Current step → fit G(z) = b/(z − a) (Fig. 16)"
)
def post_identify(body: IdentifyIn, bench: ControlDep) -> dict[str, Any]:
    return jsonable(run(lambda: experiments.identify(bench, body)))


def _nodes(request: Request) -> Nodes:
    """The app's nodes (``app.state`` is untyped; the lifespan in app.py sets them)."""
    nodes: Nodes = request.app.state.nodes
    return nodes


def _capture(bench: Bench, cap_id: int) -> Capture:
    cap = bench.captures.get(cap_id)
    if cap is None:
        raise HTTPException(404, f"no capture {cap_id}")
    return cap
