"""The EDS against its independent truths: CiA 306 file structure, CiA 301/402 object semantics
and the object table of docs/contracts.md §1 (parsed from the Markdown, not from our code)."""

from __future__ import annotations

import configparser
import math
import re
from pathlib import Path

import canopen
import pytest
from canopen.objectdictionary import ODArray, ODRecord, ODVariable

from firmware_protocol import EDS_PATH, load_od

pytestmark = [pytest.mark.timeout(60), pytest.mark.unit]

CONTRACTS = Path(__file__).resolve().parents[1] / "docs" / "contracts.md"


def _raw() -> configparser.RawConfigParser:
    cp = configparser.RawConfigParser(inline_comment_prefixes=(";",), strict=True)
    cp.optionxform = str  # type: ignore[assignment,method-assign]
    cp.read(EDS_PATH, encoding="utf-8")
    return cp


def _contract_section_1() -> str:
    text = CONTRACTS.read_text(encoding="utf-8")
    return text[text.index("## 1.") : text.index("## 2.")]


def _contract_indices() -> set[int]:
    """Every index in the first column of the §1 tables (ranges and 0x1008/9/A expanded)."""
    out: set[int] = set()
    for line in _contract_section_1().splitlines():
        if not line.startswith("| 0x"):
            continue
        cell = line.split("|")[1]
        for m in re.finditer(r"0x([0-9A-F]{4})(?:–0x([0-9A-F]{4}))?((?:/[0-9A-F])*)", cell):
            first = int(m.group(1), 16)
            last = int(m.group(2), 16) if m.group(2) else first
            if last - first > 0x10:  # "0x5000–0x50FF" is a range name, not objects
                last = first
            out.update(range(first, last + 1))
            for digit in m.group(3).split("/")[1:]:
                out.add((first & 0xFFF0) | int(digit, 16))
    return out


@pytest.fixture(scope="module")
def od() -> canopen.ObjectDictionary:
    return canopen.import_od(str(EDS_PATH), 1)


def test_every_contract_index_is_in_the_eds(od: canopen.ObjectDictionary) -> None:
    indices = _contract_indices()
    assert len(indices) > 50  # the parser found the tables
    missing = sorted(i for i in indices if i not in od)
    assert not missing, [f"0x{i:04X}" for i in missing]


def test_contract_python_names_resolve() -> None:
    """Names in §1 (python column and the manufacturer sub-object table) exist with that type."""
    view = load_od()
    text = _contract_section_1()
    type_codes = {"U8": 5, "U16": 6, "U32": 7, "I8": 2, "I16": 3, "I32": 4, "REAL32": 8}
    checked = 0
    for line in text.splitlines():
        cells = [c.strip() for c in line.split("|")[1:-1]]
        # "| 0x6040 | controlword | U16 rw | |"
        if len(cells) >= 3 and re.fullmatch(r"0x[0-9A-F]{4}", cells[0]):
            m = re.fullmatch(r"([a-z_0-9]+)", cells[1])
            t = re.match(r"(U8|U16|U32|I8|I16|I32)\b", cells[2])
            if m and t and not cells[1].startswith("sim_"):
                entry = view.entry(m.group(1))
                assert entry.data_type == type_codes[t.group(1)], cells
                checked += 1
    # manufacturer table: "| 0x2000 | motor | 1 | R | REAL32 | Ω | ..." and "| | | 2 | L | ..."
    record = None
    for line in text.splitlines():
        cells = [c.strip() for c in line.split("|")[1:-1]]
        if len(cells) != 7:
            continue
        if re.fullmatch(r"0x[0-9A-F]{4}", cells[0]):
            record = cells[1].split(" ")[0]
        if record and re.fullmatch(r"\d+", cells[2]) and re.fullmatch(r"\w+", cells[3]):
            entry = view.entry(f"{record}.{cells[3]}")
            assert entry.subindex == int(cells[2]), cells
            if cells[4] in type_codes:
                assert entry.data_type == type_codes[cells[4]], cells
            checked += 1
    assert checked >= 60


