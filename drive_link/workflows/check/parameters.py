"""The object and parameter items: ``limits``, ``gain_set``, ``store_restore``,
``cob_id_validation``, ``config_only``, ``store_status`` (what the drive must refuse,
apply as a whole, store and restore)."""

from __future__ import annotations

import time
from functools import partial

from firmware_protocol import abort_codes
from firmware_protocol.entry import f32 as _f32  # the one float32 rounding
from firmware_protocol.enums import StoreStatus
from firmware_protocol.index_ranges import SIMULATION

from ...errors import DriveError, SdoAbort
from ...link.drive import Drive
from ..gains import apply_gains
from ._base import (
    ABORT_HIGH,
    ABORT_LENGTH,
    ABORT_LOW,
    ABORT_NO_OBJECT,
    ABORT_RANGE,
    ABORT_READ_ONLY,
    ABORT_STATE,
    DATA_SET_LOST,
    CheckFailed,
    NotApplicable,
    _expect,
    _expect_abort,
    _raw_write,
    _to_switch_on_disabled,
)
from ._snapshot import _persistent_snapshot, _put_back
from .motion import _spin

__all__ = [
    "ABORT_NO_STORE",
    "ABORT_REFUSED_VALUE",
    "CONFIG_ONLY",
    "NO_STORE",
    "item_cob_id_validation",
    "item_config_only",
    "item_gain_set",
    "item_limits",
    "item_store_restore",
    "item_store_status",
]


def item_limits(d: Drive, opts: dict) -> str:
    L = float(d.read("motor.L"))
    L_c0 = float(d.read("current_controller.L_c"))
    out = []
    cases = [
        ("current_controller.L_c", 2.5 * L, (ABORT_RANGE, ABORT_HIGH), "L_c = 2.5 L"),
        ("current_controller.L_c", 0.0, (ABORT_RANGE, ABORT_LOW), "L_c = 0"),
        ("current_controller.L_c", -L, (ABORT_RANGE, ABORT_LOW), "L_c < 0"),
        ("setpoints.i_p_ref", 500.0, (ABORT_RANGE, ABORT_HIGH), "i_p_ref = 500 A"),
    ]
    vmax = int(d.read("max_motor_speed"))
    cases.append(
        ("target_velocity", vmax + 100, (ABORT_RANGE, ABORT_HIGH), "target_velocity > max")
    )
    for name, value, codes, what in cases:
        code = _expect_abort(partial(_raw_write, d, name, value), codes, what)
        out.append(f"{what}: 0x{code:08X}")
    _expect(float(d.read("current_controller.L_c")) == L_c0, "L_c changed by a refused write")
    code = _expect_abort(
        lambda: _raw_write(d, "statusword", 0), (ABORT_READ_ONLY,), "write statusword"
    )
    out.append(f"ro: 0x{code:08X}")
    code = _expect_abort(lambda: d.sdo.upload(0x2FFF, 0), (ABORT_NO_OBJECT,), "read 0x2FFF")
    out.append(f"missing: 0x{code:08X}")
    cw = d.table["controlword"]
    code = _expect_abort(
        lambda: d.sdo.download(cw.index, cw.subindex, b"\x00\x00\x00\x00"),
        ABORT_LENGTH,
        "4 bytes to U16 controlword",
    )
    out.append(f"length: 0x{code:08X}")
    return "; ".join(out)


