"""The status bar of the viser GUI (HTML/CSS strings, no GUI calls): coloured badges for the
NMT and CiA 402 state, the mode, the fault and the freshness of the data, pinned at the top of
the control panel together with Quick stop (it stays in view however far the panel scrolls).

Freshness is judged twice: by the server (the age of the newest sample, the heartbeat and the
402 state, :mod:`dashboard._known`) and by the page itself: every status tick re-sends the
freshness badge, which restarts a CSS animation; when no tick arrives for :data:`PAGE_STALE_S`
(the dashboard's loops, its process or the connection stalled), the animation ends and the
badge turns red, counting the seconds since the last tick. No script runs: viser shows HTML
without executing it. Units: s.
"""

from __future__ import annotations

import html
from typing import Any

__all__ = [
    "BAR_CSS",
    "PAGE_STALE_S",
    "badge",
    "badges_html",
    "fresh_badge",
    "mode_badge",
    "notices_css",
    "readout_html",
    "state_badge",
]

PAGE_STALE_S = 1.0  #: the page turns stale by itself when no status tick came for this (s)

GREEN, RED, AMBER, GREY, BLUE = "#1e8449", "#b03a2e", "#b9770e", "#7f8c8d", "#1f618d"

#: CSS of the bar: the pinned block (the folder holding the bar, found through the marker
#: class), the badges, the page-side stale switch (a restarted animation per tick) and the
#: live plots greyed under a stale legend (at once when the server says so; by themselves
#: when the legend's tick class stopped alternating: a changed animation name restarts it).
BAR_CSS = f"""<style>
div[style*="overflow: hidden; min-height: 0px"]:has(.bench-statusbar) {{
  overflow: clip !important; }}
div[style*="padding-top: var(--mantine-spacing-xs)"] > .mantine-Paper-root:has(.bench-statusbar) {{
  position: sticky; top: 8px; z-index: 20; background: var(--mantine-color-body, #fff);
  box-shadow: 0 0 0 10px var(--mantine-color-body, #fff), 0 12px 6px -4px rgba(0,0,0,0.15); }}
.bench-statusbar {{ display: flex; flex-wrap: wrap; gap: 4px; align-items: center; }}
.bench-badge {{ display: inline-block; color: #fff; border-radius: 4px; padding: 1px 6px;
  font-size: 0.8em; font-weight: 600; line-height: 1.5; white-space: nowrap; }}
.bench-fresh {{ position: relative; display: inline-block; }}
@property --bench-s {{ syntax: '<integer>'; inherits: false; initial-value: 0; }}
@keyframes bench-count {{ from {{ --bench-s: 0; }} to {{ --bench-s: 36000; }} }}
@keyframes bench-show {{ to {{ visibility: visible; }} }}
.bench-fresh .bench-dead {{ position: absolute; left: 0; top: 0; right: 0; bottom: 0;
  visibility: hidden; background: {RED}; overflow: visible; min-width: max-content;
  animation: bench-show 0s linear {PAGE_STALE_S}s forwards, bench-count 36000s linear forwards;
  counter-reset: bench-s var(--bench-s); }}
.bench-fresh .bench-dead::after {{
  content: "STALE · page not updated for " counter(bench-s) " s"; }}
.mantine-Notification-root {{ font-size: 0.8em; }}
div:has(> .bench-plot-stale) + div .uplot {{ opacity: 0.35; filter: grayscale(1); }}
@keyframes bench-dim-a {{ to {{ opacity: 0.35; filter: grayscale(1); }} }}
@keyframes bench-dim-b {{ to {{ opacity: 0.35; filter: grayscale(1); }} }}
div:has(> .bench-t0) + div .uplot {{ animation: bench-dim-a 0s linear {PAGE_STALE_S}s forwards; }}
div:has(> .bench-t1) + div .uplot {{ animation: bench-dim-b 0s linear {PAGE_STALE_S}s forwards; }}
</style>"""


def notices_css(control_px: float, plot_px: float, strip_px: float) -> str:
    """CSS that puts viser's notices (software WebGL, uploads) into the canvas strip between
    the plots and the controls, under the readout, where they cover nothing: viser scales the
    two docked regions (requested ``plot_px`` and ``control_px``, together wider than the
    window) to the window minus its ``strip_px`` canvas, so the strip's right edge sits
    (100vw − strip) × control / (plot + control) from the window's right edge."""
    share = control_px / (plot_px + control_px)
    return (
        "<style>.mantine-Notifications-root { top: auto !important; bottom: 8px !important;"
        f" left: auto !important; right: calc((100vw - {strip_px}px) * {share:.5f}) !important;"
        f" width: {strip_px}px !important; max-width: {strip_px}px !important;"
        " padding: 0 !important; }</style>"
    )


