"""A sweep's results folder: the append-only run log, Parquet, and the summary.

``runs.csv`` has one row per run (inputs, metrics, verdict, seed), appended by the client only
as results arrive (never by a worker) and flushed at once; the run id (``run``) is its key. A
rerun reads it, repairs a last line cut by a kill, and skips the runs present, so a sweep can be
stopped and resumed; a row whose run is already there is never written again. ``meta.json``
keeps the spec's digest: results of another spec in the same folder are refused.

At the end the rows are also written sorted by run as ``runs.parquet`` (where pyarrow is
installed) and summarised in ``summary.json`` / ``summary.md``: the fraction passing, the
reasons, and the worst cases with their inputs and the one command that re-runs each alone.
"""

from __future__ import annotations

import csv
import json
import math
import shlex
from collections import Counter
from pathlib import Path
from typing import Any

from virtual_drive.sweep.metrics import METRIC_UNITS, METRICS
from virtual_drive.sweep.runner import INPUT_COLUMNS
from virtual_drive.sweep.spec import Spec
from virtual_drive.sweep.units import SpecError

__all__ = ["COLUMNS", "ResultStore", "rerun_command", "summarize", "write_parquet"]

COLUMNS: tuple[str, ...] = (
    "run", "point", "scenario", "seed", *INPUT_COLUMNS, *METRICS,
    "passed", "fails", "severity", "error",
)  # fmt: skip
_INT = {"run", "point", "seed", "emcy"}
_BOOL = {"stable", "passed"}
_STR = {"scenario", "controller", "fails", "error"}


def _parse(col: str, text: str) -> Any:
    if col in _INT:
        return int(text)
    if col in _BOOL:
        if text not in ("True", "False"):
            raise ValueError(text)
        return text == "True"
    if col in _STR:
        return text
    return float(text)


