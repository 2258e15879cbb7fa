"""Truths beside the README's comments, read on the bus or from the paper (issue 23).

The checks of ``tests/readme_expect.py`` for the sweep, two-drive and LSS blocks judge what a
line printed against something the product's own code does not compute:

- the bus itself, through the session's hub (python-can's ``socketcand`` client, as the hub
  prints it): heartbeats with the CiA 301 NMT state byte, and SDO uploads by canopen's own
  client (identity object 0x1018, statusword 0x6041, velocity_actual_value 0x606C, error
  objects 0x603F / 0x1001 / 0x1003);
- the paper: eq. (17)'s limit L_c < 2 L and the closed deadbeat loop's poles by python-control
  (the oracle of ``tests/test_sweep_table1.py``).
"""

from __future__ import annotations

import contextlib
import csv
import re
import time
from collections.abc import Iterator
from pathlib import Path

from readme_session import Result, ShellSession

#: CiA 301 heartbeat state byte → the NMT state's name.
NMT_STATE = {0x00: "INITIALISING", 0x04: "STOPPED", 0x05: "OPERATIONAL", 0x7F: "PRE-OPERATIONAL"}


def hub_port(s: ShellSession) -> int:
    """The free port standing in for the README's hub port in this session."""
    assert len(s.ports) >= 1, "no hub port in this session"
    return int(next(iter(s.ports.values())))


def _connect(open_it):
    """python-can's socketcand client compares each handshake answer with one whole read, so
    it fails ("Expected '< ok >' got: '< ok >< frame …'") when the hub's first frames arrive
    in the same read as its ``< ok >`` (drives streaming): try again, up to 5 times."""
    import can

    for attempt in range(5):
        try:
            return open_it()
        except can.CanError:
            if attempt == 4:
                raise
            time.sleep(0.2)
    raise AssertionError("unreachable")


@contextlib.contextmanager
def bus(s: ShellSession) -> Iterator:
    import can

    b = _connect(
        lambda: can.Bus(interface="socketcand", host="127.0.0.1", port=hub_port(s), channel="vcan0")
    )
    try:
        yield b
    finally:
        b.shutdown()


def heartbeats(s: ShellSession, seconds: float = 3.0, want: set[int] | None = None) -> dict:
    """Node-ID → NMT state name of the heartbeats seen within ``seconds`` (until every node of
    ``want`` has sent one)."""
    seen: dict[int, str] = {}
    end = time.monotonic() + seconds
    with bus(s) as b:
        while time.monotonic() < end:
            msg = b.recv(0.2)
            if msg is None or not 0x701 <= msg.arbitration_id <= 0x77F or len(msg.data) != 1:
                continue
            seen[msg.arbitration_id - 0x700] = NMT_STATE.get(msg.data[0], hex(msg.data[0]))
            if want is not None and want <= set(seen):
                break
    return seen


@contextlib.contextmanager
def sdo_nodes(s: ShellSession, *node_ids: int) -> Iterator[dict]:
    """canopen's own SDO clients of ``node_ids`` on the session's hub: {id: RemoteNode}."""
    import canopen

    net = canopen.Network()
    _connect(
        lambda: net.connect(
            interface="socketcand", host="127.0.0.1", port=hub_port(s), channel="vcan0"
        )
    )
    try:
        nodes = {}
        for n in node_ids:
            node = canopen.RemoteNode(n, canopen.ObjectDictionary())
            net.add_node(node)
            node.sdo.RESPONSE_TIMEOUT = 2.0
            nodes[n] = node
        yield nodes
    finally:
        net.disconnect()


def u32(node, index: int, sub: int = 0) -> int:
    return int.from_bytes(node.sdo.upload(index, sub)[:4], "little")


def i32(node, index: int, sub: int = 0) -> int:
    return int.from_bytes(node.sdo.upload(index, sub)[:4], "little", signed=True)


def error_objects(s: ShellSession, node_id: int = 1) -> dict[str, int]:
    """0x603F error code, 0x1001 error register, 0x1003:0 number of errors (canopen's SDO)."""
    with sdo_nodes(s, node_id) as nodes:
        n = nodes[node_id]
        return {
            "0x603F": u32(n, 0x603F) & 0xFFFF,
            "0x1001": u32(n, 0x1001) & 0xFF,
            "0x1003:0": u32(n, 0x1003, 0) & 0xFF,
        }


# ------------------------------------------------------------------------------------------
# Checks (Result, ShellSession) -> problems
# ------------------------------------------------------------------------------------------


