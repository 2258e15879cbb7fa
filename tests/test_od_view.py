"""The Python view of the OD: lookups, OD references, value checks with CiA 301 abort codes, the
L_c constraint against the paper's stability result (python-control as the oracle), enums."""

from __future__ import annotations

import configparser
import math
import struct

import canopen
import control
import numpy as np
import pytest

from firmware_protocol import EDS_PATH, LimitError, load_od
from firmware_protocol.enums import ENUM_OBJECTS, ControllerType, ModeOfOperation, TraceState

pytestmark = [pytest.mark.timeout(60), pytest.mark.unit]

TOO_HIGH, TOO_LOW, INVALID = 0x06090031, 0x06090032, 0x06090030
TS = 20e-6  # s, fs = 50 kHz


@pytest.fixture(scope="module")
def view():
    return load_od()


def _abort(entry, value) -> int:
    with pytest.raises(LimitError) as info:
        entry.check(value)
    assert entry.name in str(info.value)
    return info.value.abort_code


# ---- lookups --------------------------------------------------------------------------------


def test_entry_lookup_and_fields(view) -> None:
    e = view.entry("current_controller.L_c")
    assert (e.index, e.subindex, e.type_name, e.access, e.unit) == (0x2010, 2, "REAL32", "rw", "H")
    assert e.default == pytest.approx(14.8e-6) and e.persistent and not e.pdo_mappable
    assert "L_c" in e.description
    assert view.by_index(0x2010, 2) is e
    assert view.entry("controlword") is view.by_index(0x6040)
    assert "controlword" in view and "nonsense" not in view
    names = [x.name for x in view.entries]
    assert len(names) == len(set(names)) == len(view)
    assert [(x.index, x.subindex) for x in view.entries] == sorted(
        (x.index, x.subindex) for x in view.entries
    )


def test_unknown_name_lists_close_names(view) -> None:
    with pytest.raises(KeyError) as info:
        view.entry("current_controler.Lc")
    assert "current_controller.L_c" in str(info.value)
    with pytest.raises(KeyError):
        view.by_index(0x2010, 0x30)
    with pytest.raises(KeyError):
        view.by_index(0x3000)


def test_od_reference_round_trip(view) -> None:
    assert view.od_reference("measurements.i_p") == 0x20400120  # contracts: trigger_source default
    assert view.od_reference("statusword") == 0x60410010
    assert view.od_reference("modes_of_operation") == 0x60600008
    for e in view.entries:
        if e.pdo_mappable:
            ref = view.od_reference(e.name)
            assert view.by_reference(ref) is e
    with pytest.raises(ValueError):
        view.by_reference(0x20400110)  # i_p is 32 bits, not 16
    with pytest.raises(ValueError):
        view.od_reference("trace_data")  # DOMAIN has no fixed length
    with pytest.raises(KeyError):
        view.by_reference(0x30000020)


def test_eds_limits_read_independently(view) -> None:
    """Every LowLimit/HighLimit/Unit in the EDS text is in the view (canopen drops REAL32 ones)."""
    cp = configparser.RawConfigParser(inline_comment_prefixes=(";",))
    cp.optionxform = str  # type: ignore[assignment,method-assign]
    cp.read(EDS_PATH)
    seen = 0
    for e in view.entries:
        sec = cp[f"{e.index:04X}" if e.name == e.object_name else f"{e.index:04X}sub{e.subindex:X}"]
        assert sec["ParameterName"] == (e.sub_name or e.name)
        for key, value in (("LowLimit", e.low), ("HighLimit", e.high)):
            if key in sec:
                assert value == pytest.approx(
                    float(int(sec[key], 0)) if "x" in sec[key] else float(sec[key])
                ), (e.name, key)
                seen += 1
            else:
                assert value is None
        assert e.unit == sec.get("Unit")
    assert seen > 150


# ---- value checks ---------------------------------------------------------------------------