@pytest.mark.parametrize(
    ("name", "index", "sub", "type_code", "access", "default"),
    [
        ("device_type", 0x1000, 0, 7, "ro", 0x00020192),
        ("error_register", 0x1001, 0, 5, "ro", 0),
        ("manufacturer_device_name", 0x1008, 0, 9, None, None),
        ("hardware_version", 0x1009, 0, 9, None, None),
        ("software_version", 0x100A, 0, 9, None, None),
        ("cob_id_emcy", 0x1014, 0, 7, None, 0x81),
        ("consumer_heartbeat_time.consumer_1", 0x1016, 1, 7, "rw", 0),
        ("producer_heartbeat_time", 0x1017, 0, 6, "rw", 100),
        ("store_parameters.save_all", 0x1010, 1, 7, "rw", None),
        ("restore_default_parameters.restore_all", 0x1011, 1, 7, "rw", None),
        ("identity.vendor_id", 0x1018, 1, 7, "ro", None),
        ("identity.serial_number", 0x1018, 4, 7, "ro", None),
        ("sdo_server_1.cob_id_client_to_server", 0x1200, 1, 7, None, 0x601),
        ("sdo_server_1.cob_id_server_to_client", 0x1200, 2, 7, None, 0x581),
        ("sdo_server_2.cob_id_client_to_server", 0x1201, 1, 7, None, 0x681),
        ("sdo_server_2.cob_id_server_to_client", 0x1201, 2, 7, None, 0x6B1),
        ("error_code", 0x603F, 0, 6, "ro", None),
        ("controlword", 0x6040, 0, 6, "rw", None),
        ("statusword", 0x6041, 0, 6, "ro", None),
        ("quick_stop_option_code", 0x605A, 0, 3, "rw", 2),
        ("shutdown_option_code", 0x605B, 0, 3, "rw", 0),
        ("disable_operation_option_code", 0x605C, 0, 3, "rw", 1),
        ("fault_reaction_option_code", 0x605E, 0, 3, "rw", 2),
        ("abort_connection_option_code", 0x6007, 0, 3, "rw", 3),
        ("modes_of_operation", 0x6060, 0, 2, "rw", None),
        ("modes_of_operation_display", 0x6061, 0, 2, "ro", None),
        ("supported_drive_modes", 0x6502, 0, 7, "ro", 0x0001000C),
        ("velocity_actual_value", 0x606C, 0, 4, "ro", None),
        ("target_velocity", 0x60FF, 0, 4, "rw", None),
        ("target_torque", 0x6071, 0, 3, "rw", None),
        ("motor_rated_current", 0x6075, 0, 7, "rw", 100000),
        ("motor_rated_torque", 0x6076, 0, 7, "rw", 13920),
        ("dc_link_circuit_voltage", 0x6079, 0, 7, "ro", None),
        ("max_motor_speed", 0x6080, 0, 7, "rw", 4000),
        ("profile_acceleration", 0x6083, 0, 7, "rw", 0),
        ("profile_deceleration", 0x6084, 0, 7, "rw", 0),
        ("quick_stop_deceleration", 0x6085, 0, 7, "rw", 5000),
        ("motor.R", 0x2000, 1, 8, "rw", 0.0062),
        ("motor.L", 0x2000, 2, 8, "rw", 14.8e-6),
        ("motor.pole_pairs", 0x2000, 4, 6, "rw", 4),
        ("current_controller.type", 0x2010, 1, 5, "rw", 0),
        ("current_controller.L_c", 0x2010, 2, 8, "rw", 14.8e-6),
        ("current_controller.k_p", 0x2010, 4, 8, "rw", 0.4647),
        ("current_controller.k_i", 0x2010, 5, 8, "rw", 0.0492),
        ("current_controller.emf_feedforward", 0x2010, 10, 5, "rw", 0),
        ("speed_controller.k_p", 0x2020, 1, 8, "rw", 0.2113),
        ("speed_controller.k_i", 0x2020, 2, 8, "rw", 2.9994e-5),
        ("speed_controller.current_limit", 0x2020, 3, 8, "rw", 100.0),
        ("setpoints.i_p_ref", 0x2030, 1, 8, "rw", 0.0),
        ("measurements.i_p", 0x2040, 1, 8, "ro", None),
        ("measurements.hall_sector", 0x2040, 9, 5, "ro", None),
        ("measurements.theta_e", 0x2040, 14, 8, "ro", None),
        ("protection.overcurrent_trip", 0x2050, 1, 8, "rw", 300.0),
        ("protection.overvoltage_trip", 0x2050, 2, 8, "rw", 60.0),
        ("protection.undervoltage_trip", 0x2050, 3, 8, "rw", 36.0),
        ("gain_set.V_G", 0x20F0, 9, 8, "rw", None),
        ("gain_set.speed_k_p", 0x20F0, 11, 8, "rw", None),
        ("gain_set.speed_current_limit", 0x20F0, 13, 8, "rw", None),
        ("gain_set_apply", 0x20F1, 0, 5, "wo", None),
        ("trace_config.channel_count", 0x2100, 1, 5, "rw", None),
        ("trace_config.divider", 0x2100, 2, 6, "rw", 1),
        ("trace_config.trigger_source", 0x2100, 5, 7, "rw", 0x20400120),
        ("trace_config.state", 0x2100, 10, 5, "ro", None),
        ("trace_config.capacity", 0x2100, 12, 7, "ro", 16384),
        ("trace_channels.channel_8", 0x2101, 8, 7, "rw", None),
        ("trace_data", 0x2102, 0, 0xF, "ro", None),
        ("sim_load.T_load", 0x5000, 1, 8, "rw", None),
        ("sim_load.B", 0x5000, 4, 8, "rw", None),
        ("sim_fault.inject", 0x5010, 1, 5, "rw", 0),
        ("sim_fault.V_dc_supply", 0x5010, 2, 8, "rw", None),
        ("sim_inverter.V_G", 0x5020, 4, 8, "rw", None),
        ("sim_info.sim_time", 0x5030, 1, 8, "ro", None),
        ("sim_info.speed_factor", 0x5030, 2, 8, "ro", None),
        ("sim_info.model", 0x5030, 3, 5, None, None),
    ],
)
def test_contract_objects(
    od: canopen.ObjectDictionary,
    name: str,
    index: int,
    sub: int,
    type_code: int,
    access: str | None,
    default: float | None,
) -> None:
    """Name, place, type, access and default as written in docs/contracts.md §1."""
    obj_name, _, sub_name = name.partition(".")
    var = od[obj_name][sub_name] if sub_name else od[obj_name]
    assert (var.index, var.subindex, var.data_type) == (index, sub, type_code)
    if access is not None:
        assert var.access_type == access
    if default is not None:
        assert var.default == pytest.approx(default, rel=1e-9)


