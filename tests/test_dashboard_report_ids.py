"""The Report tab lists drive_link.workflows.report's experiments without importing it (its scipy
imports held up the first page for 2-6 s): its copy of the ids must be the report's, in its
order."""

from __future__ import annotations

import subprocess
import sys


def test_report_tab_ids_are_the_reports():
    from dashboard._gui_tabs.report import REPORT_IDS
    from drive_link.workflows.report import EXPERIMENTS

    assert REPORT_IDS == tuple(EXPERIMENTS)  # (the report checks it at import too)


BUILD_TAB = """
import sys, contextlib, io, viser
from dashboard._gui_tabs.report import ReportTab
with contextlib.redirect_stdout(io.StringIO()):
    srv = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)

class Page:  # the page the tab is built on: its GUI, notices and action wrapper
    gui = srv.gui
    def action(self, fn, md, needs_control=True):
        return lambda event: None
    def md(self):
        return srv.gui.add_markdown("", visible=False)

ReportTab(Page())
print("IMPORTED", "drive_link.workflows.report" in sys.modules, "scipy.optimize" in sys.modules)
srv.stop()
"""


def test_building_the_report_tab_does_not_import_the_report():
    """In a process of its own: the Report tab built on a real viser server."""
    out = subprocess.run([sys.executable, "-c", BUILD_TAB], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    assert "IMPORTED False False" in out.stdout, out.stdout


def test_drive_link_parser_does_not_import_the_report():
    """Every ``drive-link`` command line builds the whole parser (``report --only`` names the
    experiments): importing the report there cost 0.97 s of the 1.0 s of ``drive-link --help``."""
    code = (
        "import sys; from drive_link.cli.main import build_parser; build_parser(); "
        "print('IMPORTED', 'drive_link.workflows.report' in sys.modules, 'scipy' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    assert "IMPORTED False False" in out.stdout, out.stdout


def test_a_started_dashboard_has_not_loaded_the_reports_libraries():
    """``drive-dashboard`` imports the report's scipy and matplotlib for its first report, not
    at start (about 1 CPU-s per dashboard): a running bench whose API answers has mapped no
    scipy or matplotlib extension module (/proc/PID/maps, the kernel's view of the process)."""
    import urllib.request
    from pathlib import Path

    from dashboard.browser import run_dashboard

    with run_dashboard(["--virtual", "--no-3d"]) as dash:
        with urllib.request.urlopen(f"{dash.api_url}/api/state", timeout=30) as r:
            assert r.status == 200
        maps = Path(f"/proc/{dash.proc.pid}/maps").read_text()
        assert "libpython" in maps or "python3" in maps, maps[:300]  # a real maps file
        loaded = sorted({line.split()[-1] for line in maps.splitlines()
                         if "/scipy/" in line or "/matplotlib/" in line})
        assert not loaded, loaded[:5]


LOAD_REPORT = """
import sys
sys.setswitchinterval(0.005)
from dashboard._report_loader import report_module
first = report_module()
import matplotlib
print("LOADED", first.__name__, first is report_module(), "scipy.optimize" in sys.modules,
      matplotlib.get_backend().lower(), sys.getswitchinterval())
"""


def test_the_first_report_loads_the_report_and_restores_the_switch_interval():
    """In a process of its own (the workers have the report imported already): the loader
    returns the report package, the same one on every call, with the Agg backend, and leaves
    the interpreter's GIL hand-over interval as it found it."""
    out = subprocess.run([sys.executable, "-c", LOAD_REPORT], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    assert "LOADED drive_link.workflows.report True True agg 0.005" in out.stdout, out.stdout