def test_real32_abort_codes(view) -> None:
    e = view.entry("motor.L")  # [1e-6, 1e-3] H
    assert _abort(e, 2e-3) == TOO_HIGH
    assert _abort(e, 1e-7) == TOO_LOW
    assert _abort(e, -1.0) == TOO_LOW
    assert _abort(e, math.nan) == INVALID
    assert _abort(e, math.inf) == INVALID
    assert _abort(e, -math.inf) == INVALID
    assert _abort(e, 1e39) == TOO_HIGH  # not representable as REAL32
    assert _abort(e, 10**400) == TOO_HIGH and _abort(e, -(10**400)) == TOO_LOW
    assert _abort(e, "1e-5") == INVALID
    assert _abort(e, None) == INVALID
    assert e.check(20e-6) == pytest.approx(20e-6)
    assert e.check(np.float32(20e-6)) == pytest.approx(20e-6)


def test_real32_limits_compare_in_float32(view) -> None:
    """A limit value read back from the drive as float32 must be accepted again."""
    e = view.entry("motor.R")  # LowLimit 1e-4 is not exact in float32
    low32 = struct.unpack("<f", struct.pack("<f", 1e-4))[0]
    assert low32 < 1e-4
    assert e.check(low32) == low32
    below = struct.unpack(
        "<f", struct.pack("<I", struct.unpack("<I", struct.pack("<f", 1e-4))[0] - 1)
    )[0]
    assert _abort(e, below) == TOO_LOW
    # the returned value is what a REAL32 stores
    assert e.check(0.1) == struct.unpack("<f", struct.pack("<f", 0.1))[0]


def test_integer_abort_codes(view) -> None:
    e = view.entry("trace_config.divider")  # U16 [1, 5000]
    assert e.check(5000) == 5000 and e.check(1.0) == 1
    assert _abort(e, 5001) == TOO_HIGH
    assert _abort(e, 0) == TOO_LOW
    assert _abort(e, 2.5) == INVALID
    assert _abort(e, math.nan) == INVALID
    assert _abort(e, True) == INVALID
    # no explicit limit: the data type's range applies
    cw = view.entry("controlword")  # U16
    assert cw.check(0xFFFF) == 0xFFFF
    assert _abort(cw, 0x10000) == TOO_HIGH
    assert _abort(cw, -1) == TOO_LOW
    tv = view.entry("target_velocity")  # I32 rpm
    assert tv.check(-6000) == -6000
    assert _abort(tv, 6001) == TOO_HIGH and _abort(tv, -6001) == TOO_LOW


def test_enumeration_abort_codes(view) -> None:
    mode = view.entry("modes_of_operation")
    for m in ModeOfOperation:
        assert mode.check(m) == m
    assert _abort(mode, 0) == INVALID  # inside [-1, 4] but not a supported mode
    assert _abort(mode, 1) == INVALID
    assert _abort(mode, 5) == TOO_HIGH
    ctype = view.entry("current_controller.type")
    assert ctype.check(ControllerType.PREDICTIVE) == 2
    assert _abort(ctype, 3) == TOO_HIGH
    apply = view.entry("gain_set_apply")
    assert _abort(apply, 0) == INVALID and apply.check(3) == 3  # 0 = nothing to apply
    assert _abort(apply, 4) == TOO_HIGH


def test_strings_and_domains(view) -> None:
    assert _abort(view.entry("manufacturer_device_name"), 5) == INVALID
    assert view.entry("trace_data").check(b"\x00" * 8) == b"\x00" * 8
    assert _abort(view.entry("trace_data"), "abc") == INVALID


# ---- cross-object constraints ---------------------------------------------------------------