def item_gain_set(d: Drive, opts: dict) -> str:
    L = float(d.read("motor.L"))
    g0 = d.read_gains()
    for f in ("type", "L_c", "R_c", "k_p", "k_i", "T_BT", "T_DD", "T_SD", "V_G", "emf_feedforward"):
        obj = d.table[f"gain_set.{f}"]
        d.sdo.download(obj.index, obj.subindex, obj.encode(getattr(g0, f)), obj.name)
    staged_refused = False
    try:
        _raw_write(d, "gain_set.L_c", 2.5 * L)
    except SdoAbort:
        staged_refused = True
    if not staged_refused:
        _expect_abort(
            lambda: _raw_write(d, "gain_set_apply", 1),
            (ABORT_RANGE, ABORT_HIGH, ABORT_LOW, ABORT_STATE),
            "apply L_c = 2.5 L",
        )
    _expect(d.read_gains() == g0, "active gains changed by a refused gain set")
    try:
        back = apply_gains(d, {"L_c": 0.9 * L, "R_c": g0.R_c}).gains
        _expect(back["L_c"] == _f32(0.9 * L), f"L_c read back {back['L_c']}")
    finally:
        apply_gains(d, {"L_c": g0.L_c}, force=True)  # the set as found
    how = "at staging" if staged_refused else "at apply"
    return f"invalid set refused {how} with nothing changed; valid set applied and read back"


#: Why store_restore does not apply (the item's verdict "not applicable").
NO_STORE = (
    "not applicable: the drive has no parameter store (start `virtual-drive` with `--store FILE`)"
)


#: SDO aborts of a "save" command by a drive that cannot store (CiA 301 0x08000020/21).
ABORT_NO_STORE = (abort_codes.STORE, abort_codes.LOCAL_CONTROL)


def _has_store(d: Drive) -> None:
    """:class:`NotApplicable` when the drive says it has no parameter store: 0x1010:1 bit 0
    clear (CiA 301: does not save on command), or a "save" of the present values refused with
    abort 0x08000020/0x08000021 while no stored set exists (0x2060 not "ok"). A drive that has
    stored parameters and refuses to save fails the item; any other abort fails it too."""
    if not int(d.read("store_parameters.save_all")) & 1:
        raise NotApplicable(f"{NO_STORE}; 0x1010:1 bit 0 = 0 (does not save on command)")
    try:
        d.store()  # the present values: what the item stores again at its end
    except SdoAbort as exc:
        status = d.store_status()
        if exc.code in ABORT_NO_STORE and status != "ok":
            raise NotApplicable(
                f"{NO_STORE}; save refused with 0x{exc.code:08X}, store_status {status}"
            ) from None
        raise


def item_store_restore(d: Drive, opts: dict) -> str:
    """0x1010 save survives reset node; 0x1011 restore applies defaults after reset node.
    The drive is then put back as found (every stored object rewritten as it was, stored
    again), so a tuned drive keeps its gains and PDO settings. Not applicable (a verdict of
    its own, see :func:`_has_store`) on a drive without a parameter store."""
    name = "current_controller.R_c"
    orig = float(d.read(name))
    default = float(d.table[name].default or 0)
    v2 = _f32(orig * 0.9 + 1e-4)
    v3 = _f32(orig * 0.8 + 2e-4)
    _to_switch_on_disabled(d)
    _has_store(d)  # before anything is changed
    snapshot = _persistent_snapshot(d)
    failed: list[str] = []
    try:
        apply_gains(d, {"R_c": v2})  # a gain: the one gain path (Drive.write refuses it)
        d.store()
        apply_gains(d, {"R_c": v3})
        d.reset(timeout=8.0)
        got = float(d.read(name))
        _expect(got == v2, f"after store + reset node R_c = {got}, expected stored {v2}")
        d.restore_defaults(reset=True, timeout=8.0)
        got = float(d.read(name))
        _expect(
            got == _f32(default),
            f"after restore + reset node R_c = {got}, expected default {default}",
        )
    finally:
        failed = _put_back(d, snapshot)
        d.store()
        d.nmt("start")
    _expect(not failed, "drive not put back as found: " + "; ".join(failed[:3]))
    return (
        "stored value survives reset node; restore defaults applies after reset node; "
        f"{len(snapshot)} stored objects put back and stored"
    )


ABORT_REFUSED_VALUE = abort_codes.VALUE_REFUSED


