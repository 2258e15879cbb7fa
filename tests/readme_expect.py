"""What each README shell line must do: its exit status and what its comment says (issue 23).

A line without an entry in :data:`EXPECT` must exit 0 without a traceback. A line whose comment
makes a claim (``# refused …``, ``# → …``) must have an entry (the inventory test checks it),
and every entry must still be a line of a README block. Where a comment states numbers, the
numbers are read from the comment itself, so the comment and the output cannot drift apart.
Truths beside the comments: the paper (L = 14.8 µH, L_c < 2 L for stability, Table 1), the
CiA 301/402 specs (device type 0x00020192, boot-up to PRE-OPERATIONAL), the EDS, canopen's own
DCF import and python-can's own log reader.
"""

from __future__ import annotations

import configparser
import csv
import json
import re
import shutil
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import readme_truth as rt
from conftest import heartbeat_explained, min_rate
from readme_blocks import ROOT, Line
from readme_session import Result, ShellSession, _live_terminal

#: The motor's inductance, paper Table/§2 (H).
L_MOTOR = 14.8e-6

Check = Callable[[Result, ShellSession], list[str]]


@dataclass(frozen=True)
class Expect:
    """``rc``: the exit status the README's table gives; ``check``: what the comment says
    (``rc_by_check``: the check judges the exit status itself)."""

    rc: int = 0
    check: Check | None = None
    rc_by_check: bool = False
    #: a third-party server whose log may hold tracebacks (Dask logs closed connections at
    #: shutdown with one); its exit status is still judged
    traceback_ok: bool = False


def _has(*patterns: str, stream: str = "out") -> Check:
    def check(r: Result, s: ShellSession) -> list[str]:
        text = getattr(r, stream)
        return [f"{stream} lacks /{p}/" for p in patterns if not re.search(p, text, re.M)]

    return check


def _all(*checks: Check) -> Check:
    return lambda r, s: [p for c in checks for p in c(r, s)]


def _one_line_error(*words: str) -> Check:
    def check(r: Result, s: ShellSession) -> list[str]:
        lines = r.err.strip().splitlines()
        bad = [] if len(lines) == 1 else [f"stderr is {len(lines)} lines, not one"]
        return bad + [f"stderr lacks {w!r}" for w in words if w not in r.err]

    return check


def _step_files(i_from: float, i_to: float) -> Check:
    """The CSV holds the step asked for (i_p from about i_from to about i_to A), the PNG is
    a PNG."""

    def check(r: Result, s: ShellSession) -> list[str]:
        bad = []
        if (s.cwd / "step.png").read_bytes()[:8] != b"\x89PNG\r\n\x1a\n":
            bad.append("step.png is not a PNG")
        with (s.cwd / "step.csv").open(newline="") as fh:
            rows = list(csv.reader(fh))
        col = next((i for i, h in enumerate(rows[0]) if re.match(r"(.*\.)?i_p \[A\]", h)), None)
        if col is None:
            return [*bad, f"step.csv has no i_p column: {rows[0]}"]
        i_p = [float(row[col]) for row in rows[1:]]
        first, last = sum(i_p[:20]) / 20, sum(i_p[-50:]) / 50
        if abs(first - i_from) > 1.0 or abs(last - i_to) > 1.0:
            bad.append(f"step.csv i_p goes {first:.2f} → {last:.2f} A, not {i_from} → {i_to}")
        return bad

    return check


def _set_gains_refused(r: Result, s: ShellSession) -> list[str]:
    """40 µH > 2 L = 29.6 µH: unstable (the Jury limit, paper eq. 17); --force cannot apply it
    either, and the drive's L_c is unchanged."""
    bad = _one_line_error("unstable")(r, s)
    f = s.run_text("drive-link set-gains L_c=40e-6 --force $H")
    if f.rc != 8:
        bad.append(f"with --force: exit {f.rc}, not 8 ({f.err.strip()})")
    rd = s.run_text("drive-link read current_controller.L_c $H --json")
    try:
        L_c = float(json.loads(rd.out)["current_controller.L_c"])
    except (ValueError, KeyError, TypeError) as exc:
        return [*bad, f"cannot read L_c back: {exc}: {rd.out} {rd.err}"]
    if not 0 < L_c < 2 * L_MOTOR:
        bad.append(f"L_c is {L_c} H after the refused sets")
    return bad


