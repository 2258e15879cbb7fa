"""One self-contained offline HTML page of a :class:`drive_link.workflows.report.Report`: inline
CSS, figures as base64 PNG data URLs, nothing loaded from anywhere."""

from __future__ import annotations

import html
from typing import Any, Protocol

from ._base import ExperimentResult

__all__ = ["ReportContents", "render"]


class ReportContents(Protocol):
    """What the page shows of a report (:class:`drive_link.workflows.report.Report` is one)."""

    @property
    def drive(self) -> dict[str, Any]: ...

    @property
    def results(self) -> list[ExperimentResult]: ...

    @property
    def inconsistencies(self) -> list[dict[str, Any]]: ...

_CSS = """
body{font-family:sans-serif;max-width:980px;margin:1em auto;color:#222}
table{border-collapse:collapse;margin:.4em 0}td,th{border:1px solid #ccc;padding:2px 6px;
font-size:13px;text-align:right}th{background:#eee}td.l{text-align:left}
.pass{background:#d7f5d7}.fail{background:#f9d0d0}.na{background:#eee;color:#666}
.badge{display:inline-block;padding:1px 8px;border-radius:8px;font-weight:bold}
img{max-width:100%}section{border-top:2px solid #ddd;margin-top:1.2em}
"""


def _cls(verdict: str) -> str:
    return {"pass": "pass", "fail": "fail"}.get(verdict, "na")


def _fmt(x: float | None) -> str:
    return "—" if x is None else f"{x:.5g}"


def render(rep: ReportContents) -> str:
    """The page as a string."""
    e = html.escape
    d = rep.drive
    out = [f"<!doctype html><html><head><meta charset='utf-8'><title>Commissioning report"
           f"</title><style>{_CSS}</style></head><body>",
           "<h1>Commissioning report</h1>",
           "<p>Valle et al., <i>Simple and Effective Digital Control of a Variable-Speed Low "
           "Inductance BLDC Motor Drive</i>, IEEE Access 2020: the paper's experiments on this "
           "drive. Verdict per metric: pass when |measured − model| ≤ tolerance.</p>",
           "<table>"]
    for k, v in d.items():
        out.append(f"<tr><th>{e(str(k))}</th><td class='l'>{e(str(v))}</td></tr>")
    out.append("</table><h2>Summary</h2><table><tr><th>experiment</th><th>paper</th>"
               "<th>verdict</th><th>s</th></tr>")
    for r in rep.results:
        out.append(f"<tr><td class='l'><a href='#{e(r.id)}'>{e(r.id)}</a></td>"
                   f"<td class='l'>{e(r.paper_ref)}</td><td class='{_cls(r.verdict)}'>"
                   f"{e(r.verdict)}</td><td>{r.seconds:.1f}</td></tr>")
    out.append("</table>")
    for r in rep.results:
        out.append(f"<section id='{e(r.id)}'><h2>{e(r.title)} <small>({e(r.id)}, "
                   f"{e(r.paper_ref)})</small> <span class='badge {_cls(r.verdict)}'>"
                   f"{e(r.verdict)}</span></h2>")
        if r.reason:
            out.append(f"<p><b>{e(r.reason)}</b></p>")
        if r.conditions:
            out.append(f"<p>Conditions: {e(r.conditions)}</p>")
        if r.metrics:
            out.append("<table><tr><th>metric</th><th>measured</th><th>model</th><th>paper</th>"
                       "<th>unit</th><th>tolerance</th><th>verdict</th></tr>")
            for name, m in r.metrics.items():
                out.append(f"<tr><td class='l'>{e(name)}</td><td>{_fmt(m.measured)}</td>"
                           f"<td>{_fmt(m.model)}</td><td>{_fmt(m.paper)}</td>"
                           f"<td class='l'>{e(m.unit)}</td><td>{_fmt(m.tolerance)}</td>"
                           f"<td class='{_cls(m.verdict)}'>{e(m.verdict)}</td></tr>")
            out.append("</table>")
        for n in r.notes:
            out.append(f"<p>{e(n)}</p>")
        for png in r.figures:
            out.append(f"<img alt='{e(r.id)}' src='data:image/png;base64,{png}'>")
        out.append("</section>")
    out.append("<section><h2>The paper's inconsistencies</h2><table><tr><th>item</th>"
               "<th>the paper prints</th><th>its equations give</th><th>the product "
               "reproduces</th></tr>")
    for i in rep.inconsistencies:
        out.append(f"<tr><td class='l'>{e(i['id'])}</td><td class='l'>{e(i['printed'])}</td>"
                   f"<td class='l'>{e(i['computed'])}</td><td class='l'>{e(i['reproduced'])}"
                   "</td></tr>")
    out.append("</table></section></body></html>")
    return "\n".join(out)
