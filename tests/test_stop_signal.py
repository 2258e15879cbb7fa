"""SIGTERM ends ``virtual-drive run`` / ``virtual-drive hub`` whatever the main thread holds.

Truth: a Python signal handler runs in the main thread between two bytecodes (Python's
``signal`` documentation), possibly while that thread holds a lock; a handler that takes a lock
the thread already holds waits for ever. ``threading.Event.set()`` takes the Event's Condition
lock, which the main loop's ``Event.wait()`` holds at moments: a drive once hung that way on
SIGTERM. Each check runs in a child process with a bounded wait, so a hang fails the test
instead of stopping the run.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

pytestmark = pytest.mark.timeout(60)

_CHILD = textwrap.dedent(
    """
    import os, signal, threading, time
    from virtual_drive.stop_signal import StopSignal
    held = threading.Lock()
    with StopSignal() as stop:
        # the main thread holds a lock when the signal comes (as inside Event.wait)
        with held:
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(0.01)  # the handler runs here
        print("requested", stop.requested, "wait", stop.wait(5.0), flush=True)
    print("restored", signal.getsignal(signal.SIGTERM) is signal.SIG_DFL, flush=True)
    """
)


def test_the_stop_request_takes_no_lock_and_the_handlers_are_restored():
    r = subprocess.run(
        [sys.executable, "-c", _CHILD], capture_output=True, text=True, timeout=30
    )
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["requested", "True", "wait", "True", "restored", "True"]

