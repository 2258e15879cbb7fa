"""Write :mod:`drive_link.link.od_names` (the object names as ``Literal`` types) from the EDS.

Run ``python -m drive_link.link._od_names_gen`` after the EDS changes (``--check``: exit 1 if the
checked-in module drifted; the unit tests run that check). The names are grouped by the Python
type :meth:`drive_link.Drive.read` returns for them (:meth:`drive_link.ObjectInfo.decode`):
REAL32 → float, integers → int, VISIBLE_STRING → str, DOMAIN → bytes.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from ._objects import ObjectInfo, default_table

__all__ = ["PATH", "main", "render"]

PATH = Path(__file__).with_name("od_names.py")
_GROUPS = (
    ("FloatName", "REAL32 objects: ``Drive.read`` returns a float (SI units per the OD)."),
    ("IntName", "Integer objects: ``Drive.read`` returns an int."),
    ("TextName", "VISIBLE_STRING objects: ``Drive.read`` returns a str."),
    ("BytesName", "DOMAIN objects: ``Drive.read`` returns bytes."),
)


def _group(o: ObjectInfo) -> str:
    if o.fmt:
        return "FloatName" if o.is_float else "IntName"
    return "TextName" if o.type_name == "VISIBLE_STRING" else "BytesName"


def render() -> str:
    """The text of :mod:`drive_link.link.od_names` for the shipped EDS."""
    names: dict[str, list[str]] = {g: [] for g, _ in _GROUPS}
    for o in sorted(default_table(), key=lambda o: (o.index, o.subindex)):
        if o.readable:
            names[_group(o)].append(o.name)
    out = [
        '"""Object names of the drive as ``Literal`` types, by the type a read returns.',
        "",
        "GENERATED from firmware_protocol/bldc_drive.eds by",
        "``python -m drive_link.link._od_names_gen``; do not edit.",
        ':meth:`drive_link.Drive.read` is overloaded on them: ``drive.read("measurements.speed")``',
        'is a float to a type checker.',
        '"""',
        "",
        "from typing import Literal",
        "",
        "__all__ = [" + ", ".join(f'"{g}"' for g, _ in sorted(_GROUPS)) + "]",
        "",
    ]
    for g, doc in _GROUPS:
        out.append(f"{g} = Literal[")
        out.extend(f'    "{n}",' for n in names[g])
        out.append("]")
        out.append(f'"""{doc}"""')
        out.append("")
    return "\n".join(out)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m drive_link.link._od_names_gen")
    parser.add_argument("--check", action="store_true", help="exit 1 if the module drifted")
    args = parser.parse_args(argv)
    text = render()
    if args.check:
        ok = PATH.exists() and PATH.read_text() == text
        if not ok:
            print(f"{PATH} drifted from the EDS: run python -m drive_link.link._od_names_gen")
        return 0 if ok else 1
    PATH.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
