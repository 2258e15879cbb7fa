"""The generated files against the EDS: the C header compiles (gcc, C99, pedantic) and its
macros equal the EDS text, it has no 8-bit types and no double; OD.md lists every object;
neither drifts."""

from __future__ import annotations

import configparser
import contextlib
import io
import re
import shutil
import subprocess
import sys
from pathlib import Path

import canopen
import pytest

from firmware_protocol import EDS_PATH, load_od
from firmware_protocol.generate import main as generate_main
from firmware_protocol.generate import render_header, render_markdown

pytestmark = pytest.mark.timeout(120)

PKG = EDS_PATH.parent
HEADER = PKG / "bldc_drive_od.h"
MARKDOWN = PKG / "OD.md"
GCC_FLAGS = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-Wdouble-promotion"]
BITS = {1: 1, 2: 8, 3: 16, 4: 32, 5: 8, 6: 16, 7: 32, 8: 32}
TYPE_NAMES = {
    1: "BOOLEAN",
    2: "INTEGER8",
    3: "INTEGER16",
    4: "INTEGER32",
    5: "UNSIGNED8",
    6: "UNSIGNED16",
    7: "UNSIGNED32",
    8: "REAL32",
    9: "VISIBLE_STRING",
    0xF: "DOMAIN",
}


def _eds_rows() -> list[dict[str, str]]:
    """Every VAR / sub-object of the EDS, straight from the text (not through firmware_protocol)."""
    cp = configparser.RawConfigParser(inline_comment_prefixes=(";",))
    cp.optionxform = str  # type: ignore[assignment,method-assign]
    cp.read(EDS_PATH, encoding="utf-8")
    rows = []
    for sec in cp.sections():
        m = re.fullmatch(r"([0-9A-F]{4})(?:sub([0-9A-F]+))?", sec)
        if not m:
            continue
        s = dict(cp[sec])
        index = int(m.group(1), 16)
        if m.group(2) is None:
            if int(s.get("ObjectType", "0x7"), 0) in (0x8, 0x9):
                continue
            s["name"], s["sub"] = s["ParameterName"], "0"
        else:
            parent = cp[m.group(1)]["ParameterName"]
            s["name"], s["sub"] = f"{parent}.{s['ParameterName']}", str(int(m.group(2), 16))
        s["index"] = str(index)
        rows.append(s)
    return rows


def _macro(name: str) -> str:
    """The header's documented naming: OD_<OBJECT>__<SUB>, upper case."""
    return "OD_" + "__".join(p.upper() for p in name.split("."))


def _c_literal(text: str, data_type: int) -> str:
    if data_type == 8:
        return f"({text}f)"
    value = int(text, 0)
    if (
        data_type in (2, 3, 4)
        and text.lower().startswith("0x")
        and value >= 1 << (BITS[data_type] - 1)
    ):
        value -= 1 << BITS[data_type]
    return f"({value}L)" if data_type in (2, 3, 4) else f"({value}UL)"


@pytest.fixture(scope="module")
def gcc() -> str:
    path = shutil.which("gcc")
    if path is None:
        pytest.fail("gcc is required to check the DSP header")
    return path