def _deadbeat_closed_loop_stable(L: float, R: float, L_c: float, R_c: float) -> bool:
    """Paper eq. (15) deadbeat k=2 on P(z) = Gamma / (z (z - Phi)), by python-control."""
    phi, phi_c = math.exp(-R * TS / L), math.exp(-R_c * TS / L_c)
    gamma, gamma_c = (1 - phi) / (2 * R), (1 - phi_c) / (2 * R_c)
    plant = control.tf([gamma], [1, -phi, 0], TS)
    ctrl = control.tf([1, -phi_c, 0], [gamma_c, 0, -gamma_c], TS)
    closed = control.feedback(ctrl * plant, 1)
    return bool(np.all(np.abs(control.poles(closed)) < 1 - 1e-9))


@pytest.mark.parametrize("L", [14.8e-6, 1e-6, 1e-3])
def test_L_c_constraint_matches_deadbeat_stability(view, L: float) -> None:
    """Valle et al.: the deadbeat loop is stable for 0 < L_c < 2 L; the OD rule says the same."""
    R = 0.0062
    for ratio in (0.05, 0.3, 0.7, 1.0, 1.5, 1.9, 1.97, 2.03, 2.2, 3.0, 5.0):
        L_c = ratio * L
        stable = _deadbeat_closed_loop_stable(L, R, L_c, R)
        values = {"motor.L": L, "current_controller.L_c": L_c, "gain_set.L_c": L_c}
        try:
            view.check_constraints(values)
            accepted = True
        except LimitError as exc:
            assert exc.abort_code == TOO_HIGH
            accepted = False
        assert accepted == stable, (L, ratio)


def test_constraint_abort_code_depends_on_written_side(view) -> None:
    # writing L_c above 2 L: L_c too high
    with pytest.raises(LimitError) as info:
        view.check_constraints({"current_controller.L_c": 30e-6}, changed="current_controller.L_c")
    assert info.value.abort_code == TOO_HIGH
    # lowering motor.L under L_c / 2 (L_c at its default 14.8 uH): motor.L too low
    with pytest.raises(LimitError) as info:
        view.check_constraints({"motor.L": 7e-6}, changed="motor.L")
    assert info.value.abort_code == TOO_LOW
    assert "motor.L" in str(info.value) and "L_c" in str(info.value)
    view.check_constraints({"motor.L": 8e-6}, changed="motor.L")  # 14.8 < 16: fine
    # the staged set has no rule of its own (scratch space, checked as the objects it becomes
    # when applied): only the active objects' rules
    view.check_constraints({"gain_set.L_c": 40e-6})
    assert not view.constraints_for("gain_set.L_c")
    # float32 boundary: L_c == 2 L exactly is rejected (strict inequality)
    with pytest.raises(LimitError):
        view.check_constraints({"motor.L": 10e-6, "current_controller.L_c": 20e-6})


def test_other_constraints(view) -> None:
    view.check_constraints({"setpoints.i_p_ref": -100.0})
    with pytest.raises(LimitError) as info:
        view.check_constraints({"setpoints.i_p_ref": -100.5})
    assert info.value.abort_code == TOO_HIGH
    with pytest.raises(LimitError) as info:
        view.check_constraints(
            {"setpoints.i_p_ref": 50.0, "speed_controller.current_limit": 40.0},
            changed="speed_controller.current_limit",
        )
    assert info.value.abort_code == TOO_LOW
    with pytest.raises(LimitError):
        view.check_constraints({"target_velocity": 4001})
    view.check_constraints({"target_velocity": -4000})
    with pytest.raises(LimitError):
        view.check_constraints({"trace_config.channel_count": 8, "trace_config.length": 2049})
    view.check_constraints(
        {
            "trace_config.channel_count": 8,
            "trace_config.length": 2048,
            "trace_config.pre_trigger": 2047,
        }
    )
    with pytest.raises(LimitError):
        view.check_constraints({"trace_config.length": 100, "trace_config.pre_trigger": 100})
    with pytest.raises(LimitError):
        view.check_constraints({"protection.undervoltage_trip": 60.0})
    assert view.constraints_for("motor.L")
    for c in view.constraints:
        for name in c.names:
            assert name in view


# ---- enumerations ---------------------------------------------------------------------------


