"""``drive-link`` commands of the drive's state and setpoints: ``scan``, ``status``,
``enable``, ``disable``, ``quick-stop``, ``fault-reset``, ``mode``, ``set-speed``,
``set-current``."""

from __future__ import annotations

import argparse
from collections.abc import Callable

from ..errors import InvalidValue, NodeNotFound, StateError
from ..link import _connection
from ..link.cia402 import OPERATION_ENABLED, STATE_TIMEOUT_S
from ..link.drive import Drive
from ._common import AddCommand, _emit, _object_value, _timeout, _usable_state
from .connect import bus_settings_from_args

__all__ = ["add_parsers"]


def cmd_scan(args: argparse.Namespace) -> int:
    from ..link._scan import scan

    conn = _connection.acquire(**bus_settings_from_args(args))  # --fd, --bus-kwargs ... too
    listen = _timeout(args, 1.0)
    try:
        nodes = scan(conn.bus, timeout=listen)
    finally:
        _connection.release(conn)
    if not nodes:  # exit 4 "no node", as for a command whose node does not answer
        raise NodeNotFound(
            f"no node answered on the bus (SDO probe of 1..127, heartbeats for {listen:g} s)"
        )
    data = [
        {
            "node_id": n.node_id,
            "device_type": n.device_type,
            "nmt_state": n.nmt_state,
            "abort_code": n.abort_code,
        }
        for n in nodes
    ]

    def text() -> str:
        lines = []
        for n in nodes:
            dt = (
                f"device_type 0x{n.device_type:08X} ({n.profile})"
                if n.device_type is not None
                else "no SDO answer"
            )
            lines.append(f"node {n.node_id:3d}: {dt}, {n.nmt_state or 'no heartbeat seen'}")
        return "\n".join(lines)

    _emit(args, data, text)
    return 0


#: What a store_status value means for the user (0x2060).
_STORE_STATUS_TEXT = {
    "ok": "stored parameters loaded",
    "defaults": "no stored parameters: defaults in use",
    "damaged": "STORED PARAMETERS DAMAGED: defaults in use (EMCY 0x6310), store again",
    "unreadable": "STORED PARAMETERS UNREADABLE: defaults in use (EMCY 0x6310), store again",
    "unknown": "not reported by this firmware (no 0x2060)",
}


def _status_text(st: dict) -> str:
    lines = []
    for k, v in st.items():
        if k == "store_status":
            v = f"{v} ({_STORE_STATUS_TEXT.get(str(v), 'unexpected value')})"
        elif k == "supervision_rearmed_at" and v is None:
            v = "never (no restart seen)"
        elif k == "error_code" and isinstance(v, int):
            from ..link._emcy import describe

            v = f"0x{v:04X} ({describe(v)})" if v else "0x0000"
        elif k in ("statusword", "error_register") and isinstance(v, int):
            v = f"0x{v:04X}" if k == "statusword" else f"0x{v:02X}"
        lines.append(f"{k:>22}: {v}")
    return "\n".join(lines)


def cmd_status(args: argparse.Namespace, d: Drive) -> int:
    st = d.status()
    st["gains"] = d.read_gains().to_dict()
    _emit(args, st, lambda: _status_text(st))
    return 0


def _state_cmd(fn_name: str) -> Callable[[argparse.Namespace, Drive], int]:
    def run(args: argparse.Namespace, d: Drive) -> int:
        state = getattr(d, fn_name)(timeout=_timeout(args, STATE_TIMEOUT_S))
        _emit(args, {"state": state}, state)
        return 0

    return run


def _switch_mode(args: argparse.Namespace, d: Drive, mode: str, allowed: bool, flag: str) -> bool:
    """Select ``mode``. The drive changes modes only with the power stage off (0x6060 answers
    0x08000022 in OPERATION ENABLED): if it is enabled in another mode, disable, switch and
    return True (the caller enables again) when ``allowed``; otherwise a one-line refusal
    naming the fix. Nothing is changed before that check."""
    state = _usable_state(d)
    now = d.mode
    if now == mode:
        return False
    if state == OPERATION_ENABLED:
        if not allowed:
            raise StateError(
                f"the drive is OPERATION ENABLED in {now} mode and changes mode only with the "
                f"power stage off: run `drive-link disable` first, or add {flag} "
                "(disable, switch, enable again)"
            )
        d.disable(timeout=_timeout(args, STATE_TIMEOUT_S))
        d.set_mode(mode)
        return True
    d.set_mode(mode)
    return False