def test_header_compiles_and_every_macro_equals_the_eds(gcc: str, tmp_path: Path) -> None:
    checks: list[str] = []
    statics: list[str] = []
    n_static = 0
    for row in _eds_rows():
        m, dt = _macro(row["name"]), int(row["DataType"], 0)
        checks.append(f"CHECK({m}_INDEX == {row['index']}u);")
        checks.append(f"CHECK({m}_SUB == {row['sub']}u);")
        checks.append(f"CHECK({m}_TYPE == {dt}u);")
        checks.append(f"CHECK({m}_PDO == {int(row.get('PDOMapping', '0'))}u);")
        if dt in BITS:
            ref = (int(row["index"]) << 16) | (int(row["sub"]) << 8) | BITS[dt]
            checks.append(f"CHECK({m}_REF == {ref}UL);")
            # C2000 portability: the C type is wide enough and 8-bit objects use 16 bits
            statics.append(
                f"typedef char sa_{n_static}[(sizeof({m}_CTYPE) * 8u >= {max(BITS[dt], 16)}u) "
                "? 1 : -1];"
            )
            n_static += 1
        for key, suffix in (("LowLimit", "MIN"), ("HighLimit", "MAX"), ("DefaultValue", "DEFAULT")):
            if key not in row or dt not in BITS:
                continue
            text = row[key]
            if "$NODEID" in text.upper():
                offset = int(re.sub(r"\$NODEID|\+|\s", "", text, flags=re.I), 0)
                checks.append(f"CHECK({m}_DEFAULT(5) == {offset + 5}UL);")
                continue
            checks.append(f"CHECK({m}_{suffix} == {_c_literal(text, dt)});")
            if dt == 8:  # REAL32 macros are float, never double
                statics.append(
                    f"typedef char sa_{n_static}[(sizeof({m}_{suffix}) == sizeof(float)) ? 1 : -1];"
                )
                n_static += 1
            else:
                literal = _c_literal(text, dt)
                statics.append(f"typedef char sa_{n_static}[({m}_{suffix} == {literal}) ? 1 : -1];")
                n_static += 1
    assert len(checks) > 1000
    source = "\n".join(
        [
            '#include "bldc_drive_od.h"',
            "#include <stdio.h>",
            "static int failures = 0;",
            '#define CHECK(c) do { if (!(c)) { printf("FAIL %s\\n", #c); failures++; } } while (0)',
            *statics,
            "int main(void) {",
            "    OD_CURRENT_CONTROLLER__L_C_CTYPE L_c = OD_CURRENT_CONTROLLER__L_C_DEFAULT;",
            "    OD_MOTOR__L_CTYPE L = OD_MOTOR__L_DEFAULT;",
            "    CHECK(L_c < OD_CURRENT_CONTROLLER__L_C_BOUND_FACTOR * L);",
            "    CHECK(OD_TRACE_CONFIG__TRIGGER_MODE_FAULT == 3u);",
            "    CHECK(OD_MODES_OF_OPERATION_PSEUDO_CURRENT == -1);",
            "    CHECK(sizeof(OD_MODES_OF_OPERATION_CTYPE) * 8u >= 16u);",
            *("    " + c for c in checks),
            "    return failures;",
            "}",
        ]
    )
    src = tmp_path / "check_od.c"
    src.write_text(source + "\n")
    exe = tmp_path / "check_od"
    build = subprocess.run(
        [gcc, *GCC_FLAGS, f"-I{PKG}", str(src), "-o", str(exe)],
        capture_output=True,
        text=True,
        timeout=90,
    )
    assert build.returncode == 0, build.stderr[:3000]
    run = subprocess.run([str(exe)], capture_output=True, text=True, timeout=30)
    assert run.returncode == 0, run.stdout[:3000]


@pytest.mark.unit
def test_header_has_no_8bit_types_and_no_double() -> None:
    text = HEADER.read_text()
    code = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    code = re.sub(r'"[^"\n]*"', '""', code)  # string literals (e.g. the version "0.1.0")
    for banned in ("uint8_t", "int8_t", "double", "long double"):
        assert not re.search(rf"\b{banned}\b", code), banned
    # every floating literal carries the f suffix (a bare 1.5 would be a double)
    for lit in re.finditer(r"(?<![\w.])(\d+\.\d*(?:[eE][+-]?\d+)?|\d+[eE][+-]?\d+)(\w?)", code):
        assert lit.group(2) == "f", lit.group(0)
    assert "#ifndef BLDC_DRIVE_OD_H" in text and text.rstrip().endswith(
        "#endif /* BLDC_DRIVE_OD_H */"
    )


@pytest.mark.unit
def test_header_and_markdown_do_not_drift() -> None:
    view = load_od()
    assert HEADER.read_text(encoding="utf-8") == render_header(view), (
        "bldc_drive_od.h drifted from the EDS: run python -m firmware_protocol.generate"
    )
    assert MARKDOWN.read_text(encoding="utf-8") == render_markdown(view), (
        "OD.md drifted from the EDS: run python -m firmware_protocol.generate"
    )


