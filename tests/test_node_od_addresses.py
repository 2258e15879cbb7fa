"""The virtual drive's node code addresses objects by EDS name, never by literal index (issue 13),
through the one Python view of the EDS (``load_od().address/index_of/sub_names``, issue 25).

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

import canopen
import pytest

import firmware_protocol
from firmware_protocol import load_od
from firmware_protocol.index_ranges import COMMUNICATION, PROFILE
from virtual_drive.node import pdo, plant, ramps, reads, trace_config

pytestmark = pytest.mark.unit

NODE_DIR = Path(plant.__file__).parent
EDS = Path(firmware_protocol.__file__).parent / "bldc_drive.eds"

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
        if (path.name, text) not in NOT_INDICES
    ]
    hint = "object indices written as literals (use load_od().address(name) / index_of(name))"
    assert not left, hint + ":\n" + "\n".join(left)


def test_the_scan_sees_a_literal_index(tmp_path: Path) -> None:
    """The scan is not blind: a literal index in code is found, the same in a docstring not."""
    probe = tmp_path / "probe.py"
    probe.write_text('"""0x6041 statusword."""\n\nx = d._value(0x6041)  # 0x6041\n')
    assert _index_literals(probe) == [(3, "0x6041")]


def test_addresses_are_the_eds_objects() -> None:
    """The addresses the node resolves through the view are the EDS objects of those names, as
    canopen's own EDS reader (an independent parser) finds them."""
    od = canopen.import_od(str(EDS), 1)

    def at(name: str) -> tuple[int, int]:
        obj, _, sub = name.partition(".")
        return (od[obj].index, od[obj][sub].subindex) if sub else (od[obj].index, 0)

    for name, constant in [
        ("statusword", reads.STATUSWORD),
        ("trace_config.pre_trigger_filled", reads.TRACE_PRE_TRIGGER_FILLED),
        ("speed_controller.current_limit", ramps.SPEED_CURRENT_LIMIT),
        ("sim_load.J", ramps.SIM_LOAD_J),
    ]:
        assert constant == at(name), name
    assert trace_config.TRACE_CHANNELS_INDEX == od["trace_channels"].index
    assert pdo.N_TPDO == sum(
        1 for o in od.values() if o.name.startswith("tpdo") and o.name.endswith("_communication")
    )
    view = load_od()
    for record in ("gain_set", "trace_config", "current_controller", "pre_defined_error_field"):
        assert view.index_of(record) == od[record].index
        subs = {sub: v.name for sub, v in od[record].subindices.items() if sub}
        assert view.sub_names(record) == subs, record
    # plant maps: the EDS sub names are the simulator's keywords
    for index, (_setter, kw) in plant.SETTERS.items():
        for sub, key in kw.items():
            assert od[index][sub].name == key
