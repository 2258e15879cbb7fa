"""The one CSV writer and the one PNG writer of recorded data (traces, replays, captures,
report figures).

CSV: one header row, then one row per sample, every number as ``%.9g`` (float32 data exactly,
float64 to 9 significant digits). PNG: a matplotlib figure (Agg backend) saved once and closed.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "column_header",
    "csv_text",
    "header_with_units",
    "png_bytes",
    "write_csv",
    "write_png",
]


def column_header(name: str, unit: str, *, keep_empty: bool = True) -> str:
    """``"name [unit]"``; an empty unit gives ``"name []"`` or, without ``keep_empty``,
    ``"name"``."""
    return f"{name} [{unit}]" if unit or keep_empty else name


def csv_text(
    header: Sequence[str], columns: Sequence[Any], *, lineterminator: str = "\r\n"
) -> str:
    """CSV of ``columns`` (equal-length number sequences) under ``header`` (one name each)."""
    if len(header) != len(columns):
        raise ValueError(f"{len(header)} header names for {len(columns)} columns")
    buf = io.StringIO(newline="")
    w = csv.writer(buf, lineterminator=lineterminator)
    w.writerow(list(header))
    for row in zip(*(np.asarray(c) for c in columns), strict=True):
        w.writerow([f"{x:.9g}" for x in row])
    return buf.getvalue()


def write_csv(
    path: str | Path, header: Sequence[str], columns: Sequence[Any], **kw: str
) -> Path:
    """:func:`csv_text` written to ``path``; returns the path."""
    path = Path(path)
    with path.open("w", newline="") as fh:
        fh.write(csv_text(header, columns, **kw))
    return path


def png_bytes(fig: Any, *, dpi: float | None = None, tight: bool = True) -> bytes:
    """The PNG of a matplotlib figure (``tight``: ``tight_layout`` first); a pyplot figure is
    closed afterwards (a bare :class:`matplotlib.figure.Figure` needs no closing)."""
    if tight:
        fig.tight_layout()
    buf = io.BytesIO()
    if dpi is None:
        fig.savefig(buf, format="png")
    else:
        fig.savefig(buf, format="png", dpi=dpi)
    if getattr(fig.canvas, "manager", None) is not None:  # made by pyplot
        import matplotlib.pyplot as plt

        plt.close(fig)
    return buf.getvalue()


def write_png(path: str | Path, fig: Any, *, dpi: float | None = None, tight: bool = True) -> Path:
    """:func:`png_bytes` written to ``path``; returns the path."""
    path = Path(path)
    path.write_bytes(png_bytes(fig, dpi=dpi, tight=tight))
    return path


def header_with_units(
    names: Sequence[str], units: Mapping[str, str], *, keep_empty: bool = True
) -> list[str]:
    """:func:`column_header` of every name with its unit from ``units`` ("" if none)."""
    return [column_header(n, units.get(n, ""), keep_empty=keep_empty) for n in names]
