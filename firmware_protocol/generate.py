"""Regenerate the files derived from the EDS: the DSP header and the Markdown OD reference.

Usage::

    python -m firmware_protocol.generate            # rewrite bldc_drive_od.h and OD.md
    python -m firmware_protocol.generate --check    # exit 1 if either drifted from the EDS
    python -m firmware_protocol.generate --strict-eds out.eds   # copy without custom keys

Both outputs are pure functions of the EDS (through :func:`firmware_protocol.od.load_od`) and the
cross-object constraints of :mod:`firmware_protocol.constraints`; nothing else (no dates) goes
in, so a re-run on an unchanged EDS is byte-identical.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from ._c_header import HEADER_NAME, render_header
from ._markdown import MARKDOWN_NAME, render_markdown
from ._strict_eds import CIA306_OBJECT_KEYS, render_strict_eds
from .od import EDS_PATH, ObjectDictionaryView, load_od

__all__ = [
    "CIA306_OBJECT_KEYS",
    "HEADER_NAME",
    "MARKDOWN_NAME",
    "main",
    "outputs",
    "render_header",
    "render_markdown",
    "render_strict_eds",
]


def outputs(view: ObjectDictionaryView) -> dict[str, str]:
    """File name -> generated text."""
    return {HEADER_NAME: render_header(view), MARKDOWN_NAME: render_markdown(view)}


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``python -m firmware_protocol.generate``; returns the exit status."""
    parser = argparse.ArgumentParser(
        prog="python -m firmware_protocol.generate",
        allow_abbrev=False,
        description="Regenerate bldc_drive_od.h and OD.md from the EDS.",
    )
    parser.add_argument("--check", action="store_true", help="exit 1 if a file drifted")
    parser.add_argument("--eds", type=Path, default=EDS_PATH, help="EDS file (default: packaged)")
    parser.add_argument(
        "--out-dir", type=Path, default=EDS_PATH.parent, help="directory of the outputs"
    )
    parser.add_argument(
        "--strict-eds",
        type=Path,
        metavar="PATH",
        help="also write a copy of the EDS without the project's custom keys to PATH",
    )
    args = parser.parse_args(argv)
    try:
        view = load_od(args.eds)
        generated = outputs(view)
    except (OSError, ValueError, KeyError) as exc:
        print(f"error: cannot load {args.eds}: {' '.join(str(exc).split())}", file=sys.stderr)
        return 2
    if args.strict_eds is not None:
        try:
            strict = render_strict_eds(args.eds.read_text(encoding="utf-8"))
            args.strict_eds.write_text(strict, encoding="utf-8")
        except OSError as exc:
            print(f"error: cannot write {args.strict_eds}: {exc}", file=sys.stderr)
            return 2
        print(f"wrote {args.strict_eds}")
    drift = []
    for name, text in generated.items():
        path = args.out_dir / name
        current = path.read_text(encoding="utf-8") if path.exists() else None
        if current == text:
            continue
        if args.check:
            drift.append(name)
        else:
            path.write_text(text, encoding="utf-8")
            print(f"wrote {path}")
    if drift:
        print(
            f"drift: {', '.join(drift)} differ from {args.eds.name}; "
            "run `python -m firmware_protocol.generate`",
            file=sys.stderr,
        )
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