def cmd_mode(args: argparse.Namespace, d: Drive) -> int:
    if _switch_mode(args, d, args.mode, args.re_enable, "--re-enable"):
        d.enable(timeout=_timeout(args, STATE_TIMEOUT_S))
    _emit(args, {"mode": d.mode, "state": d.state}, f"mode {d.mode} ({d.state})")
    return 0


def _set_setpoint(
    args: argparse.Namespace, d: Drive, mode: str, name: str, value: float | int, key: str
) -> int:
    """Write the setpoint ``name`` in ``mode``: the value is checked against the object's
    limits and the drive's state first (nothing is changed when refused); a drive that is not
    enabled is refused unless ``--enable`` (a zero setpoint is written: it is the stopped
    state); prints the read-back as ``key`` with the state."""
    obj = d.table[name]
    checked = obj.check(value)
    if not isinstance(checked, float | int):  # (both setpoints are numeric objects)
        raise InvalidValue(f"{name} is not a number ({obj.type_name})")
    value = checked
    state = _usable_state(d)
    if state != OPERATION_ENABLED and not args.enable and value != 0:
        raise StateError(
            f"nothing written: the drive is {state} and a setpoint moves nothing until it is "
            "enabled; add --enable (or run `drive-link enable` first)"
        )
    again = _switch_mode(args, d, mode, args.switch_mode, "--switch-mode")
    d.write(name, value)
    if args.enable or again:
        d.enable(timeout=_timeout(args, STATE_TIMEOUT_S))
    out = {key: d.read_number(name), "state": d.state}
    unit = obj.unit
    _emit(args, out, f"{key} {out[key]:g} {unit} ({out['state']})")
    return 0


def cmd_set_speed(args: argparse.Namespace, d: Drive) -> int:
    return _set_setpoint(args, d, "speed", "target_velocity", args.rpm, "target_velocity")


def cmd_set_current(args: argparse.Namespace, d: Drive) -> int:
    return _set_setpoint(args, d, "current", "setpoints.i_p_ref", args.amps, "i_p_ref")


def add_parsers(add: AddCommand) -> None:
    """The state and setpoint commands, in ``drive-link --help``'s order."""
    add(
        "scan",
        cmd_scan,
        "list the nodes on the bus (SDO probe of 0x1000 on 1..127 + heartbeats)",
        False,
    )
    add("status", cmd_status, "NMT / CiA 402 state, mode, measurements, gains")
    add("enable", _state_cmd("enable"), "CiA 402: go to OPERATION ENABLED")
    add("disable", _state_cmd("disable"), "CiA 402: disable operation (power stage off)")
    add("quick-stop", _state_cmd("quick_stop"), "CiA 402: quick stop")
    add("fault-reset", _state_cmd("fault_reset"), "CiA 402: reset a fault")
    p = add(
        "mode",
        cmd_mode,
        "select speed / current / torque mode (the drive changes mode only while disabled)",
    )
    p.add_argument("mode", choices=["speed", "current", "torque"])
    p.add_argument(
        "--re-enable",
        action="store_true",
        help="if the drive is enabled in another mode: disable, switch, enable again",
    )
    p = add(
        "set-speed",
        cmd_set_speed,
        "speed mode and target_velocity (whole rpm; 1000rpm, '100 rad/s'); needs the drive "
        "enabled (--enable) unless the value is 0",
    )
    p.add_argument(
        "rpm", type=_object_value("target_velocity"), help="speed setpoint, rpm (or with a unit)"
    )
    p.add_argument("--enable", action="store_true", help="also enable the drive")
    p.add_argument(
        "--switch-mode",
        action="store_true",
        help="if the drive is enabled in another mode: disable, switch to speed, enable again",
    )
    p = add(
        "set-current",
        cmd_set_current,
        "current mode and i_p_ref (A; 50A, 500mA); needs the drive enabled (--enable) unless "
        "the value is 0",
    )
    p.add_argument(
        "amps", type=_object_value("setpoints.i_p_ref"), help="pseudo-current setpoint, A"
    )
    p.add_argument("--enable", action="store_true", help="also enable the drive")
    p.add_argument(
        "--switch-mode",
        action="store_true",
        help="if the drive is enabled in another mode: disable, switch to current, enable again",
    )