def _design_table1(r: Result, s: ShellSession) -> list[str]:
    """The comment's numbers (Table 1, L_c = 1.5 L) against the JSON, to the digits written."""
    m = re.search(
        r"([\d.]+) dB, PM ([\d.]+)° \(([\d.]+)° at ([\d.]+) kHz, ([\d.]+)° at ([\d.]+) kHz\), "
        r"‖S‖∞ = ([\d.]+)",
        r.comment,
    )
    if m is None:
        return [f"comment no longer states the margins: {r.comment}"]
    gm, pm, pm1, f1, pm2, f2, s_inf = m.groups()
    d = json.loads(r.out)
    cross = d["crossovers"][:2]
    pairs = [(gm, d["gain_margin_db"]), (pm, d["phase_margin_deg"]), (s_inf, d["sensitivity_peak"])]
    for (want_pm, want_f), c in zip(((pm1, f1), (pm2, f2)), cross, strict=False):
        pairs += [(want_pm, c["phase_margin_deg"]), (want_f, c["hz"] / 1e3)]
    bad = [] if len(d["crossovers"]) == 2 else [f"{len(d['crossovers'])} crossovers, not 2"]
    for want, got in pairs:
        digits = len(want.split(".")[1]) if "." in want else 0
        if round(got, digits) != float(want):
            bad.append(f"comment says {want}, output {got:.{digits + 2}f}")
    # the paper's Table 1 row L_c = 1.5 L: 2.5 dB, phase margin ±41.6° (one of our crossovers)
    if round(d["gain_margin_db"], 1) != 2.5 or 41.6 not in [
        round(c["phase_margin_deg"], 1) for c in d["crossovers"]
    ]:
        bad.append("no longer Table 1's 1.5 L row (2.5 dB, 41.6°)")
    return bad


def _design_ip(r: Result, s: ShellSession) -> list[str]:
    m = re.search(r"k_p ([\d.]+), k_i ([\d.]+)e(-?\d+)", r.comment)
    if m is None:
        return [f"comment no longer states k_p, k_i: {r.comment}"]
    d = json.loads(r.out)
    kp, ki = d["kp"], d["ki"]
    bad = []
    if round(kp, len(m[1].split(".")[1])) != float(m[1]):
        bad.append(f"k_p {kp} is not the comment's {m[1]}")
    if f"{ki:.{len(m[2].split('.')[1])}e}" != f"{m[2]}e{int(m[3]):+03d}":
        bad.append(f"k_i {ki:.3e} is not the comment's {m[2]}e{m[3]}")
    return bad


def _check_items(r: Result, s: ShellSession) -> list[str]:
    """Every item PASS; a heartbeat or TPDO rate item that failed only as far as the kernel
    kept the drive's process waiting meanwhile is accepted (as in tests/test_link_check.py)."""
    items = re.findall(r"^(PASS|FAIL|SKIP|N/A)\s+(\w+)\s*(.*)$", r.out, re.M)
    bad = [] if len(items) >= 10 else [f"only {len(items)} pass/fail items"]
    if r.rc not in (0, 1):
        bad.append(f"exit {r.rc} (README: 0 all pass, 1 a failed check)")
    if re.search(r"^(\d+)/(\d+) passed", r.out, re.M) is None:
        bad.append("no 'N/M passed' line")
    unexplained = [
        f"{name}: {detail}"
        for v, name, detail in items
        if v == "FAIL" and not _explained(name, detail, r.extra.get("drive_wait", 0.0))
    ]
    if r.rc == 1 and not any(v == "FAIL" for v, _, _ in items):
        bad.append("exit 1 with no failed item")
    return bad + unexplained


def _check_as_found(r: Result, s: ShellSession) -> list[str]:
    """The items (above); store_restore "N/A" on a drive started without ``--store`` (the
    comment); the error objects 0x603F, 0x1001, 0x1003:0 (canopen's SDO) as before the line."""
    bad = _check_items(r, s)
    if "store_restore N/A" in r.comment and not re.search(r"^N/A\s+store_restore\b", r.out, re.M):
        bad.append("store_restore is not N/A")
    after = rt.error_objects(s)
    if "as found" in r.comment and after != r.extra.get("before"):
        bad.append(f"error objects {r.extra.get('before')} before, {after} after")
    return bad


