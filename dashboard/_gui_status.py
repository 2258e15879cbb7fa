"""The status texts of the viser GUI (HTML/markdown strings, no GUI calls): the status block,
the plot legends with the freshness mark, and who is in control.

Units: rpm, A, ms (heartbeat age), % (bus load), frames/s (dropped).
"""

from __future__ import annotations

import html
import time

from dashboard._gui_field import fmt as _fmt

__all__ = ["DROP_WINDOW_S", "controller_text", "legend", "setpoints_text", "status_html"]

DROP_WINDOW_S = 5.0  #: dropped-frame rate over this window (s)


def setpoints_text(s: dict, latest: dict) -> str:
    """Speed and i_p with the setpoint of the mode in use only (speed mode: speed*; current
    mode: i_p*; an unknown mode: none), so no stale setpoint of another mode is shown."""
    mode = s.get("mode")
    speed = f"<b>speed</b> {_fmt(latest.get('measurements.speed'), '.1f')} rpm"
    i_p = f"<b>i_p</b> {_fmt(latest.get('measurements.i_p'), '.2f')} A"
    if mode == "speed":
        speed += f" (set {_fmt(s.get('speed_setpoint'), '.0f')})"
    elif mode == "current":
        i_p += f" (set {_fmt(s.get('current_setpoint'), '.1f')})"
    return f"{speed} · {i_p}"


def status_html(
    s: dict,
    latest: dict,
    rate: float | None,
    stale: bool,
    fresh_txt: str,
    stream: tuple[int, int, str | None] = (0, 0, None),
) -> str:
    """The status details under the bar: bus and node, speed and i_p with the setpoint of the
    mode in use, heartbeat age (s), bus load, dropped TPDO frames/s (``rate``, never
    negative), the age of each part of the state, EMCY and bus health.

    ``s`` is :meth:`Bench.state`, ``latest`` the newest live values, ``stream`` (errors,
    restarts, last error) of the plot thread. Always the same number of lines.
    """
    stream_errors, plot_restarts, last_stream_error = stream
    live = s.get("live") or {}
    load = live.get("bus_load")
    emcy = s.get("emcy") or []
    emcy_txt = (
        ", ".join(
            f"0x{int(e.get('code', 0)):04X} {e.get('text', '')}".strip() for e in emcy[-3:]
        )
        or "none"
    )
    hb = s.get("heartbeat_age_s")
    expected = sum(
        float(t.get("expected_hz") or 0.0) for t in (live.get("tpdo") or {}).values()
    )
    if rate is not None:
        rate = max(0.0, rate)
    share = f" ({100 * rate / expected:.1f} %)" if rate is not None and expected else ""
    e = html.escape
    ages = s.get("ages_s") or {}
    stale_parts = set(s.get("stale") or ())
    age_txt = " · ".join(
        (f"<span style='color:#b03a2e'>{k} {_fmt(v, '.1f')} s</span>" if k in stale_parts
         else f"{k} {_fmt(v, '.1f')} s")
        for k, v in ages.items()
    )
    fresh = f"<b>ages</b> {age_txt}"
    if stream_errors or plot_restarts:
        fresh += (
            f" <span title='{e(last_stream_error or '')}'>· stream recovered "
            f"{stream_errors} error(s), {plot_restarts} restart(s)</span>"
        )
    extra = []
    for key, label in (
        ("bus_state", "CAN"),
        ("bus_error_frames", "error frames"),
        ("store_status", "parameter store"),
        ("boots_seen", "boots seen"),
        ("supervision_rearmed_at", "supervision re-armed"),
    ):
        v = s.get(key)
        if v is not None:
            warn = (key == "bus_state" and v in ("ERROR_PASSIVE", "BUS_OFF")) or (
                key == "store_status" and v in ("damaged", "unreadable")
            )
            txt = f"<b>{label}</b> {e(str(v))}"
            extra.append(f"<span style='color:#b03a2e'>{txt}</span>" if warn else txt)
    drops = (
        f"<span title='TPDO frames that the drive&#39;s event timer promised but that did "
        f"not arrive, per second over the last {DROP_WINDOW_S:g} s (total since start: "
        f"{e(str(live.get('dropped', '–')))})'><b>dropped</b> "
        f"{_fmt(rate, '.1f')} frames/s{share}</span>"
    )
    lines = [
        f"<b>Bus</b> {e(str(s['bus']))} · <b>node</b> {s['node_id']}",
        setpoints_text(s, latest),
        f"<b>heartbeat</b> {_fmt(hb, '.2f')} s ago · "
        f"<b>bus load</b> {_fmt(load * 100 if load is not None else None, '.1f')} % · {drops}",
        fresh,
        f"<b>faults/EMCY</b> {e(emcy_txt)}",
    ]
    lines.append(" · ".join(extra) or "&nbsp;")  # always the same number of lines
    return "<div style='font-size:0.85em;line-height:1.35'>" + "<br>".join(lines) + "</div>"


def legend(
    names: tuple[str, str],
    unit: str,
    colors: tuple[str, str],
    fresh: str,
    stale: bool = False,
    tick: int = 0,
) -> str:
    """A live plot's legend line: the measurement (solid, strong) and its reference (dashed,
    muted), then the freshness badge (``fresh``: :func:`dashboard._gui_statusbar.fresh_badge`,
    red when the data or the page's updates stopped). Its classes let the bar's CSS grey the
    plot under it: at once when ``stale``, and by itself when no tick re-sent the legend for
    PAGE_STALE_S (the class alternating with ``tick`` restarts that timer)."""
    measured, ref = names
    sw = (
        f"<span style='color:{colors[0]};font-weight:bold'>━</span> {html.escape(measured)} "
        f"({unit}, measured) <span style='color:{colors[1]}'>╌</span> {html.escape(ref)} "
        f"({unit}, reference)"
    )
    cls = f"bench-legend bench-t{tick % 2}" + (" bench-plot-stale" if stale else "")
    return f"<div class='{cls}' style='font-size:0.8em'>{sw} · {fresh}</div>"


def controller_text(ctl: dict | None, yours: bool, gone: float | None) -> str:
    """Who controls the node (``ctl``: :meth:`Bench.state`'s controller), "(you)" when the page
    asking holds the lease (``yours``), and the s until a closed page's lease frees (``gone``)."""
    if not ctl:
        return "**In control:** nobody (your first action takes control)"
    you = " (you)" if yours else ""
    since = time.strftime("%H:%M:%S", time.localtime(ctl["since"]))
    txt = f"**In control:** {ctl['client']}{you} since {since}"
    if gone is not None:
        txt += f" · its page closed: control frees in {max(0.0, gone):.0f} s"
    return txt
