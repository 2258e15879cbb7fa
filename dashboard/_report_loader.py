"""The Report tab's experiments (:mod:`drive_link.workflows.report`), imported by the first report.

The report imports scipy (``signal``, ``optimize``) and draws its figures with matplotlib: about
1 CPU-s (0.75 s on the idle 2-core host, 2-6 s at load 8), which every dashboard used to pay at
start although most never run a report. The first report imports them instead. Meanwhile the
interpreter hands the GIL to a waiting thread after 0.5 ms instead of 5 ms, so the API and the
live plots keep answering while the import runs; its longest single hold (an extension module's
initialisation, ~55 ms on the idle host) is not shortened by that.
"""

from __future__ import annotations

import sys
import threading
from types import ModuleType

__all__ = ["SWITCH_INTERVAL_S", "report_module"]

#: the GIL hand-over interval while the report is imported, s (the interpreter's default: 5 ms)
SWITCH_INTERVAL_S = 5e-4

_lock = threading.Lock()
_loaded: list[ModuleType] = []  # the imported package, once it is complete


def report_module() -> ModuleType:
    """:mod:`drive_link.workflows.report`, imported on the first call (with matplotlib's Agg
    backend: no display), with a short GIL hand-over interval while it imports."""
    if _loaded:
        return _loaded[0]
    with _lock:
        if not _loaded:
            old = sys.getswitchinterval()
            sys.setswitchinterval(min(old, SWITCH_INTERVAL_S))
            try:
                import matplotlib

                matplotlib.use("Agg", force=False)  # the report's figures: no display
                import matplotlib.pyplot

                import drive_link.workflows.report as report
            finally:
                sys.setswitchinterval(old)
            _loaded.append(report)
    return _loaded[0]
