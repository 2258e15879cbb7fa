"""The README's vcan0 block runs as written on a real kernel SocketCAN (issue 23).

This host's kernel has no AF_CAN, so the block runs inside User-Mode Linux (the SocketCAN
lane's runner, ``tests/uml/runner.py``) through ``python tests/readme_session.py
socketcan-vcan0``: the same line-by-line session and checks as the other README blocks. The
block's first line (``sudo modprobe vcan && sudo ip link add … vcan0 && sudo ip link set up
vcan0``) is what the lane's PID 1 (``tests/uml/init.sh``, root) does before the job; the other
two lines run as written: a virtual drive on vcan0 in the background and ``drive-link … status``
against it. ``SOCKETCAN_LANE=off`` skips it, as it skips the lane.
"""

from __future__ import annotations

import importlib.util
import json
import os
import sys
from pathlib import Path

import pytest
import readme_blocks as rb
import readme_session as rs
from test_readme_commands import report

pytestmark = pytest.mark.timeout(400)


def _runner():
    """tests/uml/runner.py, loaded as test_socketcan_lane.py loads it (one module)."""
    if "uml_runner" not in sys.modules:
        path = Path(__file__).resolve().parent / "uml" / "runner.py"
        spec = importlib.util.spec_from_file_location("uml_runner", path)
        assert spec and spec.loader
        sys.modules["uml_runner"] = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(sys.modules["uml_runner"])
    return sys.modules["uml_runner"]


def test_vcan0_block_runs_in_uml(tmp_path):
    if os.environ.get("SOCKETCAN_LANE", "").lower() == "off":
        pytest.skip("SOCKETCAN_LANE=off")
    uml = _runner()
    why = uml.unavailable()
    assert why is None, why
    rb.block_by_key("socketcan-vcan0")  # still in the README
    script = Path(rs.__file__).resolve()
    res = uml.run_in_uml(
        [sys.executable, str(script), "socketcan-vcan0", str(tmp_path)], timeout=300, cwd=rb.ROOT
    )
    assert res.problem is None, f"{res.problem}\n{res.output[-2000:]}"
    line = next((ln for ln in res.output.splitlines() if ln.startswith("READMESESSION ")), None)
    assert res.rc == 0 and line, res.output[-3000:]
    results = [(rs.Result(**r), bad) for r, bad in json.loads(line.split(" ", 1)[1])]
    assert [r.cmd for r, _ in results] == [
        "virtual-drive --interface socketcan --channel vcan0 &",
        "drive-link --interface socketcan --channel vcan0 status",
        "virtual-drive --interface socketcan --channel vcan0 &",  # its end (SIGTERM)
    ]
    failed = report(results)
    assert not failed, failed
