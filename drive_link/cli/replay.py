"""``drive-link replay FILE``: a bus recording decoded offline
(:func:`drive_link.link._replay.replay_file`) as a summary, CSV files, trace files and a text
plot."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from ..errors import DriveError
from ..link._replay import replay_file
from ._common import _emit

__all__ = ["cmd_replay"]


def _write_csv(path: Path, cols: dict[str, np.ndarray], units: dict[str, str]) -> Path:
    from ..link.writers import column_header, write_csv

    names = list(cols)
    header = [column_header(n, units.get(n, "s" if n == "t" else ""), keep_empty=False)
              for n in names]  # fmt: skip
    return write_csv(path, header, [cols[n] for n in names])


def cmd_replay(args: argparse.Namespace) -> int:
    """``drive-link replay FILE [--csv OUT] [--trace-csv OUT] [--trace-png OUT] [--plot S...]``."""
    rep = replay_file(args.file, node=args.node)
    wanted = [f"--{k.replace('_', '-')}" for k in ("trace_csv", "trace_png") if getattr(args, k)]
    if wanted and not rep.traces:  # before anything is written: nothing half-made
        raise DriveError(
            f"{rep.path}: {' and '.join(wanted)} cannot be made: the recording holds no complete"
            f" trace upload (0x2102) of node {rep.node}"
        )
    wanted = [f"--{k}" for k in ("csv", "plot") if getattr(args, k)]
    if wanted and not rep.live.stats["frames"]:
        raise DriveError(
            f"{rep.path}: {' and '.join(wanted)} cannot be made: the recording holds no TPDO of"
            f" node {rep.node} (TPDOs flow in OPERATIONAL only; another node: --node)"
        )
    out = rep.summary()
    if args.csv:
        out["csv"] = str(_write_csv(Path(args.csv), rep.table(), rep.live.units))
    for key, path in (("trace_csv", args.trace_csv), ("trace_png", args.trace_png)):
        if not path:
            continue
        saved = []
        for i, tr in enumerate(rep.traces):
            p = Path(path)
            if len(rep.traces) > 1:
                p = p.with_name(f"{p.stem}_{i + 1}{p.suffix}")
            saved.append(str(tr.to_csv(p) if key == "trace_csv" else tr.to_png(p)))
        out[key] = saved
    plot: list[str] = []
    if args.plot:
        from .live_plot import render, resolve_signals

        sigs = resolve_signals(rep.live, args.plot)
        plot = render(rep.live, sigs, max(rep.duration, 1e-3), args.width, args.height)

    def text() -> str:
        lines = [
            f"{rep.path}: {rep.frames} frames in {rep.duration:.3f} s (node {rep.node})"
            + (f", {rep.error_frames} error frames" if rep.error_frames else "")
        ]
        for k, v in out["tpdo"].items():
            lines.append(
                f"  {k} {v['cob_id']}: {v['frames']} frames, {v['rate_hz']:.0f} Hz"
                f" (expected {v['expected_hz']}), dropped {v['dropped']}"
            )
        for n, s in out["signals"].items():
            lines.append(
                f"  {n} [{s['unit']}]: last {s['last']:.6g}, mean {s['mean']:.6g}, "
                f"{s['min']:.6g} .. {s['max']:.6g}"
            )
        for u in out["uploads"]:
            lines.append(
                f"  {u['kind']} upload {u['index']}:{u['subindex']} {u['bytes']} bytes"
                f" at {u['t']:.3f} s"
                + ("" if u["complete"] else f" INCOMPLETE (announced {u['size']}, CRC "
                   f"{'ok' if u['crc_ok'] else 'wrong' if u['crc_ok'] is False else 'none'})")
            )
        for tr in rep.traces:
            lines.append(
                f"  trace: {len(tr.t)} samples every {tr.dt * 1e6:g} µs, "
                f"channels {', '.join(tr.signals)}"
            )
        lines += [f"saved {out['csv']}"] if "csv" in out else []
        lines += [f"saved {p}" for p in out.get("trace_csv", []) + out.get("trace_png", [])]
        asked = [f"--{k.replace('_', '-')}" for k in ("trace_csv", "trace_png") if k in out]
        if asked and not rep.traces:
            lines.append(f"no trace upload in {rep.path}: nothing saved for {', '.join(asked)}")
        return "\n".join(lines + plot)

    if args.json and plot:
        out["plot"] = plot
    _emit(args, out, text)
    return 0