@pytest.mark.unit
def test_markdown_lists_every_object_once_with_its_attributes() -> None:
    text = MARKDOWN.read_text(encoding="utf-8")
    rows: dict[str, list[str]] = {}
    for line in text.splitlines():
        cells = [c.strip() for c in re.split(r"(?<!\\)\|", line)[1:-1]]
        if len(cells) == 9 and cells[0].startswith("`"):
            name = cells[0].strip("`")
            assert name not in rows, name
            rows[name] = cells
    eds = _eds_rows()
    assert set(rows) == {r["name"] for r in eds}
    for r in eds:
        cells = rows[r["name"]]
        assert cells[1] == f"0x{int(r['index']):04X}:{int(r['sub']):02X}"
        assert cells[2] == TYPE_NAMES[int(r["DataType"], 0)]
        assert cells[3] == r["AccessType"]
        assert cells[4] == r.get("Unit", "")
        assert (cells[7] == "yes") == (r.get("PDOMapping") == "1")
        if "MinNonZero" in r:  # "0 or [min_nonzero, high]"
            assert cells[6].startswith("0 or [") and cells[6].endswith("]"), r["name"]
        elif "LowLimit" in r:
            assert cells[6].startswith("[") and cells[6].endswith("]"), r["name"]
    # one table per range
    for title in ("0x1000-0x1FFF", "0x2000-0x4FFF", "0x5000-0x5FFF", "0x6000-0x9FFF"):
        assert re.search(rf"^## .*\({title}", text, flags=re.M), title
    assert "current_controller.L_c < 2 * motor.L" in text
    # the PDO table reads as contracts.md §1 states the defaults
    pdo_rows = {
        line.split("|")[1].strip(): line
        for line in text.splitlines()
        if re.match(r"\| [RT]PDO", line)
    }
    assert set(pdo_rows) == {"RPDO1", "RPDO2", "TPDO1", "TPDO2", "TPDO3", "TPDO4"}
    assert re.search(r"`measurements.i_p` \(32\), `measurements.speed` \(32\)", pdo_rows["TPDO2"])
    assert "| 1 ms |" in pdo_rows["TPDO2"] and "| 10 ms |" in pdo_rows["TPDO1"]
    assert "$NODEID+0x200" in pdo_rows["RPDO1"] and "`controlword` (16)" in pdo_rows["RPDO1"]