class ResultStore:
    """The results folder ``out`` of ``spec`` (created if missing)."""

    def __init__(self, out: str | Path, spec: Spec) -> None:
        self.out = Path(out)
        self.spec = spec
        self.csv_path = self.out / "runs.csv"
        meta_path = self.out / "meta.json"
        if meta_path.exists():
            try:
                meta = json.loads(meta_path.read_text(encoding="utf-8"))
            except (OSError, ValueError) as exc:
                raise SpecError(f"{meta_path}: unreadable ({exc})") from None
            if meta.get("digest") != spec.digest:
                raise SpecError(
                    f"{self.out} holds results of another spec (digest {meta.get('digest')}, "
                    f"this one {spec.digest}): choose another --out"
                )
        self.out.mkdir(parents=True, exist_ok=True)
        meta = {"digest": spec.digest, "name": spec.name, "runs": spec.n_runs,
                "spec": str(spec.path) if spec.path else None}  # fmt: skip
        meta_path.write_text(json.dumps(meta, indent=1) + "\n", encoding="utf-8")
        self._rows: dict[int, dict[str, Any]] = {}
        self._load()

    def _load(self) -> None:
        if not self.csv_path.exists() or self.csv_path.stat().st_size == 0:
            with self.csv_path.open("w", newline="", encoding="utf-8") as fh:
                csv.writer(fh).writerow(COLUMNS)
            return
        data = self.csv_path.read_bytes()
        if not data.endswith(b"\n"):  # a line cut by a kill: drop it (its run runs again)
            data = data[: data.rfind(b"\n") + 1]
            with self.csv_path.open("r+b") as fh:
                fh.truncate(len(data))
        lines = data.decode("utf-8").splitlines()
        reader = csv.reader(lines)
        header = next(reader, None)
        if header is None:
            with self.csv_path.open("w", newline="", encoding="utf-8") as fh:
                csv.writer(fh).writerow(COLUMNS)
            return
        if tuple(header) != COLUMNS:
            raise SpecError(f"{self.csv_path}: columns of another version; use --out")
        for rec in reader:
            if len(rec) != len(COLUMNS):
                continue
            try:
                row = {c: _parse(c, t) for c, t in zip(COLUMNS, rec, strict=True)}
            except ValueError:
                continue
            self._rows.setdefault(row["run"], row)  # the first row of a run counts

    def done(self) -> set[int]:
        """Run ids present."""
        return set(self._rows)

    def append(self, rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
        """Write the rows whose run is not present yet (flushed); returns those written."""
        new = []
        for r in rows:
            if r["run"] in self._rows:
                continue
            self._rows[r["run"]] = r
            new.append(r)
        if new:
            with self.csv_path.open("a", newline="", encoding="utf-8") as fh:
                w = csv.writer(fh)
                for r in new:
                    w.writerow([r[c] for c in COLUMNS])
                fh.flush()
        return new

    def rows(self) -> list[dict[str, Any]]:
        """All rows, one per run, sorted by run."""
        return [self._rows[k] for k in sorted(self._rows)]


def write_parquet(rows: list[dict[str, Any]], path: str | Path) -> Path | None:
    """``rows`` as a Parquet file, or None when pyarrow is not installed."""
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        return None
    cols = {c: [r[c] for r in rows] for c in COLUMNS}
    pq.write_table(pa.table(cols), str(path))
    return Path(path)


def rerun_command(spec: Spec, run: int) -> str:
    """The one command that re-runs ``run`` alone and prints its row."""
    path = str(spec.path) if spec.path else "SPEC.toml"
    return f"virtual-drive sweep {shlex.quote(path)} --run {run}"


def _finite(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def summarize(rows: list[dict[str, Any]], spec: Spec, worst: int = 5) -> dict[str, Any]:
    """Fraction passing, failure reasons, trips, per-scenario counts and metric ranges, and the
    ``worst`` worst runs (largest severity) with their swept inputs and re-run command."""
    n = len(rows)
    passed = sum(1 for r in rows if r["passed"])
    reasons: Counter[str] = Counter()
    for r in rows:
        for f in filter(None, r["fails"].split(";")):
            reasons[f.split(">")[0] if ">" in f else f] += 1
    trips = Counter(f"0x{r['emcy']:04X}" for r in rows if r["emcy"])
    per_sc: dict[str, dict[str, int]] = {}
    for r in rows:
        d = per_sc.setdefault(r["scenario"], {"runs": 0, "passed": 0})
        d["runs"] += 1
        d["passed"] += int(r["passed"])
    ranges: dict[str, dict[str, list[float]]] = {}  # per scenario: ss_error is A or rpm
    for name in per_sc:
        sc_rows = [r for r in rows if r["scenario"] == name]
        for m in METRICS:
            vals = [r[m] for r in sc_rows if _finite(r[m]) and m not in ("stable", "emcy")]
            if vals:
                ranges.setdefault(name, {})[m] = [min(vals), max(vals)]
    ranked = sorted(rows, key=lambda r: (-_category(r), -r["severity"], r["run"]))[:worst]
    show = [*spec.swept] or ["L_c/L", "R_c/R"]
    worst_rows = [
        {
            "run": r["run"], "scenario": r["scenario"], "seed": r["seed"],
            "severity": r["severity"], "fails": r["fails"],
            "inputs": {k: r[k] for k in show if k in r},
            "metrics": {m: r[m] for m in METRICS},
            "command": rerun_command(spec, r["run"]),
        }
        for r in ranked if not r["passed"] or r["severity"] > 0
    ]  # fmt: skip
    return {
        "name": spec.name,
        "digest": spec.digest,
        "runs": n,
        "planned": spec.n_runs,
        "passed": passed,
        "fraction_passing": passed / n if n else math.nan,
        "unstable": sum(1 for r in rows if not r["stable"]),
        "fail_reasons": dict(reasons.most_common()),
        "trips": dict(trips),
        "per_scenario": per_sc,
        "metric_ranges": ranges,
        "metric_units": METRIC_UNITS,
        "worst": worst_rows,
    }


def _category(r: dict[str, Any]) -> int:
    """2 not stable / tripped / invalid, 1 failed a limit, 0 passed."""
    if not r["stable"] or r["emcy"] or r["error"]:
        return 2
    return 0 if r["passed"] else 1


def _fmt(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def summary_markdown(s: dict[str, Any]) -> str:
    """The summary as Markdown (``summary.md``, and printed by the CLI)."""
    frac = s["fraction_passing"]
    lines = [
        f"# Sweep {s['name']} ({s['digest']})",
        "",
        f"{s['passed']} of {s['runs']} runs pass ({100 * frac:.1f} %); "
        f"{s['unstable']} not stable; planned {s['planned']}.",
    ]
    if s["fail_reasons"]:
        why = ", ".join(f"{k}: {v}" for k, v in s["fail_reasons"].items())
        lines.append(f"Failures by reason: {why}.")
    if s["trips"]:
        lines.append("Trips (EMCY): " + ", ".join(f"{k}: {v}" for k, v in s["trips"].items()))
    for name, d in s["per_scenario"].items():
        lines.append(f"- scenario {name}: {d['passed']} of {d['runs']} pass")
    if s["worst"]:
        lines += ["", "## Worst cases", ""]
        for w in s["worst"]:
            ins = ", ".join(f"{k}={_fmt(v)}" for k, v in w["inputs"].items())
            met = ", ".join(
                f"{k}={_fmt(v)}" for k, v in w["metrics"].items() if not _nan(v)
            )
            lines.append(
                f"- run {w['run']} ({w['scenario']}): {w['fails'] or 'pass'}; {ins}; {met}"
            )
            lines.append(f"  `{w['command']}`")
    return "\n".join(lines) + "\n"


def _nan(v: Any) -> bool:
    return isinstance(v, float) and math.isnan(v)
