"""The SocketCAN lane runs in the background while the rest of the suite runs.

User-Mode Linux is slow per system call (about 38 µs), so the vcan0 suite inside it takes minutes
of wall time but little of it is waiting on the host: it would double the suite's time if it ran
in turn. :func:`start` boots it once per test run, right after collection (``tests/conftest.py``,
only when ``tests/test_socketcan_lane.py::test_socketcan_lane`` is selected), in a detached
``tests/uml/runner.py`` process that writes its result to a JSON file; the lane test, ordered
last, waits for that file with a bounded time (:func:`wait`).

Once per run: with pytest-xdist every worker collects, so the first worker to create the run's
directory (named after ``PYTEST_XDIST_TESTRUNUID``, the same in every worker of one run) starts
the lane. The runner watches the pytest process that owns the run (xdist's controller, or the
single pytest process) and kills UML when that process is gone, so an interrupted run never
leaves UML behind.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import tempfile
import time
from collections.abc import Mapping, Sequence
from pathlib import Path

__all__ = ["RESULT", "failure_message", "failures", "run_dir", "start", "wait"]

HERE = Path(__file__).resolve().parent
RUNNER = HERE / "runner.py"
#: File the runner writes when the lane ends: {"rc", "output", "problem", "seconds"}.
RESULT = "result.json"


def _owner_pid() -> int:
    """PID of the pytest process that owns this run (xdist workers are children of it)."""
    return os.getppid() if os.environ.get("PYTEST_XDIST_WORKER") else os.getpid()


def run_dir() -> Path:
    """The lane's directory for this test run (same path in every xdist worker of the run)."""
    run = os.environ.get("PYTEST_XDIST_TESTRUNUID") or f"pid{_owner_pid()}"
    return Path(tempfile.gettempdir()) / f"socketcan-lane-{run}"


def start(argv: Sequence[str], *, timeout: float, env: Mapping[str, str]) -> Path:
    """Start the lane (``argv`` inside UML, at most ``timeout`` s) unless this run already did;
    returns the run's directory. Never raises for a lane that cannot run: the runner writes
    the one-line reason into the result file."""
    d = run_dir()
    try:
        d.mkdir()
    except FileExistsError:
        return d
    cmd = [sys.executable, str(RUNNER), "--timeout", repr(timeout)]
    cmd += ["--result", str(d / RESULT), "--watch-pid", str(_owner_pid())]
    for k, v in env.items():
        cmd += ["-e", f"{k}={v}"]
    cmd += ["--", *argv]
    with open(d / "runner.log", "wb") as log:
        subprocess.Popen(
            cmd,
            stdin=subprocess.DEVNULL,
            stdout=log,
            stderr=subprocess.STDOUT,
            start_new_session=True,
            cwd=HERE.parent.parent,
        )
    (d / "started").write_text(f"{time.time():.3f}\n")
    return d


def wait(d: Path, timeout: float) -> dict | None:
    """The lane's result (dict) once the runner has written it, None after ``timeout`` s."""
    path = d / RESULT
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if path.exists():
            try:
                return json.loads(path.read_text())
            except json.JSONDecodeError:
                pass  # being written (the runner renames it into place; a partial read is rare)
        time.sleep(1.0)
    return None


#: Bounds of :func:`failure_message`: the first line, one reason in the excerpt, the excerpt.
FIRST_LINE_CHARS = 700
REASON_CHARS = 1200
EXCERPT_CHARS = 6000
_SUMMARY = re.compile(r"^(FAILED|ERROR) (\S+)(?: - (.*))?$")
_HEADER = re.compile(r"^_{3,} (.+?) _{3,}$")
_BLOCK = re.compile(r"^={3,} (FAILURES|ERRORS) ={3,}$")
_END = re.compile(r"^={3,} .* ={3,}$")


def _sections(output: str) -> dict[str, list[str]]:
    """Header → reasons (in order) of the FAILURES/ERRORS sections of pytest's output: the
    first ``E`` line of each (the exception and its message: an assertion's own message), else
    the section's first line (``pytest.fail(..., pytrace=False)`` prints the bare message)."""
    out: dict[str, list[str]] = {}
    inside = False
    header: str | None = None
    body: list[str] = []

    def close() -> None:
        if header is None:
            return
        e = [ln[1:].strip() for ln in body if ln.startswith("E ")]
        plain = [ln.strip() for ln in body if ln.strip() and not ln.startswith("-" * 5)]
        out.setdefault(header, []).append((e or plain or [""])[0])

    for ln in output.splitlines():
        if _BLOCK.match(ln):
            close()
            inside, header, body = True, None, []
        elif inside and _END.match(ln):
            close()
            inside, header, body = False, None, []
        elif inside and (m := _HEADER.match(ln)):
            close()
            header, body = m[1], []
        elif header is not None:
            body.append(ln)
    close()
    return out


def failures(output: str) -> list[tuple[str, str]]:
    """The inner run's failures as (``"FAILED nodeid"`` or ``"ERROR nodeid"``, reason), from
    pytest's ``-rfE`` short summary; the reason is the failure's own first ``E`` line (full
    length: the summary trims it to the terminal width, 80 columns inside UML, which left no
    reason at all after a long node id), else whatever the summary line carried."""
    sections = _sections(output)
    out = []
    for ln in output.splitlines():
        m = _SUMMARY.match(ln)
        if not m:
            continue
        word, nodeid, trimmed = m[1], m[2], (m[3] or "").strip()
        name = ".".join(nodeid.split("::")[1:]) or nodeid
        key = name if word == "FAILED" else None
        if key is None:
            key = next((k for k in sections if k.startswith("ERROR at ") and k.endswith(
                f" of {name}") and sections[k]), f"ERROR at setup of {name}")
        reasons = sections.get(key) or []
        reason = reasons.pop(0) if reasons else trimmed
        out.append((f"{word} {nodeid}", reason or "(no reason printed)"))
    return out


def _cut(text: str, n: int) -> str:
    return text if len(text) <= n else text[: n - 3] + "..."


def failure_message(output: str, what: str = "SocketCAN lane (inside UML)") -> str:
    """The outer assertion's message for an inner run that failed: one line (``what``, the
    inner result line, each failure with the start of its reason), then an excerpt with each
    failure's whole reason; bounded. Without a short summary (pytest itself failed, or the
    job was not pytest), the output's last lines."""
    found = failures(output)
    lines = [ln for ln in output.strip().splitlines() if ln.strip()]
    last = lines[-1].strip("= ") if lines else "no output"
    if not found:
        tail = "\n".join(_cut(ln, 300) for ln in lines[-15:])
        return _cut(f"{what}: {last}", FIRST_LINE_CHARS) + "\n" + _cut(tail, EXCERPT_CHARS)
    heads = [f"{head} - {_cut(reason, 160)}" for head, reason in found]
    first = _cut(f"{what}: {last}: " + "; ".join(heads), FIRST_LINE_CHARS)
    excerpt = "\n".join(f"{head}\n    {_cut(reason, REASON_CHARS)}" for head, reason in found)
    return first + "\n" + _cut(excerpt, EXCERPT_CHARS)
