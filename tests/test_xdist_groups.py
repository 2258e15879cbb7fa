"""The suite's work units hold: with ``pytest -n N`` (``--dist loadgroup``, pyproject) every test
runs in the xdist group tests/conftest.py gives it, so a module-scoped bench (a virtual drive
per matrix condition, two Chromium browsers) is started once, on one worker.

pytest-xdist marks a grouped test by appending ``@<group>`` to its node id on the worker, in its
own collection hook. Two ways lost every group silently: the conftest's hook adding the marks ran
after xdist's (it is ``tryfirst`` now), and pytest 9.2 moved the id to ``Node._id`` while xdist
3.8 still writes ``Node._nodeid`` (pyproject: pytest < 9.2). Then each worker started its own
copy of each bench (a busy CI host ran three pairs of browsers and three drives per condition
at once).
"""

from __future__ import annotations

import os

import pytest


def test_this_test_runs_in_its_xdist_group(request):
    if not os.environ.get("PYTEST_XDIST_WORKER"):
        pytest.skip("not run under pytest-xdist (-n): there are no groups to check")
    group = "tests/test_xdist_groups.py"
    assert request.node.nodeid.endswith(f"@{group}"), (
        f"node id {request.node.nodeid!r} lacks '@{group}': xdist_group marks are ignored "
        "(pytest / pytest-xdist versions that disagree on the node id?)"
    )