def test_device_type_is_cia402_servo(od: canopen.ObjectDictionary) -> None:
    value = od[0x1000].default
    assert value & 0xFFFF == 402  # device profile number (CiA 301 §7.5.2.1)
    assert (value >> 16) & 0xFF == 0x02  # CiA 402 additional information: servo drive


def test_supported_drive_modes_match_modes_of_operation(od: canopen.ObjectDictionary) -> None:
    """CiA 402 0x6502: bit (mode-1) for standard modes, manufacturer modes in bits 16..31."""
    modes = load_od().entry("modes_of_operation").enum
    assert modes is not None
    bits = od[0x6502].default
    for mode in modes:
        bit = mode - 1 if mode > 0 else 15 - mode  # -1 -> bit 16
        assert bits & (1 << bit), mode
    assert bits == 0x0001000C


def test_fileinfo_and_deviceinfo_are_complete() -> None:
    cp = _raw()
    for key in (
        "FileName",
        "FileVersion",
        "FileRevision",
        "EDSVersion",
        "Description",
        "CreationTime",
        "CreationDate",
        "CreatedBy",
    ):
        assert cp.get("FileInfo", key), key
    assert cp.get("FileInfo", "EDSVersion") == "4.0"
    info = cp["DeviceInfo"]
    for key in (
        "VendorName",
        "VendorNumber",
        "ProductName",
        "ProductNumber",
        "RevisionNumber",
        "OrderCode",
        "SimpleBootUpMaster",
        "SimpleBootUpSlave",
        "Granularity",
        "DynamicChannelsSupported",
        "GroupMessaging",
        "NrOfRXPDO",
        "NrOfTXPDO",
        "LSS_Supported",
    ):
        assert key in info, key
    for rate in (10, 20, 50, 125, 250, 500, 800, 1000):
        assert info[f"BaudRate_{rate}"] in ("0", "1")
    assert info["BaudRate_1000"] == "1" and info["BaudRate_500"] == "1"
    sections = cp.sections()
    n_rx = sum(1 for s in sections if re.fullmatch(r"14[0-9A-F]{2}", s))
    n_tx = sum(1 for s in sections if re.fullmatch(r"18[0-9A-F]{2}", s))
    assert (int(info["NrOfRXPDO"]), int(info["NrOfTXPDO"])) == (n_rx, n_tx) == (2, 4)
    # identity object agrees with DeviceInfo (CiA 306 §4.6.1)
    assert int(info["ProductNumber"], 0) == int(cp.get("1018sub2", "DefaultValue"), 0)
    assert int(info["RevisionNumber"], 0) == int(cp.get("1018sub3", "DefaultValue"), 0)
    assert int(info["VendorNumber"], 0) == int(cp.get("1018sub1", "DefaultValue"), 0)
    for i in range(1, 8):
        assert cp.get("DummyUsage", f"Dummy{i:04d}") in ("0", "1")