def _generate(*args: str) -> subprocess.CompletedProcess[str]:
    """Run the generator in-process (the ``python -m`` entry is covered once below)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = generate_main(list(args))
    return subprocess.CompletedProcess(args, code, out.getvalue(), err.getvalue())


def test_python_m_entry_point_checks_the_repo() -> None:
    result = subprocess.run(
        [sys.executable, "-m", "firmware_protocol.generate", "--check"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 0, result.stderr


@pytest.mark.unit
def test_generate_check_passes_on_the_repo_and_fails_on_drift(tmp_path: Path) -> None:
    assert _generate("--check").returncode == 0
    # a hand edit of a generated file is drift
    shutil.copy(HEADER, tmp_path / HEADER.name)
    shutil.copy(MARKDOWN, tmp_path / MARKDOWN.name)
    edited = (tmp_path / HEADER.name).read_text().replace("1.48e-05f", "1.5e-05f", 1)
    (tmp_path / HEADER.name).write_text(edited)
    result = _generate("--check", "--out-dir", str(tmp_path))
    assert result.returncode == 1
    assert "bldc_drive_od.h" in result.stderr and "OD.md" not in result.stderr
    assert (tmp_path / HEADER.name).read_text() == edited  # --check writes nothing
    # an EDS edit without regeneration is drift too
    eds = tmp_path / "bldc_drive.eds"
    eds.write_text(EDS_PATH.read_text().replace("DefaultValue=0.4647", "DefaultValue=0.5", 1))
    result = _generate("--check", "--eds", str(eds))
    assert result.returncode == 1 and "OD.md" in result.stderr
    # regeneration into a directory produces exactly the checked-in files
    out = tmp_path / "out"
    out.mkdir()
    assert _generate("--out-dir", str(out)).returncode == 0
    assert (out / HEADER.name).read_text() == HEADER.read_text()
    assert (out / MARKDOWN.name).read_text() == MARKDOWN.read_text()


@pytest.mark.unit
def test_generate_bad_input_is_one_line_and_non_zero(tmp_path: Path) -> None:
    result = _generate("--check", "--eds", str(tmp_path / "missing.eds"))
    assert result.returncode != 0
    assert result.stderr.strip().count("\n") == 0 and "missing.eds" in result.stderr


@pytest.mark.unit
def test_strict_eds_export_keeps_the_od_and_only_cia306_keys(tmp_path: Path) -> None:
    out = tmp_path / "strict.eds"
    result = _generate("--check", "--strict-eds", str(out))
    assert result.returncode == 0, result.stderr
    cp = configparser.RawConfigParser(inline_comment_prefixes=(";",))
    cp.optionxform = str  # type: ignore[assignment,method-assign]
    cp.read(out, encoding="utf-8")
    # the object-section keys CiA 306 defines (as accepted by strict checkers such as lely dcfchk)
    cia306 = {
        "SubNumber",
        "ParameterName",
        "ObjectType",
        "DataType",
        "AccessType",
        "LowLimit",
        "HighLimit",
        "DefaultValue",
        "PDOMapping",
        "ObjFlags",
        "CompactSubObj",
        "ParameterValue",
        "UploadFile",
        "DownloadFile",
        "Denotation",
        "ParamRefd",
    }
    n = 0
    for sec in cp.sections():
        if re.fullmatch(r"[0-9A-F]{4}(sub[0-9A-F]+)?", sec):
            assert set(cp[sec]) <= cia306, sec
            n += 1
    assert n == len(_eds_rows()) + sum(
        1 for s in cp.sections() if re.fullmatch(r"[0-9A-F]{4}", s) and "SubNumber" in cp[s]
    )
    strict, full = canopen.import_od(str(out), 1), canopen.import_od(str(EDS_PATH), 1)

    def flat(od):
        rows = set()
        for obj in od.values():
            for var in obj.values() if hasattr(obj, "values") else [obj]:
                rows.add(
                    (
                        var.index,
                        var.subindex,
                        var.name,
                        var.data_type,
                        var.access_type,
                        var.pdo_mappable,
                        repr(var.default),
                    )
                )
        return rows

    assert flat(strict) == flat(full)


@pytest.mark.unit
def test_generate_rejects_a_malformed_eds_in_one_line(tmp_path: Path) -> None:
    bad = tmp_path / "bad.eds"
    bad.write_text("[FileInfo]\nnot a key value line\n")
    dup = tmp_path / "dup.eds"
    dup.write_text(
        EDS_PATH.read_text().replace("ParameterName=motor\n", "ParameterName=setpoints\n")
    )
    for path in (bad, dup):
        result = _generate("--check", "--eds", str(path))
        assert result.returncode == 2
        assert result.stderr.count("\n") == 1 and "not a valid drive EDS" in result.stderr
    assert "duplicate object names" in result.stderr
    with pytest.raises(ValueError):
        load_od(dup)


def test_every_value_macro_fits_its_c_type_without_conversion(gcc: str, tmp_path: Path) -> None:
    """``OD_X_CTYPE v = OD_X_DEFAULT/MIN/MAX;`` compiles with -Wconversion -Wsign-conversion."""
    text = HEADER.read_text()
    stems = sorted(set(re.findall(r"#define (OD_\w+)_CTYPE\b", text)))
    body = []
    for stem in stems:
        for field in ("DEFAULT", "MIN", "MAX"):
            if re.search(rf"#define {stem}_{field}\s", text):
                body.append(f"    {{ {stem}_CTYPE v = {stem}_{field}; sink(&v, sizeof v); }}")
    assert len(body) > 300
    src = tmp_path / "conv.c"
    src.write_text(
        "\n".join(
            [
                '#include "bldc_drive_od.h"',
                "#include <stddef.h>",
                "void sink(const void *p, size_t n);",
                "void use_all(void);",
                "void use_all(void) {",
                *body,
                "}",
            ]
        )
        + "\n"
    )
    flags = [*GCC_FLAGS, "-Wconversion", "-Wsign-conversion", "-Wfloat-conversion"]
    build = subprocess.run(
        [gcc, *flags, f"-I{PKG}", "-c", str(src), "-o", str(tmp_path / "conv.o")],
        capture_output=True,
        text=True,
        timeout=90,
    )
    assert build.returncode == 0, build.stderr[:3000]