def _explained(name: str, detail: str, wait: float) -> bool:
    m = re.fullmatch(r"TPDO\d+ at (\d+) Hz, expected (\d+) Hz", detail)
    if name == "pdo_rates" and m:
        return int(m[1]) >= min_rate(int(m[2]), wait, 0.5)
    return name == "heartbeat" and heartbeat_explained(detail, wait)


def _activated(r: Result, s: ShellSession) -> list[str]:
    venv_bin = (s.cwd / ".venv" / "bin").resolve()
    bad = []
    for exe in ("drive-link", "virtual-drive", "drive-dashboard", "python"):
        found = shutil.which(exe, path=s.env.get("PATH"))
        if found is None or Path(found).parent.resolve() != venv_bin:
            bad.append(f"{exe} on PATH is {found}, not the venv's")
    return bad


def _objects_row(r: Result, s: ShellSession) -> list[str]:
    eds = configparser.ConfigParser(strict=False)
    eds.read(ROOT / "firmware_protocol" / "bldc_drive.eds", encoding="utf-8")
    sec = eds["2010sub2"]
    row = re.search(
        r"^0x2010:02\s+current_controller\.L_c\s+REAL32\s+(\S+)\s+(\S+)\s+(\w+)", r.out, re.M
    )
    bad = _has(r"^INDEX\s+NAME\s+TYPE\s+UNIT\s+LIMITS\s+ACCESS")(r, s)
    if row is None:
        return [*bad, "no row 0x2010:02 current_controller.L_c REAL32"]
    lo, hi = row[2].split("..")
    if row[1] != sec["Unit"] or float(lo) != float(sec["LowLimit"]) or row[3] != "rw":
        bad.append(f"row {row[0]!r} differs from the EDS {dict(sec)}")
    if float(hi) != float(sec["HighLimit"]) or sec["DataType"] != "0x0008":
        bad.append(f"row {row[0]!r} differs from the EDS {dict(sec)}")
    return bad


def _dcf(r: Result, s: ShellSession) -> list[str]:
    """canopen reads the DCF, with the R_c written two lines above (5 mΩ) and node-ID 1."""
    import canopen

    od = canopen.import_od(str(s.cwd / "bench.dcf"), node_id=1)
    bad = [] if od.node_id == 1 else [f"DCF node-ID {od.node_id}"]
    R_c = od["current_controller"]["R_c"].value
    if abs(R_c - 5e-3) > 1e-8:
        bad.append(f"DCF has R_c = {R_c}, not the 5 mOhm written")
    for name in ("motor", "speed_controller", "current_controller"):
        if name not in od.names:
            bad.append(f"DCF lacks {name}")
    return bad


def _recorded(r: Result, s: ShellSession) -> list[str]:
    import can

    m = re.search(r"recorded (\d+) frames in ([\d.]+) s to bus.blf", r.out)
    if m is None:
        return ["no 'recorded N frames' line"]
    msgs = list(can.LogReader(str(s.cwd / "bus.blf")))
    ids = {msg.arbitration_id for msg in msgs}
    bad = [] if len(msgs) == int(m[1]) else [f"bus.blf holds {len(msgs)} frames, not {m[1]}"]
    span = msgs[-1].timestamp - msgs[0].timestamp if msgs else 0.0
    if not 9.0 <= span <= 10.5:
        bad.append(f"bus.blf spans {span:.2f} s, not 10 s")
    missing = {0x181, 0x281, 0x381, 0x481, 0x701} - ids  # TPDO1-4 and heartbeat of node 1
    return bad + ([f"bus.blf lacks {sorted(map(hex, missing))}"] if missing else [])


def _replayed(r: Result, s: ShellSession) -> list[str]:
    bad = _has(*[rf"^\s+TPDO{n} 0x{n}81: \d+ frames" for n in (1, 2, 3, 4)])(r, s)
    with (s.cwd / "live.csv").open(newline="") as fh:
        rows = list(csv.reader(fh))
    if len(rows) < 1000 or not any(h.startswith("measurements.speed") for h in rows[0]):
        bad.append(f"live.csv: {len(rows)} rows, header {rows[0] if rows else None}")
    # --trace-csv: the file, or one line saying the recording holds no trace upload
    if (
        "--trace-csv trace.csv" in r.cmd
        and not (s.cwd / "trace.csv").exists()
        and not re.search(r"^no trace upload in ", r.out, re.M)
    ):
        bad.append("--trace-csv trace.csv: no file and no word why")
    return bad


