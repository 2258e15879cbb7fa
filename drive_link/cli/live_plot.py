"""``drive-link live --plot SIGNAL...``: a live terminal plot of TPDO signals (moteus tview-like).

One panel per signal, stacked, the last ``--window`` s of the drive's TPDO streams
(:class:`~drive_link.link._live.LiveStreams`: i_p, speed from TPDO2, i_p_ref, speed_ref from TPDO3
…), each with its unit, latest value and range; a status line with the frame counts, the dropped
frames (estimated from the event-timer cadence, per TPDO) and the bus load.

On a terminal it is drawn with :mod:`curses` (stdlib): keys ``space`` quick stop (the plot goes
on, so the braking shows), ``q`` quick stop and quit, ``x`` quit leaving the drive as it is
(also Ctrl-C). With ``--frames N`` (or when stdout is not a terminal) N frames are printed as
text, one every 1/``--fps`` s — for scripts and tests.
"""

from __future__ import annotations

import argparse
import math
import shutil
import sys
import time
from collections.abc import Callable, Sequence
from typing import TextIO

import numpy as np

from ..errors import InvalidValue
from ..link._live import LiveStreams
from ..link.drive import Drive

__all__ = [
    "KEYS",
    "cmd_live_plot",
    "drive_state",
    "handle_key",
    "render",
    "render_parts",
    "resolve_signals",
    "run_curses",
    "run_text",
    "status_line",
]

#: Keys of the curses view and what they do.
KEYS = {" ": "quick stop", "q": "quick stop and quit", "x": "quit"}
_MARK = "*"
_SPAN = "|"


def resolve_signals(live: LiveStreams, wanted: Sequence[str]) -> list[str]:
    """Full live-signal names for ``wanted`` (``i_p`` = ``measurements.i_p``); a name the drive
    does not stream raises :class:`InvalidValue` listing the streamed ones."""
    have = live.signals
    out = []
    for w in wanted:
        for name in (w, f"measurements.{w}"):
            if name in have:
                out.append(name)
                break
        else:
            short = ", ".join(n.removeprefix("measurements.") for n in have)
            raise InvalidValue(f"{w!r} is not streamed by the drive's TPDOs (streamed: {short})")
    return out


def _fmt(v: float) -> str:
    return "nan" if not math.isfinite(v) else f"{v:.4g}"


def _axis(v: float, span: float) -> str:
    """An axis label with the digits the span needs (two significant ones of the span)."""
    dec = max(0, min(6, 1 - math.floor(math.log10(span)))) if span > 0 else 0
    text = f"{v:.{dec}f}"
    return text if len(text) <= 10 else f"{v:.3g}"


def _panel(
    t: np.ndarray,
    y: np.ndarray,
    name: str,
    unit: str,
    width: int,
    height: int,
    t_end: float,
    seconds: float,
) -> list[str]:
    """One signal: a header line and ``height`` rows, time across (``seconds`` s ending at
    ``t_end``), per column the sample range drawn as ``|`` and the last sample as ``*``."""
    label_w = 10
    cols = max(10, width - label_w - 1)
    ok = np.isfinite(y)
    t, y = t[ok], y[ok]
    latest = float(y[-1]) if len(y) else float("nan")
    head = f"{name.removeprefix('measurements.')} [{unit}]  now {_fmt(latest)}"
    if not len(y):
        return [head + "  (no frames yet)"] + [" " * label_w + "|"] * height
    lo, hi = float(y.min()), float(y.max())
    # at least 2 % of the value's size (5 % for a flat line), so that noise of a steady signal
    # (1200 ± 0.3 rpm) stays a line instead of filling the panel
    least = max(abs(lo), abs(hi)) * (0.02 if hi > lo else 0.1) or 1e-3
    if hi - lo < least:
        mid = (hi + lo) / 2
        lo, hi = mid - least / 2, mid + least / 2
    head += f"  min {_fmt(float(y.min()))}  max {_fmt(float(y.max()))}"
    grid = [[" "] * cols for _ in range(height)]
    col = np.clip(((t - (t_end - seconds)) / seconds * cols).astype(int), 0, cols - 1)
    row = np.clip(((hi - y) / (hi - lo) * (height - 1)).round().astype(int), 0, height - 1)
    # t is increasing, so each column's samples are one run: its range and its last sample
    starts = np.flatnonzero(np.r_[True, col[1:] != col[:-1]])
    ends = np.r_[starts[1:], len(col)] - 1
    lows = np.minimum.reduceat(row, starts)
    highs = np.maximum.reduceat(row, starts)
    for c, r0, r1, last in zip(col[starts], lows, highs, row[ends], strict=True):
        for r in range(int(r0), int(r1) + 1):
            grid[r][c] = _SPAN
        grid[int(last)][c] = _MARK
    lines = [head]
    for r in range(height):
        label = _axis(hi, hi - lo) if r == 0 else _axis(lo, hi - lo) if r == height - 1 else ""
        lines.append(f"{label:>{label_w}}|" + "".join(grid[r]))
    return lines


