"""dashboard._gui_cast: the patched viser cast gives exactly what viser's own method gives, for
every property hint of every viser message type (the oracle is viser 1.1.1's original method,
kept by the patch), on arrays, tuples of arrays, lists, scalars and colours."""

from __future__ import annotations

import dataclasses
import typing

import numpy as np
import pytest
import viser._messages as messages
from viser._assignable_props_api import AssignablePropsBase

from dashboard._gui_cast import install_fast_cast, installed_cast

pytestmark = pytest.mark.unit


def _same(a: object, b: object) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return (
            isinstance(a, np.ndarray)
            and isinstance(b, np.ndarray)
            and a.dtype == b.dtype
            and np.array_equal(a, b, equal_nan=a.dtype.kind in "fc")
        )
    if isinstance(a, tuple) and isinstance(b, tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    return type(a) is type(b) and a == b


def _outcome(fn, *args):
    try:
        return fn(*args)
    except Exception as exc:  # the same error type counts as the same outcome
        return ("raised", type(exc))


def test_fast_cast_equals_visers_cast_on_every_props_hint():
    install_fast_cast()
    install_fast_cast()  # idempotent
    fast = AssignablePropsBase._cast_value_recursive
    installed = installed_cast()
    assert installed is not None and installed[0] is fast
    original = installed[1]
    assert original is not fast
    assert original.__module__ == "viser._assignable_props_api"
    obj = object.__new__(AssignablePropsBase)

    class Viser(AssignablePropsBase):  # viser's own method, recursing into itself
        _cast_value_recursive = original

    oracle = object.__new__(Viser)
    rng = np.random.default_rng(7)
    values = [
        rng.random(5),
        rng.random(5).astype(np.float32),
        (rng.random(3), rng.random(3), rng.random(3)),
        [1, 2, 3],
        (1, 2, 3),
        (255, 0, 128),
        np.array([[0.1, 0.5, 1.0]]),
        "text",
        1.5,
        None,
    ]
    checked = 0
    for name in dir(messages):
        cls = getattr(messages, name)
        if not (isinstance(cls, type) and dataclasses.is_dataclass(cls) and name.endswith("Props")):
            continue
        for prop, hint in typing.get_type_hints(cls).items():
            for v in values:
                want = _outcome(oracle._cast_value_recursive, hint, v, prop)
                got = _outcome(obj._cast_value_recursive, hint, v, prop)
                assert _same(want, got), (name, prop, hint, v, want, got)
                checked += 1
    assert checked > 1000  # every props class of viser was seen
