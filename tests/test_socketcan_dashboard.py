"""The dashboard's two-drive session on a real kernel SocketCAN ``vcan0``, in a real browser
(part of the SocketCAN lane: skipped with ``SOCKETCAN_LANE=off``).

vcan0 exists only inside User-Mode Linux, and nothing may listen on a network port for it (UML's
``port:`` channels bind every interface). The route is CAN itself over a serial line, as a
serial-line CAN adapter (slcan) connects a PC to a bus: the test makes a pty pair; UML gets one
end as its serial line 1 (``ssl1=fd:N``); inside, tests/uml/slcan_bridge.py relays ttyS1
(python-can's ``slcan`` interface) ⇄ vcan0 (``socketcan``) with ``can.RedirectReader`` both
ways, and ``virtual-drive run --interface socketcan --channel vcan0 --nodes 1,2`` serves the
drives on vcan0. (The kernel's slcan line discipline routed by can-gw was tried first: UML's
serial line passed only one frame back per frame sent, then ENOBUFS; see the README.)
On the host, ``drive-dashboard --interface slcan --channel /dev/pts/N`` (python-can's slcan
interface, pyserial) opens the other end, and headless Chromium (/usr/bin/chromium) drives
the page: pick node 2, take control, Enable, "+ step".

Truth: every frame on vcan0, written inside UML by a raw python-can socket of its own to a
candump log, decoded with the TPDO1 mapping and COB-ID that canopen reads from the EDS
(statusword 0x6041 and velocity_actual_value 0x606C): node 2 reaches OPERATION ENABLED and
the step's speed (CiA 402 statusword bits, Table 30), node 1 is never enabled and stays at 0.
"""

from __future__ import annotations

import importlib.util
import os
import re
import sys
import tempfile
import threading
import time
from pathlib import Path

import can
import canopen
import pytest
from conftest import PLOT_RATE_ARGS
from test_dashboard_two_drives_e2e import select_node, wait_text

from dashboard.browser import CHROMIUM, click, click_until, launch, open_bench, run_dashboard
from firmware_protocol import EDS_PATH

HERE = Path(__file__).resolve().parent


def _load(name: str, path: Path):
    """tests/uml/runner.py by path, under the name tests/test_socketcan_lane.py gives it."""
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, path)
        assert spec and spec.loader
        mod = importlib.util.module_from_spec(spec)
        sys.modules[name] = mod
        spec.loader.exec_module(mod)
    return sys.modules[name]


uml = _load("uml_runner", HERE / "uml" / "runner.py")

MODE = os.environ.get("SOCKETCAN_LANE", "").strip().lower() or "full"
#: Wall time for UML to boot and the drives to come up on vcan0 on a busy host, s.
READY_S = 240.0
#: The "+ step" button's setpoint, rpm (the dashboard's default step).
STEP_RPM = 500

pytestmark = [
    pytest.mark.timeout(600),
    pytest.mark.skipif(MODE == "off", reason="SocketCAN lane: SOCKETCAN_LANE=off"),
    pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium"),
]


def tpdo1(node_id: int) -> tuple[int, list[tuple[int, int, int]]]:
    """TPDO1's COB-ID and mapping [(index, subindex, bits)] of ``node_id``, read from the EDS by
    canopen (0x1800:1, 0x1A00)."""
    od = canopen.import_od(str(EDS_PATH), node_id)
    cob = int(od[0x1800][1].default) & 0x7FF
    m = od[0x1A00]
    fields = [int(m[s].default) for s in range(1, int(m[0].default) + 1)]
    return cob, [(f >> 16, (f >> 8) & 0xFF, f & 0xFF) for f in fields]


def decode(log: Path, node_id: int) -> list[tuple[float, int, int]]:
    """(time, statusword, velocity_actual_value) of every TPDO1 of ``node_id`` on vcan0."""
    cob, mapping = tpdo1(node_id)
    assert [(i, b) for i, _, b in mapping] == [(0x6041, 16), (0x606C, 32)], mapping
    out = []
    for msg in can.LogReader(str(log)):
        if msg.arbitration_id == cob and len(msg.data) >= 6:
            sw = int.from_bytes(msg.data[0:2], "little")
            v = int.from_bytes(msg.data[2:6], "little", signed=True)
            out.append((msg.timestamp, sw, v))
    return out