def readout_html(s: dict[str, Any], latest: dict[str, float]) -> str:
    """The readout column in the strip: speed and i_p as large numbers with the setpoint of
    the mode in use only (rpm, A)."""
    from dashboard._gui_field import fmt

    mode = s.get("mode")

    def big(name: str, value: Any, spec: str, unit: str, color: str, setpoint: str) -> str:
        return (
            f"<div style='color:#555'>{name}</div>"
            f"<div style='font-size:1.6em;font-weight:700;color:{color};line-height:1.1'>"
            f"{fmt(value, spec)}</div><div style='color:#555'>{unit}{setpoint}</div>"
        )

    sp = f" · set {fmt(s.get('speed_setpoint'), '.0f')}" if mode == "speed" else ""
    ip = f" · set {fmt(s.get('current_setpoint'), '.1f')}" if mode == "current" else ""
    live = s.get("live") or {}
    load = live.get("bus_load")
    hb = s.get("heartbeat_age_s")
    ages = s.get("ages_s") or {}
    emcy = s.get("emcy") or []

    def line(name: str, value: str) -> str:
        return f"<div style='color:#555;margin-top:5px'>{name}<br><b>{value}</b></div>"

    small = (
        line("heartbeat", f"{fmt(hb, '.2f')} s ago")
        + line("newest data", f"{fmt(ages.get('live'), '.2f')} s old")
        + line("bus load", f"{fmt(load * 100 if load is not None else None, '.0f')} %")
        + line("EMCY", f"{len(emcy)} seen" if emcy else "none")
        + (line("load torque", f"{fmt(s.get('T_load'), '.3g')} N·m")
           if s.get("virtual") else "")
    )
    return (
        "<div style='font-size:0.8em;line-height:1.3'>"
        + big("speed", latest.get("measurements.speed"), ".0f", "rpm", "#1a5fb4", sp)
        + "<div style='height:6px'></div>"
        + big("i_p", latest.get("measurements.i_p"), ".1f", "A", "#1e7b34", ip)
        + small
        + "</div>"
    )


def badge(text: str, color: str, title: str = "") -> str:
    """One coloured badge (``text`` escaped)."""
    t = f" title='{html.escape(title)}'" if title else ""
    return (
        f"<span class='bench-badge' style='background:{color}'{t}>{html.escape(text)}</span>"
    )


def _age(age: float | None) -> str:
    return "never read" if age is None else f"{age:.1f} s old"


def state_badge(state: str | None, age: float | None, stale: bool) -> str:
    """The CiA 402 state: green enabled, red fault / quick stop, amber on the way, grey off."""
    if state is None:
        return badge("402 unknown", GREY, "no statusword yet")
    color = {
        "OPERATION ENABLED": GREEN,
        "FAULT": RED,
        "FAULT REACTION ACTIVE": RED,
        "QUICK STOP ACTIVE": RED,
        "SWITCHED ON": AMBER,
        "READY TO SWITCH ON": AMBER,
    }.get(state, GREY)
    if stale:
        return badge(f"{state} ({_age(age)})", GREY, "the statusword stopped arriving")
    return badge(state, color, "CiA 402 state (statusword 0x6041)")


def mode_badge(mode: str | None, age: float | None, stale: bool) -> str:
    if mode is None:
        return badge("mode ?", GREY, "not read yet")
    txt = f"{mode} mode" + (f" ({_age(age)})" if stale else "")
    return badge(txt, GREY if stale else BLUE, "modes of operation display 0x6061")


def fault_badge(s: dict[str, Any]) -> str:
    """Red with the newest EMCY's text while the drive is in FAULT, else green "no fault"."""
    state = s.get("state")
    emcy = s.get("emcy") or []
    if state in ("FAULT", "FAULT REACTION ACTIVE"):
        last = emcy[-1] if emcy else {}
        code = int(last.get("code", 0) or 0)
        txt = f"FAULT 0x{code:04X} {last.get('text', '')}".strip() if last else "FAULT"
        return badge(txt, RED, "Fault reset clears it once the cause is gone")
    if state is None:
        return badge("fault ?", GREY)
    return badge("no fault", GREEN)


def nmt_badge(nmt: str | None) -> str:
    color = {"OPERATIONAL": GREEN, "PRE-OPERATIONAL": AMBER}.get(str(nmt), RED)
    return badge(f"NMT {nmt or '?'}", GREY if nmt is None else color, "from the heartbeat")


def badges_html(s: dict[str, Any]) -> str:
    """The state badges (NMT, 402, mode, fault) of :meth:`Bench.state` ``s``."""
    ages = s.get("ages_s") or {}
    stale = set(s.get("stale") or ())
    return " ".join(
        (
            nmt_badge(s.get("nmt_state")),
            state_badge(s.get("state"), ages.get("statusword"), "statusword" in stale),
            mode_badge(s.get("mode"), ages.get("mode"), "mode" in stale),
            fault_badge(s),
        )
    )


def fresh_badge(stale: bool, text: str, tick: int) -> str:
    """The freshness badge: green with the data's age, red "STALE ..." when the server knows
    the data stopped, and red by itself on the page when no tick re-sent it for PAGE_STALE_S
    (``tick`` makes every tick's HTML differ, so the page re-creates it and restarts the
    animation)."""
    inner = badge(("⚠ " if stale else "● ") + text, RED if stale else GREEN)
    return (
        f"<span class='bench-fresh' data-tick='{tick}'>{inner}"
        "<span class='bench-badge bench-dead'></span></span>"
    )
