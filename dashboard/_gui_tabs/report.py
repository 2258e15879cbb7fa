"""Report tab: the commissioning report of :mod:`drive_link.workflows.report` (the paper's
experiments on the connected drive) run as a long action of the bench (progress bar, Cancel, the
drive put back as found by each experiment), with the verdicts shown and report.html / report.json
offered for download. The last report is kept per bench, so every browser can download it.

Units: as each metric states (A, rpm, s, Ω, H, %).
"""

from __future__ import annotations

import json
import weakref
from typing import Any

from dashboard._gui_page import Page
from dashboard._report_loader import report_module
from drive_link.workflows.report_ids import EXPERIMENT_IDS

__all__ = ["REPORT_IDS", "ReportTab"]

REPORT_DEADLINE_S = 600.0  #: the whole report gives up (and puts the drive back) after this, s
#: the experiments' ids in their order, from the light module: the tab is built without
#: importing drive_link.workflows.report, whose scipy imports cost 2-6 s of CPU on a loaded host
#: and held up the first page's plots (the first report imports it: dashboard._report_loader)
REPORT_IDS = EXPERIMENT_IDS
_LAST: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()  #: bench → its last Report


class ReportTab:
    """The Report tab of one page (the last report is kept per bench)."""

    def __init__(self, page: Page) -> None:
        self.page = page
        gui = page.gui
        gui.add_markdown(
            "The paper's experiments on this drive, each with its verdict (pass when the "
            "measurement agrees with the paper's equations within the tolerance). Each one says "
            "what it changes and puts the drive back as found, also on Cancel. About 40 s on "
            "the virtual drive."
        )
        self.rep_checks = {
            key: gui.add_checkbox(key.replace("_", " "), initial_value=True)
            for key in REPORT_IDS
        }
        self.rep_run = gui.add_button("Run report", color="blue")
        self.rep_dl = gui.add_button_group("Download report", ("HTML", "JSON"))
        self.rep_md = gui.add_markdown("", visible=False)
        self.rep_result = gui.add_markdown("")
        self.rep_run.on_click(page.action(self._run_report, self.rep_md))
        self.rep_dl.on_click(page.action(self._download_report, self.rep_md, needs_control=False))

    def _run_report(self, event: Any) -> str:
        from drive_link.workflows.steps import Hooks

        run_report = report_module().run_report

        only = [k for k, cb in self.rep_checks.items() if cb.value]
        if not only:
            raise ValueError("tick at least one experiment")
        said: list[str] = []
        with self.page.bench.long_action("report", REPORT_DEADLINE_S) as act:
            hooks = Hooks(progress=act.progress, sleep=act.sleep, say=said.append)
            rep = run_report(self.page.bench.drive, only, hooks)
        _LAST[self.page.bench] = rep
        rows = ["| experiment | verdict | s |", "|---|---|---|"]
        rows += [f"| {r.id} | **{r.verdict}** | {r.seconds:.1f} |" for r in rep.results]
        self.rep_result.content = "\n".join(rows)
        failed = sum(r.verdict == "fail" for r in rep.results)
        return (f"report done in {rep.drive['seconds']} s: {len(rep.results) - failed} of "
                f"{len(rep.results)} not failed; download it below")

    def _download_report(self, event: Any) -> None:
        from drive_link.workflows.report.html import render

        rep = _LAST.get(self.page.bench)
        if rep is None:
            raise ValueError("run the report first")
        if event.target.value == "HTML":
            data = render(rep).encode("utf-8")
            name = "report.html"
        else:
            data = json.dumps(rep.as_dict(), indent=1, allow_nan=False).encode("utf-8")
            name = "report.json"
        self.page.client.send_file_download(name, data, save_immediately=True)
