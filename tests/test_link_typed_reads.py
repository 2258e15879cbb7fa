"""Typed reads: drive_link.link.od_names (the ``Literal`` names Drive.read is overloaded on) is the
EDS's, grouped by the type a read returns.

Truth: canopen's own EDS import (its ODVariable data types, CiA 301 Table 44 codes), not our
object table; and the generator's --check against the checked-in module.
"""

from __future__ import annotations

from typing import get_args

import canopen
import pytest
from canopen.objectdictionary import datatypes

from drive_link.link import _od_names_gen, od_names
from firmware_protocol import EDS_PATH

pytestmark = pytest.mark.unit

INTEGER_TYPES = datatypes.INTEGER_TYPES


def _canopen_variables() -> dict[tuple[int, int], canopen.objectdictionary.ODVariable]:
    od = canopen.import_od(str(EDS_PATH), node_id=1)
    out = {}
    for obj in od.values():
        if isinstance(obj, canopen.objectdictionary.ODVariable):
            out[(obj.index, obj.subindex)] = obj
        else:
            for var in obj.values():
                out[(var.index, var.subindex)] = var
    return out


def test_the_checked_in_names_module_is_the_generated_one():
    assert _od_names_gen.main(["--check"]) == 0


def test_names_are_grouped_by_the_eds_data_type():
    from drive_link.link._objects import default_table

    table = default_table()
    variables = _canopen_variables()
    groups = {
        "FloatName": lambda t: t == datatypes.REAL32,
        "IntName": lambda t: t in INTEGER_TYPES,
        "TextName": lambda t: t == datatypes.VISIBLE_STRING,
        "BytesName": lambda t: t == datatypes.DOMAIN,
    }
    seen: set[str] = set()
    for group, is_type in groups.items():
        names = get_args(getattr(od_names, group))
        assert names, group
        for n in names:
            o = table[n]
            var = variables[(o.index, o.subindex)]
            assert is_type(var.data_type), f"{n}: EDS type 0x{var.data_type:04X} not {group}"
        seen.update(names)
    readable = {o.name for o in table if o.readable}
    assert seen == readable  # every readable object has its group, nothing else
    assert "measurements.speed" in get_args(od_names.FloatName)