def test_intenums_match_eds_enum_keys() -> None:
    cp = configparser.RawConfigParser(inline_comment_prefixes=(";",))
    cp.optionxform = str  # type: ignore[assignment,method-assign]
    cp.read(EDS_PATH)
    view = load_od()
    covered = set()
    for cls, names in ENUM_OBJECTS.items():
        for name in names:
            e = view.entry(name)
            sec = cp[
                f"{e.index:04X}" if e.name == e.object_name else f"{e.index:04X}sub{e.subindex:X}"
            ]
            pairs = dict(item.split(":") for item in sec["Enum"].split(","))
            from_eds = {int(k): v for k, v in pairs.items()}
            assert from_eds == {m.value: m.name for m in cls}, name
            covered.add(name)
    with_enum = {e.name for e in view.entries if e.enum}
    assert with_enum == covered
    assert TraceState.DONE == 3 and ModeOfOperation.PSEUDO_CURRENT == -1


# ---- canopen object dictionary --------------------------------------------------------------


def test_canopen_od_is_fresh_and_complete(view) -> None:
    od1, od2 = view.canopen_od(), view.canopen_od(node_id=9)
    assert od1 is not od2
    assert od1[0x2010][2].min == pytest.approx(1e-8) and od1[0x2010][2].max == pytest.approx(2e-3)
    assert od1[0x2010][2].unit == "H"
    assert od1[0x6060].value_descriptions[-1] == "PSEUDO_CURRENT"
    assert od2[0x1800][1].default == 0x189
    assert od2["measurements"]["i_p"].pdo_mappable
    # fresh: a change to one dictionary (a LocalNode writing defaults) is not seen by the next
    od1[0x2010][2].max = 1.0
    od1[0x6060].value_descriptions.clear()
    od3 = view.canopen_od()
    assert od3 is not od1 and od3[0x2010][2] is not od1[0x2010][2]
    assert od3[0x2010][2].max == pytest.approx(2e-3)
    assert od3[0x6060].value_descriptions[-1] == "PSEUDO_CURRENT"
    assert od3[0x2010][2].parent is od3[0x2010]  # the copy's tree links to itself


def test_od_served_by_canopen_local_node_over_virtual_bus(view) -> None:
    """A canopen master reads and writes the drive OD through a real SDO exchange."""
    channel = "test_od_view_sdo"
    server_net, client_net = canopen.Network(), canopen.Network()
    server_net.connect(interface="virtual", channel=channel, receive_own_messages=False)
    client_net.connect(interface="virtual", channel=channel, receive_own_messages=False)
    try:
        local = server_net.create_node(5, view.canopen_od(5))
        remote = client_net.add_node(5, view.canopen_od(5))
        remote.sdo.RESPONSE_TIMEOUT = 2.0
        assert remote.sdo["device_type"].raw == 0x00020192
        assert remote.sdo["current_controller"]["L_c"].raw == pytest.approx(14.8e-6)
        remote.sdo["current_controller"]["k_p"].raw = 0.5
        assert local.sdo["current_controller"]["k_p"].raw == pytest.approx(0.5)
        assert remote.sdo["tpdo2_communication"]["cob_id"].raw == 0x285
        assert remote.sdo["modes_of_operation"].raw == ModeOfOperation.PROFILE_VELOCITY
    finally:
        server_net.disconnect()
        client_net.disconnect()


def test_load_od_validates_arguments(tmp_path) -> None:
    with pytest.raises(ValueError):
        load_od(node_id=0)
    with pytest.raises(ValueError):
        load_od(node_id=128)
    with pytest.raises(FileNotFoundError):
        load_od(tmp_path / "missing.eds")
    assert load_od() is load_od(EDS_PATH)  # cached and immutable


def test_package_docstring_examples_run() -> None:
    import doctest

    import firmware_protocol

    result = doctest.testmod(firmware_protocol)
    assert result.attempted >= 3 and result.failed == 0