def scan_nodes(r: Result, s: ShellSession) -> list[str]:
    """``scan``: exactly the nodes its comment names (node 1 when it names none), each with the
    CiA 402 device type and the NMT state its heartbeat on the bus says (and the comment's
    state, if it names one)."""
    want = {int(n) for n in re.findall(r"\b(\d+)\b", r.comment)} or {1}
    rows = {
        int(m[1]): m[2]
        for m in re.finditer(
            r"^node\s+(\d+): device_type 0x00020192 \(CiA 402\), ([A-Z-]+)$", r.out, re.M
        )
    }
    bad = [] if set(rows) == want else [f"scan lists nodes {sorted(rows)}, not {sorted(want)}"]
    said = re.search(r"\b(PRE-OPERATIONAL|OPERATIONAL|STOPPED)\b", r.comment)
    hb = heartbeats(s, 3.0, want)
    for n, state in rows.items():
        if hb.get(n) != state:
            bad.append(f"node {n}: scan says {state}, its heartbeat {hb.get(n)}")
        if said and state != said[1]:
            bad.append(f"node {n}: {state}, the comment says {said[1]}")
    return bad


def node2_turns(r: Result, s: ShellSession) -> list[str]:
    """The comment "node 2 turns, node 1 stays disabled": 0x606C of node 2 reaches the 500 rpm
    asked for; node 1's statusword (0x6041) is SWITCH ON DISABLED (CiA 402: xxxx xxxx x1xx 0000)."""
    want = float(re.search(r"set-speed (\d+)rpm", r.cmd)[1])
    bad, v = [], None
    with sdo_nodes(s, 1, 2) as nodes:
        end = time.monotonic() + 20.0
        while time.monotonic() < end:
            v = i32(nodes[2], 0x606C)
            if abs(v - want) <= 0.02 * want:
                break
            time.sleep(0.2)
        else:
            bad.append(f"node 2 at {v} rpm (0x606C), not {want:g}")
        sw = u32(nodes[1], 0x6041) & 0xFFFF
    if sw & 0x4F != 0x40:
        bad.append(f"node 1 statusword 0x{sw:04X}: not SWITCH ON DISABLED")
    return bad


def only_node_frames(r: Result, s: ShellSession) -> list[str]:
    """``monitor --show-nodes N``: every row a frame of node N (COB-ID & 0x7F = N) or NMT
    (0x000); node N's four TPDOs and heartbeat (OPERATIONAL: CiA 301 lets PDOs flow) are there;
    the other node is on the bus meanwhile (its heartbeat), so the filter had frames to drop."""
    n = int(re.search(r"--show-nodes (\d+)", r.cmd)[1])
    ids = {int(m, 16) for m in re.findall(r"^\s*0x([0-9A-Fa-f]{3})\s", r.out, re.M)}
    bad = [f"row 0x{i:03X} is not node {n}'s" for i in sorted(ids) if i and i & 0x7F != n]
    missing = {0x180 + n, 0x280 + n, 0x380 + n, 0x480 + n, 0x700 + n} - ids
    if missing:
        bad.append(f"rows lack {sorted(map(hex, missing))}")
    others = set(heartbeats(s, 2.0)) - {n}
    if not others:
        bad.append("no other node's heartbeat on the bus: the filter was not tested")
    return bad


def lss_serials(r: Result, s: ShellSession) -> list[str]:
    """``lss``: the comment's first node gets the comment's serial, each configured node's
    identity (0x1018:1-4, read by canopen from the new node-ID) is what the line printed, and
    the serials are the ones the drives were started with (``--serial-base``, two drives)."""
    m = re.search(r"node (\d+): serial 0x([0-9a-fA-F]+)", r.comment)
    rows = re.findall(
        r"^node (\d+): serial 0x([0-9a-f]+) \(vendor 0x([0-9a-f]+), product 0x([0-9a-f]+), "
        r"revision 0x([0-9a-f]+)\)",
        r.out,
        re.M,
    )
    if m is None or not rows:
        return [f"no node/serial to compare: comment {r.comment!r}, output {r.out!r}"]
    got = {int(n): [int(x, 16) for x in (ser, ven, prod, rev)] for n, ser, ven, prod, rev in rows}
    bad = []
    if got.get(int(m[1]), [None])[0] != int(m[2], 16):
        bad.append(f"node {m[1]} is not serial 0x{m[2]}: {got}")
    base = int(re.search(r"--serial-base (0x[0-9a-fA-F]+)", s.history_cmd("--serial-base"))[1], 16)
    if sorted(v[0] for v in got.values()) != [base, base + 1]:
        bad.append(f"serials {sorted(v[0] for v in got.values())}, not {base:#x}, {base + 1:#x}")
    first = int(re.search(r"--first-id (\d+)", r.cmd)[1])
    if sorted(got) != [first, first + 1]:
        bad.append(f"node-IDs {sorted(got)}, not {first} and {first + 1}")
    with sdo_nodes(s, *got) as nodes:
        for n, printed in got.items():
            ident = [u32(nodes[n], 0x1018, sub) for sub in (4, 1, 2, 3)]
            if ident != printed:
                bad.append(f"node {n}: 0x1018 says {ident}, the line printed {printed}")
    return bad


