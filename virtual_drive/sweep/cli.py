"""``virtual-drive sweep SPEC``: robustness sweep of a gain set (see ``virtual_drive.sweep``).

Exit status: 0 the sweep ran (with ``--check``: and every run passed; 1 if one failed its
limits), 2 a bad spec, option, results folder or scheduler (one line on stderr), 130
interrupted (the rows so far are kept; the same command resumes).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

__all__ = ["add_parser", "run_sweep_command"]


def add_parser(
    subparsers: argparse._SubParsersAction[argparse.ArgumentParser],
) -> argparse.ArgumentParser:
    """Register the ``sweep`` sub-command."""
    p = subparsers.add_parser(
        "sweep",
        help="robustness sweep of a gain set over the motor's spread (local pool or Dask)",
        description="Run the closed-loop simulation for every run of a TOML spec (grids and "
        "seeded distributions of motor, supply and gains; scenarios; limits) and write "
        "runs.csv (+ runs.parquet), summary.md/json and PNG maps into --out. A rerun skips the "
        "runs already there.",
    )
    p.add_argument("spec", metavar="SPEC", help="sweep spec (TOML)")
    p.add_argument("--out", metavar="DIR", help="results folder (default: ./<spec name>.sweep)")
    p.add_argument(
        "--scheduler", metavar="ADDR", help="Dask scheduler, e.g. tcp://127.0.0.1:8786"
    )
    p.add_argument(
        "--workers", type=int, metavar="N", help="local worker processes (default: all cores)"
    )
    p.add_argument("--map", nargs=2, metavar=("X", "Y"), help="parameters of the map plots")
    p.add_argument("--no-plots", action="store_true", help="write no PNG")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument(
        "--run", type=int, metavar="N", help="run only run N in this process and print its row"
    )
    p.add_argument("--plot", metavar="PNG", help="with --run: plot that run's response")
    p.add_argument("--json", action="store_true", help="print the row / summary as JSON")
    p.add_argument(
        "--check", action="store_true", help="exit 1 if a run fails its limits (nightly jobs)"
    )
    p.set_defaults(func=run_sweep_command)
    return p


def _error(msg: str, code: int = 2) -> int:
    print(f"virtual-drive sweep: error: {msg}", file=sys.stderr, flush=True)
    return code


def _jsonable(v: Any) -> Any:
    if isinstance(v, float) and not math.isfinite(v):
        return None if math.isnan(v) else ("inf" if v > 0 else "-inf")
    if isinstance(v, dict):
        return {k: _jsonable(x) for k, x in v.items()}
    if isinstance(v, list):
        return [_jsonable(x) for x in v]
    return v


def _one_run(spec: Any, args: argparse.Namespace) -> int:
    from virtual_drive.sweep.runner import run_one, run_trace

    job = spec.job(args.run)
    row = run_one(job)
    if args.json:
        print(json.dumps(_jsonable(row)))
    else:
        for k, v in row.items():
            print(f"{k} = {v}")
    if args.plot:
        from virtual_drive.sweep.plots import plot_run

        title = f"{spec.name} run {args.run} ({job.scenario.name}): {row['fails'] or 'pass'}"
        plot_run(run_trace(job), title, args.plot, job.scenario.unit)
        print(f"plot: {args.plot}", file=sys.stderr)
    return 1 if args.check and not row["passed"] else 0


def run_sweep_command(args: argparse.Namespace) -> int:
    """Run the sweep (or one run with ``--run``); returns the exit status."""
    from virtual_drive.sweep.spec import load_spec
    from virtual_drive.sweep.units import SpecError

    if args.workers is not None and args.workers < 1:
        return _error("--workers must be >= 1")
    if args.plot and args.run is None:
        return _error("--plot needs --run N")
    if args.run is not None and args.scheduler:
        return _error("--run runs in this process; leave out --scheduler")
    try:
        spec = load_spec(args.spec)
        if args.map:
            from virtual_drive.sweep.runner import INPUT_COLUMNS

            known = {*spec.swept, *INPUT_COLUMNS}
            bad = [m for m in args.map if m not in known]
            if bad:
                return _error(f"--map: {bad[0]!r} is not a swept parameter ({sorted(known)})")
        if args.run is not None:
            return _one_run(spec, args)
        from virtual_drive.sweep.driver import run_sweep
        from virtual_drive.sweep.results import summary_markdown

        out = Path(args.out) if args.out else Path.cwd() / f"{Path(args.spec).stem}.sweep"
        res = run_sweep(
            spec, out, scheduler=args.scheduler, workers=args.workers,
            progress=not args.no_progress, plots=not args.no_plots,
            map_axes=tuple(args.map) if args.map else None,
        )  # fmt: skip
    except SpecError as exc:
        return _error(str(exc))
    except KeyboardInterrupt:
        print("virtual-drive sweep: interrupted; the same command resumes", file=sys.stderr)
        return 130
    except Exception as exc:  # an engine gave up (workers kept dying); rows so far are kept
        msg = " ".join(str(exc).split()) or type(exc).__name__
        return _error(f"sweep stopped: {msg[:300]}; the same command resumes", 1)
    if args.json:
        print(json.dumps(_jsonable(res.summary)))
    else:
        sys.stdout.write(summary_markdown(res.summary))
        print(f"\n{res.executed} runs computed, {res.skipped} already in {res.out}")
        for f in res.files:
            print(f"wrote {f}")
    s = res.summary
    return 1 if args.check and not s["passed"] == s["runs"] == s["planned"] else 0
