"""The ``unit`` marker cannot lie: inside a unit test, opening a socket or starting a process
fails (tests/conftest.py, ``pytest_runtest_protocol``), so ``pytest -m unit`` runs only tests
that need no process, socket or browser (issue 23, item 6)."""

from __future__ import annotations

import socket
import subprocess

import pytest

pytestmark = pytest.mark.unit


def test_a_unit_test_cannot_bind_or_connect_a_socket():
    with socket.socket() as s, pytest.raises(AssertionError, match="'unit'"):
        s.bind(("127.0.0.1", 0))
    with socket.socket() as s, pytest.raises(AssertionError, match="'unit'"):
        s.connect(("127.0.0.1", 9))


def test_a_unit_test_cannot_start_a_process():
    with pytest.raises(AssertionError, match="'unit'"):
        subprocess.run(["true"], check=False)
