"""The viser GUI's tabs, one module each, as mixins of :class:`dashboard._gui_panel.Panel`.

plots: the main area (Live, Capture, Loop), docked left and wide; speed, current, tuning,
identify, captures, config, bus: the control panel's tabs (docked right). Each module owns its
widgets and their callbacks; the panel core (:mod:`dashboard._gui_panel`) owns the lease,
notices and status.
"""

from dashboard._gui_tabs.bus import BusTab
from dashboard._gui_tabs.captures import CapturesTab
from dashboard._gui_tabs.config import ConfigTab
from dashboard._gui_tabs.current import CurrentTab
from dashboard._gui_tabs.identify import IdentifyTab
from dashboard._gui_tabs.plots import PlotArea
from dashboard._gui_tabs.report import ReportTab
from dashboard._gui_tabs.speed import SpeedTab, parse_sequence
from dashboard._gui_tabs.tuning import TuningTab

__all__ = [
    "BusTab",
    "CapturesTab",
    "ConfigTab",
    "CurrentTab",
    "IdentifyTab",
    "PlotArea",
    "ReportTab",
    "SpeedTab",
    "TuningTab",
    "parse_sequence",
]
