"""The virtual drive's node code addresses objects by EDS name, never by literal index (issue 13).

Truth: the EDS (``firmware_protocol/bldc_drive.eds``) and the CiA 301/402 index map
(:mod:`firmware_protocol.index_ranges`). The scan finds hex literals in the OD's index range in the
node modules' code (docstrings and comments excluded): each would be a second home of an object's
index, which a renumbering in the EDS would not reach.
"""

from __future__ import annotations

import ast
import io
import tokenize
from pathlib import Path

import pytest

from firmware_protocol import load_od
from firmware_protocol.index_ranges import COMMUNICATION, PROFILE
from virtual_drive.node import od_addresses, plant

pytestmark = pytest.mark.unit

NODE_DIR = Path(od_addresses.__file__).parent

#: (module, literal): hex numbers in the index range that are not object indices.
NOT_INDICES = {
    ("emcy.py", "0xF000"),  # EMCY error-code class mask and classes (CiA 301 Table 21)
    ("emcy.py", "0x2000"),
    ("emcy.py", "0x3000"),
    ("emcy.py", "0x4000"),
    ("emcy.py", "0x8000"),
    ("cia402.py", "0x3000"),  # statusword bits 12-13 (operation-mode specific)
    ("sdo_block.py", "0x1021"),  # CRC-16/CCITT polynomial
}


def _docstring_lines(tree: ast.Module) -> set[int]:
    lines: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            body = node.body
        else:
            continue
        for stmt in body:  # docstrings, and the attribute docstrings after assignments
            if isinstance(stmt, ast.Expr) and isinstance(stmt.value, ast.Constant):
                if isinstance(stmt.value.value, str):
                    lines.update(range(stmt.lineno, (stmt.end_lineno or stmt.lineno) + 1))
    return lines


def _index_literals(path: Path) -> list[tuple[int, str]]:
    src = path.read_text(encoding="utf-8")
    skip = _docstring_lines(ast.parse(src))
    found = []
    for tok in tokenize.generate_tokens(io.StringIO(src).readline):
        if tok.type != tokenize.NUMBER or not tok.string.lower().startswith("0x"):
            continue
        value = int(tok.string, 16)
        if COMMUNICATION.start <= value < PROFILE.stop and tok.start[0] not in skip:
            found.append((tok.start[0], tok.string))
    return found


@pytest.mark.parametrize("path", sorted(NODE_DIR.glob("*.py")), ids=lambda p: p.name)
def test_node_code_has_no_literal_object_index(path: Path) -> None:
    left = [
        f"{path.name}:{line}: {text}"
        for line, text in _index_literals(path)
        if (path.name, text) not in NOT_INDICES and path.name != "od_addresses.py"
    ]
    hint = "object indices written as literals (use virtual_drive.node.od_addresses)"
    assert not left, hint + ":\n" + "\n".join(left)


def test_the_scan_sees_a_literal_index(tmp_path: Path) -> None:
    """The scan is not blind: a literal index in code is found, the same in a docstring not."""
    probe = tmp_path / "probe.py"
    probe.write_text('"""0x6041 statusword."""\n\nx = d._value(0x6041)  # 0x6041\n')
    assert _index_literals(probe) == [(3, "0x6041")]


def test_addresses_are_the_eds_objects() -> None:
    """Each address constant is the EDS object of that name (spot checks against the EDS)."""
    od = load_od()
    for name, constant in [
        ("statusword", od_addresses.STATUSWORD),
        ("trace_config.pre_trigger_filled", od_addresses.TRACE_PRE_TRIGGER_FILLED),
        ("speed_controller.current_limit", od_addresses.SPEED_CURRENT_LIMIT),
        ("sim_load.J", od_addresses.SIM_LOAD_J),
    ]:
        e = od.entry(name)
        assert constant == (e.index, e.subindex)
    assert od_addresses.N_TPDO == len(
        {e.index for e in od if e.object_name.startswith("tpdo") and "communication" in e.name}
    )
    # plant maps: the EDS sub names are the simulator's keywords
    for index, (_setter, kw) in plant.SETTERS.items():
        for sub, key in kw.items():
            assert od.by_index(index, sub).sub_name == key