def test_object_lists_match_object_sections() -> None:
    """[Mandatory|Optional|ManufacturerObjects] list every object section exactly once."""
    cp = _raw()
    listed: dict[int, str] = {}
    for title in ("MandatoryObjects", "OptionalObjects", "ManufacturerObjects"):
        sec = cp[title]
        n = int(sec["SupportedObjects"], 0)
        assert set(sec) == {"SupportedObjects", *map(str, range(1, n + 1))}
        for i in range(1, n + 1):
            index = int(sec[str(i)], 0)
            assert index not in listed, f"0x{index:04X} listed twice"
            listed[index] = title
    objects = {int(s, 16) for s in cp.sections() if re.fullmatch(r"[0-9A-F]{4}", s)}
    assert set(listed) == objects
    assert {i for i, t in listed.items() if t == "MandatoryObjects"} == {0x1000, 0x1001, 0x1018}
    for index, title in listed.items():
        manufacturer = 0x2000 <= index <= 0x5FFF
        assert (title == "ManufacturerObjects") == manufacturer, hex(index)


def test_sections_follow_cia306() -> None:
    """Keys every CiA 306 tool expects, consistent sub-object counts and sub-index 0 values."""
    cp = _raw()
    access_types = {"ro", "wo", "rw", "rwr", "rww", "const"}
    for sec in cp.sections():
        if not re.fullmatch(r"[0-9A-F]{4}(sub[0-9A-F]+)?", sec):
            continue
        s = cp[sec]
        assert s.get("ParameterName"), sec
        otype = int(s.get("ObjectType", "0x7"), 0)
        if otype in (0x8, 0x9):
            subs = [x for x in cp.sections() if x.startswith(f"{sec}sub")]
            assert int(s["SubNumber"], 0) == len(subs), sec
            highest = max(int(x[len(sec) + 3 :], 16) for x in subs)
            index = int(sec, 16)
            counted = index == 0x1003 or 0x1600 <= index <= 0x17FF or 0x1A00 <= index <= 0x1BFF
            sub0 = int(cp.get(f"{sec}sub0", "DefaultValue"), 0)
            if counted:  # sub0 counts errors / mapped objects (CiA 301), it is writable
                assert sub0 <= highest and cp.get(f"{sec}sub0", "AccessType") == "rw", sec
            else:
                assert sub0 == highest, sec
            assert cp.get(f"{sec}sub0", "DataType") == "0x0005", sec
            continue
        assert otype in (0x2, 0x7), sec
        assert s["AccessType"] in access_types, sec
        int(s["DataType"], 0)
        if otype == 0x2:  # CiA 306: PDOMapping belongs to a VAR (a DOMAIN object has none)
            assert "PDOMapping" not in s, sec
        else:
            assert s["PDOMapping"] in ("0", "1"), sec
        if "ObjFlags" in s:
            assert int(s["ObjFlags"], 0) in (0, 1, 2, 3), sec
        if "StorageLocation" in s:
            assert s["StorageLocation"] in ("RAM", "PERSIST"), sec


def test_every_real32_has_unit_and_limits() -> None:
    view = load_od()
    reals = [e for e in view.entries if e.data_type == 0x08]
    assert len(reals) > 50
    for e in reals:
        assert e.unit, e.name
        assert e.low is not None and e.high is not None, e.name
        assert math.isfinite(e.low) and math.isfinite(e.high) and e.low < e.high, e.name
    # the raw EDS text carries them too (canopen drops REAL32 limits, other tools must not)
    cp = _raw()
    for e in reals:
        sec = cp[f"{e.index:04X}sub{e.subindex:X}" if e.object_name != e.name else f"{e.index:04X}"]
        assert {"Unit", "LowLimit", "HighLimit"} <= set(sec), e.name


