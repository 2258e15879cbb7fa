"""drive_link.jsonable: what it returns is accepted by a strict JSON parser (RFC 8259: no NaN)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from drive_link import jsonable

pytestmark = pytest.mark.unit


def _strict_loads(text: str):
    def refuse(name: str):
        raise ValueError(f"not JSON: {name}")

    return json.loads(text, parse_constant=refuse)


def test_numpy_and_non_finite_values_become_strict_json():
    data = {
        1: np.float32(0.5),
        "arr": np.array([1.0, np.nan, np.inf]),
        "ints": (np.int16(-3), np.uint8(7)),
        "flag": np.bool_(True),
        "z": 1 + 2j,
        "raw": b"\x01\xab",
        "nested": [{"x": float("-inf")}],
    }
    text = json.dumps(jsonable(data), allow_nan=False)
    assert _strict_loads(text) == {
        "1": 0.5,
        "arr": [1.0, None, None],
        "ints": [-3, 7],
        "flag": True,
        "z": [1.0, 2.0],
        "raw": "01ab",
        "nested": [{"x": None}],
    }


def test_plain_values_pass_unchanged():
    data = {"a": 1, "b": "text", "c": None, "d": [True, 2.5]}
    assert jsonable(data) == data
