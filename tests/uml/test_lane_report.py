"""The SocketCAN lane's failure message carries each inner failure's own reason.

Truth: the output of a real pytest run (a subprocess, with the lane's own reporting options
and the 80-column terminal UML gives it, where the ``-rfE`` summary trims the reason away after
a long node id) of a file whose failures have known messages. Runs outside UML (about 1 s).
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent


def _lane():
    if "uml_lane" not in sys.modules:
        spec = importlib.util.spec_from_file_location("uml_lane", HERE / "lane.py")
        assert spec and spec.loader
        mod = importlib.util.module_from_spec(spec)
        sys.modules["uml_lane"] = mod
        spec.loader.exec_module(mod)
    return sys.modules["uml_lane"]


INNER = '''
import pytest

ITEMS = "trace: 1999 samples, expected 2000; halt: motor still at 250 rpm after 2.6 s"


@pytest.fixture
def no_bus():
    raise RuntimeError("no vcan0 in this kernel")


@pytest.mark.parametrize("cond", ["vcan0"])
def test_drive_link_check_all_items_with_a_long_name_as_in_the_matrix(cond):
    failed = ITEMS.split("; ")
    assert not failed, f"[{cond}] check failed: {'; '.join(failed)} (run-queue wait 0.31 s/s)"


def test_cli_exit():
    pytest.fail("[vcan0] drive-link check exit 2: error: bad bus", pytrace=False)


def test_needs_bus(no_bus):
    pass


class TestGroup:
    def test_method(self):
        assert 1 + 1 == 3


def test_passes():
    pass
'''


@pytest.fixture(scope="module")
def inner_output(tmp_path_factory) -> str:
    d = tmp_path_factory.mktemp("inner")
    (d / "test_inner_matrix.py").write_text(INNER)
    env = {k: v for k, v in os.environ.items() if k not in ("CI", "BUILD_NUMBER")}
    env.update(COLUMNS="80", PYTHONDONTWRITEBYTECODE="1")
    argv = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-rfE"]
    argv += ["-p", "no:xdist", "-o", "addopts=", "test_inner_matrix.py"]
    r = subprocess.run(argv, cwd=d, env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 1, r.stdout[-2000:] + r.stderr[-2000:]
    return r.stdout


def test_each_failure_comes_with_its_own_reason(inner_output):
    found = dict(_lane().failures(inner_output))
    key = "FAILED test_inner_matrix.py::test_drive_link_check_all_items_with_a_long_name"
    key += "_as_in_the_matrix[vcan0]"
    assert found[key] == (
        "AssertionError: [vcan0] check failed: trace: 1999 samples, expected 2000; "
        "halt: motor still at 250 rpm after 2.6 s (run-queue wait 0.31 s/s)"
    )
    assert found["FAILED test_inner_matrix.py::test_cli_exit"] == (
        "[vcan0] drive-link check exit 2: error: bad bus"
    )
    assert found["ERROR test_inner_matrix.py::test_needs_bus"] == (
        "RuntimeError: no vcan0 in this kernel"
    )
    assert found["FAILED test_inner_matrix.py::TestGroup::test_method"].startswith(
        "assert (1 + 1) == 3"
    )
    assert len(found) == 4


def test_message_is_one_line_then_a_bounded_excerpt(inner_output):
    lane = _lane()
    msg = lane.failure_message(inner_output)
    first, _, excerpt = msg.partition("\n")
    assert first.startswith("SocketCAN lane (inside UML): 3 failed, 1 passed, 1 error")
    assert "halt: motor still at 250 rpm" in first and "no vcan0 in this kernel" in first
    assert len(first) <= lane.FIRST_LINE_CHARS
    assert "trace: 1999 samples, expected 2000" in excerpt
    assert len(excerpt) <= lane.EXCERPT_CHARS


@pytest.mark.unit
def test_without_a_summary_the_last_lines_are_the_reason():
    lane = _lane()
    out = "Traceback (most recent call last):\n" + "  frame\n" * 40 + "ImportError: no canopen\n"
    first, _, excerpt = lane.failure_message(out).partition("\n")
    assert first == "SocketCAN lane (inside UML): ImportError: no canopen"
    assert excerpt.count("\n") == 14 and excerpt.endswith("ImportError: no canopen")