def _shell_session(r: Result, s: ShellSession) -> list[str]:
    return _has(
        r"current_controller\.L_c = [\d.e-]+ H",  # read, completed by TAB
        r"target_velocity 1000 rpm",  # set-speed 1000 --enable
        r"usage: .*step",  # help step
    )(r, s)


def _state(s: ShellSession) -> str:
    m = re.search(r"^\s+state: (.+)$", s.run_text("drive-link status").out, re.M)
    return m[1].strip() if m else "?"


def _live_screen(r: Result, s: ShellSession) -> list[str]:
    """The panels of the signals asked for; ``x`` quits leaving the drive running (the shell
    above enabled it at 1000 rpm), ``q`` quick-stops it and quits (CiA 402: the drive leaves
    OPERATION ENABLED through QUICK STOP ACTIVE)."""
    screen = r.extra.get("screen", "")
    bad = [f"screen lacks {sig}" for sig in r.extra.get("signals", []) if sig not in screen]
    if (st := _state(s)) != "OPERATION ENABLED":
        bad.append(f"after x the drive is {st}, not left OPERATION ENABLED")
    q = _live_terminal(s, Line(r.cmd, ""), s.localize(r.cmd), key=b"q")
    if q.rc != 0 or q.problem:
        bad.append(f"with q: exit {q.rc} {q.problem}")
    if (st := _state(s)) not in ("QUICK STOP ACTIVE", "SWITCH ON DISABLED"):
        bad.append(f"after q the drive is {st}, not quick-stopped")
    return bad


def _frames(r: Result, s: ShellSession) -> list[str]:
    n = len(re.findall(r"^--- frame \d+/3", r.out, re.M))
    return [] if n == 3 else [f"{n} frames, not 3"]