def test_contract_units_and_limits() -> None:
    """Units and limits written in contracts.md §1 (SI, Ω as Ohm)."""
    view = load_od()
    expect = {
        "motor.R": ("Ohm", 1e-4, 1.0),
        "motor.L": ("H", 1e-6, 1e-3),
        "motor.K_rpm": ("V/rpm", 1e-4, 1.0),
        "motor.pole_pairs": ("1", 1, 32),
        "current_controller.R_c": ("Ohm", 0.0, 1.0),
        "current_controller.L_c": ("H", None, None),
        "current_controller.T_BT": ("s", None, None),
        "current_controller.V_G": ("V", None, None),
        "speed_controller.k_p": ("A/rpm", None, None),
        "speed_controller.k_i": ("1/sample", None, None),
        "speed_controller.current_limit": ("A", 0.0, 200.0),
        "setpoints.i_p_ref": ("A", -200.0, 200.0),
        "measurements.speed": ("rpm", None, None),
        "measurements.theta_e": ("rad", None, None),
        "trace_config.divider": (None, 1, 5000),
        "trace_config.channel_count": (None, 1, 8),
        "producer_heartbeat_time": ("ms", None, None),
        "motor_rated_current": ("mA", None, None),
        "dc_link_circuit_voltage": ("mV", None, None),
        "velocity_actual_value": ("rpm", None, None),
        "sim_load.T_load": ("N*m", None, None),
    }
    for name, (unit, low, high) in expect.items():
        e = view.entry(name)
        if unit is not None:
            assert e.unit == unit, name
        if low is not None:
            assert e.low == low and e.high == high, name
    # L_c's static range must allow every L_c < 2 L for every allowed motor L
    assert view.entry("current_controller.L_c").high >= 2 * view.entry("motor.L").high
    assert view.entry("current_controller.L_c").low > 0


def test_defaults_lie_within_limits_and_enums() -> None:
    view = load_od()
    for e in view.entries:
        if not isinstance(e.default, (int, float)):
            continue
        # CiA 306 checkers compare DefaultValue with LowLimit/HighLimit for every object
        assert e.low is None or e.low <= e.default, e.name
        assert e.high is None or e.default <= e.high, e.name
        if e.access == "wo":
            continue  # a write-only command's default (0 = nothing requested) is never read
        assert e.check(e.default) == pytest.approx(e.default, rel=1e-6), e.name


def test_measurements_and_setpoints_are_pdo_mappable() -> None:
    view = load_od()
    for e in view.entries:
        if e.object_name == "measurements" and e.subindex:
            assert e.pdo_mappable and e.access == "ro", e.name
    for name in (
        "controlword",
        "statusword",
        "target_velocity",
        "velocity_actual_value",
        "setpoints.i_p_ref",
        "modes_of_operation",
    ):
        assert view.entry(name).pdo_mappable, name
    for name in ("current_controller.L_c", "store_parameters.save_all", "trace_data"):
        assert not view.entry(name).pdo_mappable, name


def test_commands_are_not_written_by_configuration_download() -> None:
    """ObjFlags bit0 (CiA 306): tools must not write these when downloading a DCF."""
    view = load_od()
    for name in (
        "store_parameters.save_all",
        "restore_default_parameters.restore_all",
        "gain_set_apply",
        "trace_config.command",
        "sim_fault.inject",
    ):
        assert view.entry(name).obj_flags & 0x1, name
    assert view.entry("trace_data").obj_flags & 0x2  # don't read on scan (up to 64 KiB)


# ---- PDOs (CiA 301 §7.5.2.35ff) -------------------------------------------------------------

