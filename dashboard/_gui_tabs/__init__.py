"""The viser GUI's control-panel tabs (docked right), one module each: speed, current, tuning,
identify, captures, config, bus, report; the plot area (Live, Capture, Loop, docked left and
wide) is :mod:`dashboard._gui_plots`. Each tab is one object built with the page it belongs to
(:class:`dashboard._gui_page.Page`): it owns its widgets, their callbacks and their state; the
panel (:mod:`dashboard._gui_panel`) composes them. Nothing is imported here, so that importing one
tab module does not import the others.
"""

#: the tab modules (``from dashboard._gui_tabs import *`` imports them)
__all__ = [
    "bus", "captures", "config", "current", "identify", "report", "speed", "tuning",
]