def item_cob_id_validation(d: Drive, opts: dict) -> str:
    """CiA 301 §7.3.5 / §7.5.2: restricted CAN-IDs (0x000, 0x001–0x07F, 0x101–0x180,
    0x581–0x5FF, 0x601–0x67F, 0x6E0–0x6FF, 0x701–0x7FF), 29-bit IDs on an 11-bit device and
    reserved bits are refused by an SDO abort with nothing changed; 0x1016 refuses node-IDs
    outside 1..127 and accepts a valid entry."""
    n = d.node_id
    emcy0 = int(d.read("cob_id_emcy"))
    cases: list[tuple[str, int, str]] = [
        ("cob_id_emcy", 0x000, "EMCY on the NMT identifier"),
        ("cob_id_emcy", 0x601, "EMCY on a default SDO identifier"),
        ("cob_id_emcy", 0x700 + n, "EMCY on a heartbeat identifier"),
        ("cob_id_emcy", 0x20000080 + n, "29-bit EMCY identifier"),
        ("cob_id_emcy", 0xFFFFFFFF, "all bits set"),
    ]
    tpdo = "tpdo4_communication.cob_id"
    has_tpdo = tpdo in d.table
    out = []
    cob0 = int(d.read(tpdo)) if has_tpdo else 0
    consumer0 = int(d.read("consumer_heartbeat_time.consumer_1"))
    t0 = time.monotonic()
    d.nmt("pre-operational")  # CiA 301: PDOs are reconfigured in PRE-OPERATIONAL
    d.heartbeat.wait_for(("PRE-OPERATIONAL",), 2.0, after=t0)
    try:
        _raw_write(d, "cob_id_emcy", emcy0 | 0x80000000)  # EMCY invalid: its ID may now change
        for name, value, what in cases:
            code = _expect_abort(partial(_raw_write, d, name, value), _cob_aborts(), what)
            out.append(f"{what}: 0x{code:08X}")
        _expect(
            int(d.read("cob_id_emcy")) == emcy0 | 0x80000000,
            "EMCY COB-ID changed by a refused write",
        )
        if has_tpdo:
            _raw_write(d, tpdo, cob0 | 0x80000000)  # PDO invalid: its ID may now change
            for value, what in (
                (0x585, "TPDO on an SDO response identifier"),
                (0x77F, "TPDO on a heartbeat identifier"),
            ):
                code = _expect_abort(partial(_raw_write, d, tpdo, value), _cob_aborts(), what)
                out.append(f"{what}: 0x{code:08X}")
        for value, what in (
            ((0x00 << 16) | 500, "0x1016 node-ID 0"),
            ((0x80 << 16) | 500, "0x1016 node-ID 128"),
            ((0xFF << 16) | 500, "0x1016 node-ID 255"),
        ):
            code = _expect_abort(
                partial(_raw_write, d, "consumer_heartbeat_time.consumer_1", value),
                _cob_aborts(),
                what,
            )
            out.append(f"{what}: 0x{code:08X}")
        _expect(
            int(d.read("consumer_heartbeat_time.consumer_1")) == consumer0,
            "0x1016 changed by a refused write",
        )
        good = (0x7E << 16) | 1000
        d.write("consumer_heartbeat_time.consumer_1", good)
        _expect(
            int(d.read("consumer_heartbeat_time.consumer_1")) == good,
            "valid 0x1016 entry (node 0x7E, 1000 ms) not stored",
        )
    finally:
        d.write("consumer_heartbeat_time.consumer_1", consumer0)
        if int(d.read("cob_id_emcy")) != emcy0:
            try:
                _raw_write(d, "cob_id_emcy", emcy0 | 0x80000000)
            finally:
                _raw_write(d, "cob_id_emcy", emcy0)
        if has_tpdo:
            try:
                _raw_write(d, tpdo, cob0 | 0x80000000)
            finally:
                _raw_write(d, tpdo, cob0)
        d.nmt("start")
    return "; ".join(out) + "; valid 0x1016 entry accepted"


def _cob_aborts() -> tuple[int, ...]:
    return ABORT_REFUSED_VALUE


