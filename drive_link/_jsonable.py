"""Python values (numpy included) as JSON-safe values: the one converter of the project.

``json.dumps`` refuses numpy scalars and arrays and writes ``NaN``/``Infinity``, which is not
JSON (RFC 8259 §6) and which browsers' ``JSON.parse`` rejects. :func:`jsonable` turns, recursively:

- numpy arrays into lists, numpy scalars into ``int``/``float``/``bool``;
- non-finite floats (NaN, ±inf) into ``None``;
- complex numbers into ``[real, imag]``; ``bytes`` into a hex string;
- dict keys into strings, tuples into lists.

Everything else is returned as it is.
"""

from __future__ import annotations

import math
from typing import Any, TypeVar, overload

import numpy as np

__all__ = ["jsonable"]

_K = TypeVar("_K")
_V = TypeVar("_V")
_T = TypeVar("_T")


# Generic overloads: a dict or list whose items are ``Any`` still gets its precise return type
# (with a plain ``object`` fallback, mypy would call the call ambiguous and return ``Any``).
@overload
def jsonable(x: dict[_K, _V]) -> dict[str, Any]: ...
@overload
def jsonable(x: list[_T]) -> list[Any]: ...
@overload
def jsonable(x: tuple[_T, ...]) -> list[Any]: ...
@overload
def jsonable(x: _T) -> Any: ...


def jsonable(x: object) -> Any:
    """``x`` with every part JSON-safe (see the module doc): a ``dict`` comes back as a
    ``dict`` with ``str`` keys, a list or tuple as a ``list``."""
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return jsonable(x.tolist())
    if isinstance(x, np.generic):
        x = x.item()
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, complex):
        return [jsonable(x.real), jsonable(x.imag)]
    if isinstance(x, bytes | bytearray):
        return bytes(x).hex()
    return x