def render_parts(
    live: LiveStreams,
    signals: Sequence[str],
    seconds: float = 5.0,
    width: int = 100,
    height: int = 24,
) -> tuple[list[list[str]], list[str]]:
    """(panels, footer): one list of lines per signal (full names, see
    :func:`resolve_signals`), sharing ``height`` rows, the last ``seconds`` s across ``width``
    columns; the footer is the time axis and the status line."""
    streams = live.streams(seconds)
    units = live.units
    t_end = max((float(t[-1]) for t, _ in streams.values() if len(t)), default=time.time())
    rows = max(3, (height - 2) // max(1, len(signals)) - 1)
    panels = []
    for name in signals:
        t, y = streams.get(name, (np.zeros(0), np.zeros(0)))
        keep = t >= t_end - seconds
        panels.append(
            _panel(t[keep], y[keep], name, units.get(name, ""), width, rows, t_end, seconds)
        )
    footer = [f"{'':>10}+{'-' * max(10, width - 11)}  {seconds:g} s", status_line(live)]
    return panels, footer


def render(
    live: LiveStreams,
    signals: Sequence[str],
    seconds: float = 5.0,
    width: int = 100,
    height: int = 24,
) -> list[str]:
    """The plot as text lines (see :func:`render_parts`)."""
    panels, footer = render_parts(live, signals, seconds, width, height)
    return [line for p in panels for line in p] + footer


def status_line(live: LiveStreams) -> str:
    """Frames, dropped frames per TPDO and the bus load."""
    st = live.stats
    per = "  ".join(
        f"{k} {v['frames']} fr/{v['dropped']} dropped" for k, v in sorted(st["tpdo"].items())
    )
    load = st.get("bus_load")
    bus = f"  bus {100 * load:.1f} %" if load is not None else ""
    return f"dropped {st['dropped']} of {st['frames'] + st['dropped']}  ({per}){bus}"


def handle_key(key: str, drive: Drive, timeout: float = 3.0) -> tuple[bool, str | None]:
    """Act on one key of the curses view: returns (quit?, message)."""
    if key in (" ", "q"):
        try:
            state = drive.quick_stop(timeout=timeout)
            msg = f"quick stop: {state}"
        except Exception as exc:  # shown in the view; 'x' still quits
            msg = f"quick stop failed: {str(exc).splitlines()[0] if str(exc) else exc!r}"
        return key == "q", msg
    if key == "x":
        return True, None
    return False, None


def run_text(
    live: LiveStreams,
    signals: Sequence[str],
    frames: int,
    fps: float = 10.0,
    seconds: float = 5.0,
    width: int = 100,
    height: int = 24,
    out: TextIO | None = None,
    sleep: Callable[[float], None] = time.sleep,
) -> None:
    """Print ``frames`` renderings, one every 1/``fps`` s, each after a ``--- frame k`` line."""
    out = out or sys.stdout
    for k in range(frames):
        sleep(1.0 / fps)
        lines = render(live, signals, seconds, width, height)
        out.write(f"--- frame {k + 1}/{frames}\n" + "\n".join(lines) + "\n")
        out.flush()


def run_curses(
    drive: Drive, signals: Sequence[str], fps: float = 10.0, seconds: float = 5.0
) -> str | None:
    """The interactive view until ``q``/``x``/Ctrl-C; returns the last message (quick stop)."""
    import curses

    live = drive.live
    result: dict[str, str | None] = {"msg": None}

    def loop(scr: curses.window) -> None:
        curses.curs_set(0)
        scr.nodelay(True)
        colours = []
        if curses.has_colors():
            curses.start_color()
            curses.use_default_colors()
            for i, c in enumerate(
                (curses.COLOR_GREEN, curses.COLOR_CYAN, curses.COLOR_YELLOW, curses.COLOR_MAGENTA)
            ):
                curses.init_pair(i + 1, c, -1)
                colours.append(curses.color_pair(i + 1))
        period = 1.0 / fps
        while True:
            h, w = scr.getmaxyx()
            panels, footer = render_parts(live, signals, seconds, w - 1, h - 2)
            keys = "  ".join(f"[{'space' if k == ' ' else k}] {v}" for k, v in KEYS.items())
            footer.append((result["msg"] or drive_state(drive)) + "   " + keys)
            scr.erase()
            rows = [(line, i) for i, p in enumerate(panels) for line in p]
            rows += [(line, -1) for line in footer]
            for y, (line, i) in enumerate(rows[: h - 1]):
                attr = colours[i % len(colours)] if colours and i >= 0 else 0
                try:
                    scr.addstr(y, 0, line[: w - 1], attr)
                except curses.error:
                    pass
            scr.refresh()
            t_next = time.monotonic() + period
            while time.monotonic() < t_next:
                ch = scr.getch()
                if ch == -1:
                    time.sleep(0.02)
                    continue
                quit_, msg = handle_key(chr(ch) if 0 <= ch < 256 else "", drive)
                if msg:
                    result["msg"] = msg
                if quit_:
                    return

    try:
        curses.wrapper(loop)
    except KeyboardInterrupt:
        pass
    return result["msg"]


def drive_state(drive: Drive) -> str:
    """NMT state and the 402 state from the statusword in the TPDOs (no SDO round trip, so a
    silent drive cannot stall the view)."""
    from ..link.cia402 import state_from_statusword

    sw = drive.live.latest().get("statusword", float("nan"))
    state = state_from_statusword(int(sw)) if math.isfinite(sw) else "402 state ?"
    return f"{drive.nmt_state}, {state}"


def cmd_live_plot(args: argparse.Namespace, d: Drive) -> int:
    """``live --plot SIGNAL... [--frames N] [--fps F] [--window S]``."""
    if not args.fps > 0 or not math.isfinite(args.fps):
        raise InvalidValue(f"--fps {args.fps}: must be > 0")
    if not args.window > 0 or not math.isfinite(args.window):
        raise InvalidValue(f"--window {args.window}: must be > 0 s")
    live = d.live
    signals = resolve_signals(live, args.plot)
    nmt = d.nmt_state
    if nmt != "OPERATIONAL" and not getattr(args, "json", False):
        print(
            f"drive-link: note: node {d.node_id} is {nmt}: TPDOs flow only in OPERATIONAL "
            "(drive-link nmt start)",
            file=sys.stderr,
        )
    size = shutil.get_terminal_size((100, 24))
    width = args.width or size.columns
    height = args.height or size.lines
    if args.frames is not None:
        if args.frames < 1:
            raise InvalidValue(f"--frames {args.frames}: must be >= 1")
        run_text(live, signals, args.frames, args.fps, args.window, width, height)
        return 0
    if not (sys.stdout.isatty() and sys.stdin.isatty()):
        raise InvalidValue("the live plot needs a terminal; use --frames N for text output")
    msg = run_curses(d, signals, args.fps, args.window)
    if msg:
        print(msg)
    return 0