#: Motor parameters (0x2000): configuration, changeable only while the power stage is off.
CONFIG_ONLY = (
    "motor.R",
    "motor.L",
    "motor.K_rpm",
    "motor.pole_pairs",
    "motor.rated_current",
    "motor.V_dc_nominal",
)


def _config_only_names(d: Drive) -> list[str]:
    """Objects the EDS marks ``ConfigOnly=1`` (simulation objects 0x5000–0x5FFF left out: the
    DSP has none), else the motor parameters."""
    marked = [
        o.name
        for o in d.table
        if getattr(o.entry, "config_only", False)
        and o.index not in SIMULATION
        and o.writable
        and o.fmt
    ]
    return marked or [n for n in CONFIG_ONLY if n in d.table]


def item_config_only(d: Drive, opts: dict) -> str:
    """CiA 402 device state rule (abort 0x08000022): configuration objects (EDS ConfigOnly=1:
    motor parameters, protection thresholds, rated current/torque) are refused while OPERATION
    ENABLED with nothing changed, and accepted again once the power stage is off."""
    names = _config_only_names(d)
    _expect(bool(names), "no configuration-only objects in the object dictionary")
    orig = {n: d.read_number(n) for n in names}  # (numeric: each has a struct format)
    changed: dict[str, float | int] = {}
    for n in names:
        info = d.table[n]
        v = orig[n]
        if isinstance(v, float):
            w = _f32(v * 1.01 if info.high is None or v * 1.01 <= info.high else v * 0.99)
        else:
            w = v + 1 if info.high is None or v + 1 <= info.high else v - 1
        changed[n] = w
    try:
        _spin(d)
        for n in names:
            _expect_abort(
                partial(_raw_write, d, n, changed[n]),
                (ABORT_STATE,),
                f"{n} while OPERATION ENABLED",
            )
            _expect(d.read(n) == orig[n], f"{n} changed by a refused write")
        _to_switch_on_disabled(d)
        for n in names:
            _raw_write(d, n, changed[n])
            got = d.read(n)
            _expect(got == changed[n], f"{n} = {changed[n]!r} refused or changed at rest ({got!r})")
            _raw_write(d, n, orig[n])
    finally:
        _to_switch_on_disabled(d)
        for n in names:
            try:
                if d.read(n) != orig[n]:
                    _raw_write(d, n, orig[n])
            except DriveError:
                pass
    return (
        f"{len(names)} configuration objects refused (0x08000022) while enabled, accepted at "
        f"rest: {', '.join(names)}"
    )


def item_store_status(d: Drive, opts: dict) -> str:
    """0x2060 store_status (U8 ro: 0 ok, 1 defaults, 2 damaged, 3 unreadable); on 2/3 the drive
    has sent EMCY 0x6310 and keeps error register bit 0 and the entry in 0x1003."""
    obj = d.table["store_status"]
    where = f"0x{obj.index:04X} store_status"
    try:
        raw = d.sdo.upload(obj.index, obj.subindex, obj.name)
    except SdoAbort as exc:
        raise CheckFailed(f"{where} not readable: abort 0x{exc.code:08X} ({exc.meaning})") from None
    _expect(len(raw) == 1, f"{where} is {len(raw)} bytes, expected 1 (U8)")
    value = raw[0]
    _expect(value in set(StoreStatus), f"{where} = {value}, expected 0..3")
    name = StoreStatus(value).name.lower()
    if value in (StoreStatus.DAMAGED, StoreStatus.UNREADABLE):
        reg = int(d.read("error_register"))
        _expect(bool(reg & 0x01), f"store {name} but error register 0x{reg:02X} lacks bit 0")
        codes = [e.code for e in d.error_history()]
        _expect(
            DATA_SET_LOST in codes,
            f"store {name} but no 0x{DATA_SET_LOST:04X} in 0x1003 ({codes})",
        )
    return f"store_status = {value} ({name})"