def operation_enabled(sw: int) -> bool:
    """CiA 402 Table 30: xxxx xxxx x01x 0111."""
    return sw & 0x6F == 0x27


def test_dashboard_two_drives_on_vcan0_in_a_browser(tmp_path):
    out = Path(tempfile.mkdtemp(prefix="slcan-", dir=tmp_path))
    master, slave = os.openpty()  # UML: master (ttyS1); the dashboard opens the slave's path
    pts = os.ttyname(slave)
    res: dict[str, uml.UmlResult] = {}

    def boot() -> None:
        res["uml"] = uml.run_in_uml(
            [sys.executable, str(HERE / "uml" / "slcan_bridge.py")],
            timeout=READY_S + 300,
            env={"SLCAN_OUT": str(out), "SLCAN_HOLD_S": "300"},
            extra_args=[f"ssl1=fd:{master}"],
            pass_fds=[master],
        )

    t0 = time.monotonic()
    th = threading.Thread(target=boot, name="uml", daemon=True)
    th.start()
    try:
        while not (out / "ready").exists() and th.is_alive():
            assert time.monotonic() - t0 < READY_S, "drives on vcan0 not up in time"
            time.sleep(0.2)
        if not th.is_alive():
            r = res["uml"]
            pytest.fail(f"UML ended before the drives were up: {r.problem or r.output[-1500:]}")
        t_ready = time.monotonic() - t0
        args = ["--interface", "slcan", "--channel", pts, "--node", "1", "--no-3d", *PLOT_RATE_ARGS]
        args += ["--bus-kwargs", "sleep_after_open=0"]
        with run_dashboard(args, timeout=120) as dash:
            from playwright.sync_api import sync_playwright

            with sync_playwright() as p:
                browser = launch(p)
                page = browser.new_context(viewport={"width": 1280, "height": 800}).new_page()
                page.set_default_timeout(90_000)
                open_bench(page, dash.gui_url)
                wait_text(page, r"node 2\s+(OPERATIONAL|PRE-OPERATIONAL)", 90)
                select_node(page, 2)
                click(page, page.get_by_role("button", name="Take control"))
                wait_text(page, r"In control: browser #\d+ \(you\)", 60)
                click_until(
                    page, page.get_by_role("button", name="Enable"),
                    lambda t: wait_text(page, r"OPERATION ENABLED", t),
                )  # fmt: skip
                click(page, page.get_by_role("button", name="+ step"))
                wait_text(page, rf"\(set {STEP_RPM}\)", 60)
                m = None
                deadline = time.monotonic() + 60
                while time.monotonic() < deadline:
                    m = re.search(r"speed ([-\d.]+) rpm \(set (-?\d+)\)", page.inner_text("body"))
                    if m and abs(float(m.group(1)) - STEP_RPM) < 5:
                        break
                    time.sleep(0.2)
                assert m and abs(float(m.group(1)) - STEP_RPM) < 5, m and m.group(0)
                time.sleep(1.0)  # a few more TPDOs at the new speed on vcan0
                browser.close()
        t_session = time.monotonic() - t0 - t_ready
    finally:
        (out / "done").write_text("done\n")
        th.join(120)
        os.close(slave)
        os.close(master)
    r = res["uml"]
    assert r.rc == 0, f"inside UML: {r.problem or ''} {r.output[-2000:]}"
    print(f"UML + drives ready in {t_ready:.0f} s, browser session {t_session:.0f} s, "
          f"all {r.seconds:.0f} s ({r.kernel}), load {os.getloadavg()[0]:.1f}")  # fmt: skip

    # the truth on vcan0
    two = decode(out / "vcan0.log", 2)
    one = decode(out / "vcan0.log", 1)
    assert two and one, "no TPDO1 of node 1 or node 2 on vcan0"
    enabled = [(t, v) for t, sw, v in two if operation_enabled(sw)]
    assert enabled, f"node 2 never OPERATION ENABLED on vcan0: {[hex(s) for _, s, _ in two[-5:]]}"
    assert any(abs(v - STEP_RPM) < 5 for _, v in enabled), f"node 2 on vcan0: {enabled[-5:]}"
    assert not any(operation_enabled(sw) for _, sw, _ in one), "node 1 was enabled"
    assert {v for _, _, v in one} == {0}, "node 1 turned"