def drive_started(r: Result, s: ShellSession) -> list[str]:
    """A background start's comment: "hub + drives 1 and 2" (each node said it is ready),
    "serials 0x40, 0x41" (the unconfigured drives' serials in its ready line)."""
    text = r.out + r.err
    bad = []
    if "drives" in r.comment and "serial" not in r.comment:
        for n in re.findall(r"\b(\d+)\b", r.comment):
            if not re.search(rf"node {n} ready", text):
                bad.append(f"node {n} did not say it is ready")
    for ser in re.findall(r"0x([0-9a-fA-F]+)", r.comment):
        m = re.search(r"\(serial ([\d,]+)\) ready", text)
        if m is None or int(ser, 16) not in [int(x) for x in m[1].split(",")]:
            bad.append(f"no drive with serial 0x{ser} ready")
    return bad


# ------------------------------------------------------------------------------------------
# Sweeps: eq. (17) and the closed loop's poles
# ------------------------------------------------------------------------------------------


def _radius(row: dict) -> float:
    from test_sweep_table1 import _oracle_radius

    return _oracle_radius(*(float(row[k]) for k in ("L", "R", "L_c", "R_c")))


def _rows(folder: Path) -> list[dict]:
    with (folder / "runs.csv").open(newline="") as fh:
        return list(csv.DictReader(fh))


def sweep_table1(r: Result, s: ShellSession) -> list[str]:
    """The comment "N runs: Table 1 over L_c/L x R_c/R": runs.csv holds N runs, one per point of the
    L_c/L x R_c/R grid, and each run's ``stable`` is what the poles of the closed deadbeat loop
    (python-control, eqs. 8, 15) say, except within 0.2 % of the unit circle."""
    n = int(re.match(r"(\d+) runs", r.comment)[1])
    rows = _rows(s.cwd / re.search(r"--out (\S+)", r.cmd)[1])
    bad = [] if len(rows) == n else [f"runs.csv has {len(rows)} runs, not {n}"]
    grid = {(row["L_c/L"], row["R_c/R"]) for row in rows}
    if len(grid) != len(rows):
        bad.append(f"{len(grid)} L_c/L x R_c/R points for {len(rows)} runs")
    wrong = [
        (row["run"], row["L_c/L"], row["R_c/R"], row["stable"])
        for row in rows
        if abs((rho := _radius(row)) - 1.0) >= 0.002 and (row["stable"] == "True") != (rho < 1.0)
    ]
    return bad + ([f"stable against the poles: {wrong[:5]}"] if wrong else [])


def sweep_one_run(r: Result, s: ShellSession) -> list[str]:
    """The comment "one run alone: its row (L_c = 2.03 L: unstable)": the printed row is run N
    of the sweep's runs.csv (same inputs, same verdict), its L_c/L rounds to the comment's
    figure, it is unstable, and so say eq. (17) (L_c > 2 L) and the closed loop's poles."""
    row = dict(re.findall(r"^(\S+) = (.*)$", r.out, re.M))
    m = re.search(r"L_c = ([\d.]+) L: (unstable|stable)", r.comment)
    if m is None or "L_c/L" not in row:
        return [f"no L_c/L to compare: comment {r.comment!r}"]
    bad = []
    ratio = float(row["L_c"]) / float(row["L"])
    if round(ratio, len(m[1].split(".")[1])) != float(m[1]):
        bad.append(f"L_c/L = {ratio:.4f}, the comment says {m[1]}")
    said_stable = m[2] == "stable"
    if (row.get("stable") == "True") != said_stable:
        bad.append(f"stable = {row.get('stable')}, the comment says {m[2]}")
    if (ratio < 2.0) != said_stable or (_radius(row) < 1.0) != said_stable:
        bad.append(f"eq. (17)/poles: L_c/L {ratio:.3f}, radius {_radius(row):.4f}")
    n = re.search(r"--run (\d+)", r.cmd)[1]
    spec = re.search(r"sweep (\S+\.toml)", r.cmd)[1]
    folders = [f for f in s.cwd.glob("*.sweep") if spec in s.history_cmd(f"--out {f.name}")]
    same = [x for f in folders[:1] for x in _rows(f) if x["run"] == n]
    if not same:
        return [*bad, f"no run {n} of {spec} swept in this session to compare with"]
    keys = ("L", "R", "L_c", "R_c", "stable", "fails")
    if any(same[0][k] != row.get(k) for k in keys):
        bad.append(f"run {n} differs from {folders[0].name}/runs.csv")
    return bad


def same_rows(r: Result, s: ShellSession) -> list[str]:
    """On Dask: the same rows as the local pool's sweep of the same spec (same seed)."""
    out = s.cwd / re.search(r"--out (\S+)", r.cmd)[1]
    spec = re.search(r"sweep (\S+\.toml)", r.cmd)[1]
    other = [
        f for f in s.cwd.glob("*.sweep") if f != out and spec in s.history_cmd(f"--out {f.name}")
    ]
    if not other:
        return [f"no local sweep of {spec} in this session to compare with"]
    a = sorted(_rows(out), key=lambda x: int(x["run"]))
    b = sorted(_rows(other[0]), key=lambda x: int(x["run"]))
    return [] if a == b else [f"{out.name} differs from {other[0].name} ({len(a)} vs {len(b)})"]