EXPECTED_PDOS = {
    # mapping index: (comm index, COB-ID base, event timer ms, [(index, sub, bits), ...])
    0x1600: (0x1400, 0x200, None, [(0x6040, 0, 16), (0x60FF, 0, 32)]),
    0x1601: (0x1401, 0x300, None, [(0x2030, 1, 32)]),
    0x1A00: (0x1800, 0x180, 10, [(0x6041, 0, 16), (0x606C, 0, 32)]),
    0x1A01: (0x1801, 0x280, 1, [(0x2040, 1, 32), (0x2040, 5, 32)]),
    0x1A02: (0x1802, 0x380, 1, [(0x2040, 10, 32), (0x2040, 11, 32)]),
    0x1A03: (0x1803, 0x480, 10, [(0x2040, 6, 32), (0x2040, 7, 32)]),
}
_TYPE_BITS = {1: 1, 2: 8, 3: 16, 4: 32, 5: 8, 6: 16, 7: 32, 8: 32}


@pytest.mark.parametrize("map_index", sorted(EXPECTED_PDOS))
def test_pdo_default_mapping(od: canopen.ObjectDictionary, map_index: int) -> None:
    comm_index, cob_base, event_ms, expected = EXPECTED_PDOS[map_index]
    mapping = od[map_index]
    count = mapping[0].default
    words = [mapping[i].default for i in range(1, count + 1)]
    decoded = [(w >> 16, (w >> 8) & 0xFF, w & 0xFF) for w in words]
    assert decoded == expected
    assert sum(bits for _, _, bits in decoded) <= 64
    for index, sub, bits in decoded:
        target = od[index] if isinstance(od[index], ODVariable) else od[index][sub]
        assert target.pdo_mappable, (hex(index), sub)
        assert _TYPE_BITS[target.data_type] == bits
        if map_index < 0x1800:
            assert target.access_type in ("rw", "wo", "rww")  # RPDO writes it
        else:
            assert target.access_type in ("ro", "rw", "rwr", "const")
    for i in range(count + 1, 9):
        assert mapping[i].default == 0
    comm = od[comm_index]
    assert comm[1].default == cob_base + 1  # node-ID 1, bit31 clear = valid
    assert comm[2].default == 0xFF
    if event_ms is not None:
        assert comm[5].default == event_ms


def test_node_id_resolves_cob_ids_per_predefined_connection_set() -> None:
    od = load_od(node_id=42).canopen_od()
    assert od[0x1014].default == 0x80 + 42
    assert od[0x1200][1].default == 0x600 + 42 and od[0x1200][2].default == 0x580 + 42
    for n in range(4):
        assert od[0x1800 + n][1].default == 0x180 + 0x100 * n + 42
    for n in range(2):
        assert od[0x1400 + n][1].default == 0x200 + 0x100 * n + 42
    # second SDO server stays clear of the predefined set for N <= 47
    for nid in (1, 47):
        od = load_od(node_id=nid).canopen_od()
        rx, tx = od[0x1201][1].default, od[0x1201][2].default
        assert 0x680 <= rx < 0x6E0 and 0x680 <= tx < 0x6E0 and rx != tx


def test_structure_types(od: canopen.ObjectDictionary) -> None:
    assert isinstance(od[0x1003], ODArray) and isinstance(od[0x2101], ODArray)
    assert isinstance(od[0x2010], ODRecord) and isinstance(od[0x1018], ODRecord)
    assert od[0x1003][0].access_type == "rw"  # write 0 clears the history (CiA 301)
    assert len([k for k in od[0x1003] if k]) == 8


def test_sim_load_defaults_reproduce_the_papers_identified_speed_model() -> None:
    """Valle et al. §IV: G(z) = b / (z - a), a ~ 0.9999785, b = 3.33715e-4 rpm/(A sample) at
    Ts = 20 us. With T_e = K_t i_p (K_t = K_rpm * 60 / 2 pi, line-to-line BLDC) and
    J dw/dt = T_e - (B + k_gen * 60 / 2 pi) w, the OD's default mechanics must give that model."""
    view = load_od()
    Ts = 20e-6
    rpm_per_rad_s = 60 / (2 * math.pi)
    K_t = view.entry("motor.K_rpm").default * rpm_per_rad_s
    J = view.entry("sim_load.J").default
    B_total = (
        view.entry("sim_load.B").default + view.entry("sim_load.k_gen").default * rpm_per_rad_s
    )
    a = math.exp(-B_total / J * Ts)
    b = K_t / J * Ts * rpm_per_rad_s
    assert a == pytest.approx(0.9999785, abs=2e-8)
    assert b == pytest.approx(3.33715e-4, rel=1e-3)
