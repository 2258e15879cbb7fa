"""Objects by what a user types: a name (``current_controller.L_c``), an index (``0x6041``,
``0x2010:2``, ``0x2010sub2``, ``24641``) or a search pattern (``objects L_c``, ``objects 0x20*``).

:func:`select` returns the one :class:`~drive_link.link._objects.ObjectInfo` meant, or raises
:class:`~drive_link.errors.UnknownObject` in one line; :func:`search` lists the objects a
pattern matches (a case-insensitive substring or shell pattern of the name, the index text
``0x2010:02`` or the description) and :func:`describe` gives one object's row for
``drive-link objects``: name, index:sub, type, unit, limits, access.
"""

from __future__ import annotations

import fnmatch
import re
from typing import Any

from ..errors import UnknownObject
from ._objects import ObjectInfo, ObjectTable, default_table

__all__ = ["describe", "index_text", "search", "select", "table_text"]

_INDEX = re.compile(
    r"^(?P<index>0[xX][0-9a-fA-F]{1,4}|\d{1,5})"
    r"(?:(?::|sub|\.)(?P<sub>0[xX][0-9a-fA-F]{1,2}|[0-9a-fA-F]{1,2}))?$"
)


def _index_sub(m: re.Match) -> tuple[int, int | None]:
    """(index, sub-index or None) of an :data:`_INDEX` match: a hex index takes a hex sub-index
    (``0x2010:0A`` = sub 10, as CiA 306 writes them), a decimal index a decimal one."""
    hexa = m["index"].lower().startswith("0x")
    index = int(m["index"], 16 if hexa else 10)
    s = m["sub"]
    if s is None:
        return index, None
    if s.lower().startswith("0x"):
        return index, int(s, 16)
    return index, int(s, 16 if hexa else 10)


def index_text(obj: ObjectInfo) -> str:
    """``0xIIII:SS`` of ``obj`` (the CiA 306 spelling without the ``sub``)."""
    return f"0x{obj.index:04X}:{obj.subindex:02X}"


def select(text: str, table: ObjectTable | None = None) -> ObjectInfo:
    """The object ``text`` names: an OD name or ``INDEX[:SUB]`` (hex with 0x or decimal; a bare
    index means sub-index 0, or the record's only readable sub-object 1 when sub 0 is its count)."""
    table = table or default_table()
    s = text.strip()
    m = _INDEX.match(s)
    if m is None:
        return table[s]
    index, sub = _index_sub(m)
    sub = sub or 0
    obj = table.by_index(index, sub)
    if obj is None:
        subs = sorted(o.subindex for o in table if o.index == index)
        if subs:
            have = ", ".join(f"{x}" for x in subs[:12])
            raise UnknownObject(f"object 0x{index:04X} has no sub-index {sub} (it has {have})")
        raise UnknownObject(f"no object at index 0x{index:04X} in the drive's dictionary")
    return obj


def search(pattern: str | None = None, table: ObjectTable | None = None) -> list[ObjectInfo]:
    """Objects whose name, ``0xIIII:SS`` index text or description match ``pattern`` (case-
    insensitive substring, or a shell pattern when it holds ``*?[``); all when None/empty.
    An exact index (``0x2010``) lists every sub-object of that index."""
    table = table or default_table()
    objs = sorted(table, key=lambda o: (o.index, o.subindex))
    if not pattern:
        return objs
    p = pattern.strip().lower()
    m = _INDEX.match(p)
    if m is not None and p.startswith("0x"):
        index, sub = _index_sub(m)
        return [o for o in objs if o.index == index and (sub is None or o.subindex == sub)]
    glob = any(c in p for c in "*?[")

    def hit(o: ObjectInfo) -> bool:
        fields = (o.name.lower(), index_text(o).lower())
        if glob:
            return any(fnmatch.fnmatchcase(f, p) for f in fields)
        return any(p in f for f in fields) or p in o.description.lower()

    return [o for o in objs if hit(o)]


def _limit(x: Any) -> str:
    return "" if x is None else f"{x:g}" if isinstance(x, float) else str(x)


def describe(obj: ObjectInfo) -> dict[str, Any]:
    """One object's row: ``name``, ``index`` (``0xIIII:SS``), ``type``, ``unit``, ``low``,
    ``high`` (None = the type's range), ``access``, ``default``, ``enum`` and ``description``."""
    return {
        "name": obj.name,
        "index": index_text(obj),
        "type": obj.type_name,
        "unit": obj.unit if obj.unit != "1" else "",
        "low": obj.low,
        "high": obj.high,
        "access": obj.access,
        "default": obj.default,
        "enum": {str(v): label for v, label in obj.enum} or None,
        "description": obj.description,
    }


def table_text(objs: list[ObjectInfo]) -> str:
    """The rows of :func:`describe` as an aligned text table (one line per object)."""
    rows = [("INDEX", "NAME", "TYPE", "UNIT", "LIMITS", "ACCESS")]
    for o in objs:
        d = describe(o)
        if o.enum:
            lim = "|".join(f"{v}={label}" for v, label in o.enum)
        elif d["low"] is None and d["high"] is None:
            lim = ""
        else:
            lim = f"{_limit(d['low'])}..{_limit(d['high'])}"
        rows.append((d["index"], d["name"], d["type"], d["unit"], lim, d["access"]))
    w = [max(len(r[i]) for r in rows) for i in range(len(rows[0]) - 1)]
    return "\n".join(
        "  ".join(c.ljust(w[i]) for i, c in enumerate(r[:-1])) + "  " + r[-1] for r in rows
    )