H = "$H"
EXPECT: dict[str, Expect] = {
    # "A session against the virtual drive"
    "virtual-drive --hub --hub-port 29600 &": Expect(0, _has(r"node 1 ready on")),
    f"drive-link scan {H}": Expect(0, rt.scan_nodes),  # node 1 here; 1 and 2 with two drives
    f"drive-link nmt start {H} && drive-link enable {H} && drive-link set-speed 1000 {H}": Expect(
        0, _has(r"OPERATION ENABLED", r"target_velocity 1000 rpm")
    ),
    f"drive-link step current --from 15 --to 20 --csv step.csv --png step.png {H}": Expect(
        0, _step_files(15, 20)
    ),
    f"drive-link set-gains L_c=40e-6 {H}": Expect(8, _set_gains_refused),
    "drive-link design --Lc 22.2e-6 --json": Expect(0, _design_table1),
    "drive-link design --a 0.9999785 --b 3.33715e-4 --xi 1 --wn 2.3 --json": Expect(0, _design_ip),
    f"drive-link check {H}": Expect(0, _check_as_found, rc_by_check=True),
    # "Using drive-link"
    ". .venv/bin/activate": Expect(0, _activated),
    "drive-link objects L_c": Expect(0, _objects_row),
    "drive-link read 0x6041 0x2010:2 target_velocity": Expect(
        0,
        _has(
            r"^statusword = \d+",
            r"^current_controller\.L_c = [\d.e-]+ H$",
            r"^target_velocity = -?[\d.]+ rpm$",
        ),
    ),
    "drive-link set-speed 1000rpm --enable": Expect(
        0, _has(r"^target_velocity 1000 rpm \(OPERATION ENABLED\)")
    ),
    "drive-link step current --from 15A --to 20A --csv step.csv --png step.png": Expect(
        0, _step_files(15, 20)
    ),
    "drive-link status": Expect(
        0,
        _has(
            r"^\s+mode: speed$",
            r"^\s+state: OPERATION ENABLED$",
            r"^\s+speed_ref_rpm: 1000(\.0*)?$",
        ),
    ),
    "drive-link set-current 5A": Expect(1, _one_line_error("speed mode", "--switch-mode")),
    "drive-link write current_controller.R_c 5mohm": Expect(
        0,
        _has(
            r"^current_controller\.R_c = 0\.00499999\d* Ohm$|^current_controller\.R_c = "
            r"0\.005 Ohm$"
        ),
    ),
    "drive-link config save bench.dcf": Expect(0, _dcf),
    "drive-link config diff bench.dcf": Expect(0, _has(r"^0 differ")),
    "drive-link config load bench.dcf --dry-run": Expect(0, _has(r"^would write 0 objects")),
    # "Tools"
    "drive-link shell": Expect(0, _shell_session),
    "drive-link live --plot speed speed_ref i_p": Expect(0, _live_screen),
    "drive-link live --plot speed --frames 3": Expect(0, _frames),
    "drive-link record bus.blf --seconds 10s": Expect(0, _recorded),
    "drive-link replay bus.blf --csv live.csv --plot speed": Expect(0, _replayed),
    "drive-link monitor --seconds 3 --show-nodes 1": Expect(
        0, _has(r"^\s*ID\s+kind\s+count\s+Hz\s+age s\s+data\s+meaning$", r"^\s*0x701 heartbeat")
    ),
    # "Robustness sweeps"
    "virtual-drive sweep examples/sweeps/table1.toml --out table1.sweep": Expect(
        0, rt.sweep_table1
    ),
    "virtual-drive sweep examples/sweeps/table1.toml --run 150": Expect(0, rt.sweep_one_run),
    "dask scheduler --host 127.0.0.1 --port 8786 --dashboard-address 127.0.0.1:0 &": Expect(
        0, traceback_ok=True
    ),
    "dask worker tcp://127.0.0.1:8786 --host 127.0.0.1 --nworkers 2 --nthreads 1 "
    "--dashboard-address 127.0.0.1:0 &": Expect(0, traceback_ok=True),
    "virtual-drive sweep examples/sweeps/table1.toml --out table1-dask.sweep --scheduler "
    "tcp://127.0.0.1:8786 --no-progress": Expect(0, rt.same_rows),
    # "Loopback hub and several drives"
    "virtual-drive hub --nodes 1-2 --port 29620 &": Expect(0, rt.drive_started),
    f"drive-link --node 2 set-speed 500rpm --enable {H}": Expect(0, rt.node2_turns),
    f"drive-link monitor --seconds 2 --show-nodes 2 {H}": Expect(0, rt.only_node_frames),
    # "Drives without a node-ID: LSS"
    "virtual-drive run --hub --hub-port 29610 --unconfigured 2 --serial-base 0x40 &": Expect(
        0, rt.drive_started
    ),
    "drive-link lss --host 127.0.0.1 --port 29610 --first-id 2": Expect(0, rt.lss_serials),
    "drive-link scan --host 127.0.0.1 --port 29610": Expect(0, rt.scan_nodes),
    # "Using real CAN", vcan0 (inside User-Mode Linux)
    "virtual-drive --interface socketcan --channel vcan0 &": Expect(0, _has(r"ready on")),
    "drive-link --interface socketcan --channel vcan0 status": Expect(
        0, _has(r"^\s+nmt_state: PRE-OPERATIONAL$", r"^\s+bus_state: ERROR_ACTIVE$")
    ),
}

#: A comment that makes one of these claims needs an entry in EXPECT.
CLAIM = re.compile(r"refused|→|->|\d")


def before(line: Line, s: ShellSession) -> dict | None:
    """What a line's check compares with afterwards, read before it runs."""
    if line.cmd == f"drive-link check {H}":
        return rt.error_objects(s)
    return None


def judge(r: Result, s: ShellSession | None) -> list[str]:
    """Problems of one line's result (empty: as the README says)."""
    exp = EXPECT.get(r.cmd, Expect())
    bad = [r.problem] if r.problem else []
    if r.rc is not None and r.rc != exp.rc and not (exp.rc_by_check and s is not None):
        last = (r.err.strip() or r.out.strip()).splitlines()[-1:] or [""]
        bad.append(f"exit {r.rc}, README expects {exp.rc}: {last[0][-300:]}")
    if "Traceback (most recent call last)" in r.err + r.out and not exp.traceback_ok:
        bad.append("printed a traceback")
    if not bad and exp.check is not None and s is not None:
        try:
            bad += exp.check(r, s)
        except Exception as exc:  # a check that cannot read the output is a failed line
            bad.append(f"check failed: {type(exc).__name__}: {exc}")
    return bad


judge.before = before  # type: ignore[attr-defined]  # readme_session.run_blocks calls it
