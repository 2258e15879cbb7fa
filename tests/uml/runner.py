"""Run a command inside User-Mode Linux with a real kernel SocketCAN (the SocketCAN lane).

This machine's kernel has no CAN support; Debian's ``user-mode-linux`` package is a second Linux
kernel that runs as an ordinary process and ships the CAN modules. It boots with the host's root
file system (hostfs), so the checkout and its ``.venv`` are visible at the same paths; PID 1 is
``tests/uml/init.sh``, which loads the CAN modules, creates ``vcan0`` (and ``vcan1``, an
adapter-like bus with a 10-frame queue at 1 Mbit/s), runs the job and powers off. Facts and
pitfalls: ``../shared/notes/socketcan-in-uml.md``; UML is slow per system call (about 38 µs),
so it is a place to check behaviour on real SocketCAN, not timing.

Use::

    from tests.uml.runner import run_in_uml      # or: python tests/uml/runner.py -- CMD ...
    res = run_in_uml(["python", "-m", "pytest", "tests/uml/vcan_checks.py"], timeout=300)
    res.rc, res.output, res.problem

``problem`` is one line when UML could not run the job (package missing, boot or setup
failure, timeout); then ``rc`` is None.
"""

from __future__ import annotations

import json
import os
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
INIT = HERE / "init.sh"
#: UML kernel binary (Debian package ``user-mode-linux``; ``linux`` is a symlink to it).
KERNELS = ("linux.uml", "linux")
MODULES = Path("/usr/lib/uml/modules")
#: TPDO1..4 event timers (ms) for drives inside UML (defaults 10, 1, 1, 10 ms): UML spends about
#: 38 µs per system call and moves about 800 frames/s, the default streams are 2,200 frames/s.
#: Given to the job as BENCH_TPDO_EVENT_TIMERS_MS (the scenario bench and vcan_checks apply it).
TPDO_EVENT_TIMERS_MS = (100, 50, 50, 100)
#: Pacing period of virtual drives inside UML (``virtual-drive run --tick-ms``, given as
#: VIRTUAL_DRIVE_TICK_MS): every ``time.monotonic()`` there is a real system call (50 µs), and a
#: drive paced at 1 ms used 84 % of UML's CPU doing nothing (PRE-OPERATIONAL, no PDOs).
TICK_MS = 10
#: Memory of the UML kernel (its RAM is a sparse file; only what is used is allocated).
MEM = "2G"


@dataclass
class UmlResult:
    """What a run inside UML gave: ``rc`` (the job's exit status, None if it did not run to
    the end), ``output`` (its stdout + stderr), ``problem`` (one line, None when the job ran),
    ``console`` (the kernel console: boot messages), ``setup`` (init.sh's log), ``seconds``
    (wall time of the whole boot-run-poweroff)."""

    rc: int | None
    output: str
    problem: str | None
    console: str
    setup: str
    seconds: float


def find_kernel() -> str | None:
    """Path of the UML kernel, or None."""
    for name in KERNELS:
        path = shutil.which(name)
        if path:
            return path
    return None


def unavailable() -> str | None:
    """Why UML cannot run here (one line), or None if it should."""
    kernel = find_kernel()
    if kernel is None:
        return "no User-Mode Linux kernel (linux.uml): apt-get install user-mode-linux"
    if not MODULES.is_dir() or not any(MODULES.iterdir()):
        return f"no UML kernel modules under {MODULES}: apt-get install user-mode-linux"
    missing = [t for t in ("insmod", "ip", "tc") if shutil.which(t) is None]
    if missing:
        return f"missing {', '.join(missing)} (apt-get install kmod iproute2)"
    return None


def _job_script(argv: Sequence[str], cwd: Path, env: Mapping[str, str]) -> str:
    lines = ["#!/bin/sh", f"cd {shlex.quote(str(cwd))} || exit 126"]
    lines += [f"export {k}={shlex.quote(v)}" for k, v in env.items()]
    lines.append("exec " + " ".join(shlex.quote(a) for a in argv))
    return "\n".join(lines) + "\n"


def run_in_uml(
    argv: Sequence[str],
    *,
    timeout: float = 300.0,
    cwd: str | Path = ROOT,
    env: Mapping[str, str] | None = None,
    watch_pid: int | None = None,
) -> UmlResult:
    """Boot UML, run ``argv`` (in ``cwd``, with ``env`` added to a small clean environment),
    power off; at most ``timeout`` s of wall time (then UML is killed). With ``watch_pid``, UML
    is also killed as soon as that process is gone (the test run that wanted the result)."""
    t0 = time.monotonic()
    why = unavailable()
    if why:
        return UmlResult(None, "", why, "", "", 0.0)
    kernel = find_kernel()
    assert kernel is not None
    base = {
        "PYTHONUNBUFFERED": "1",
        "PYTHONDONTWRITEBYTECODE": "1",
        "VIRTUAL_ENV": str(ROOT / ".venv"),
        "BENCH_TPDO_EVENT_TIMERS_MS": ",".join(map(str, TPDO_EVENT_TIMERS_MS)),
        "VIRTUAL_DRIVE_TICK_MS": str(TICK_MS),
        "PATH": f"{ROOT / '.venv' / 'bin'}:/usr/local/bin:/usr/bin:/bin:/usr/sbin:/sbin",
    }
    with tempfile.TemporaryDirectory(prefix="uml-job-") as tmp:
        job = Path(tmp)
        (job / "job.sh").write_text(_job_script(argv, Path(cwd), {**base, **(env or {})}))
        cmd = [
            kernel,
            f"mem={MEM}",
            "root=/dev/root",
            "rootfstype=hostfs",
            "rootflags=/",
            "rw",
            f"init={INIT}",
            "con=null",
            "con0=fd:0,fd:1",
            f"UML_JOB={job}",
        ]
        console_path = job / "console.txt"
        with open(console_path, "wb") as console:
            try:
                proc = subprocess.Popen(
                    cmd,
                    stdin=subprocess.DEVNULL,
                    stdout=console,
                    stderr=subprocess.STDOUT,
                    start_new_session=True,  # UML's host processes share this group
                    # UML keeps its run directory in $HOME/.uml and its RAM file in $TMPDIR
                    env={"PATH": os.environ.get("PATH", "/bin"), "HOME": tmp, "TMPDIR": tmp},
                )
            except OSError as exc:
                return UmlResult(None, "", f"cannot start {kernel}: {exc}", "", "", 0.0)
            timed_out = orphaned = False
            try:
                deadline = time.monotonic() + timeout
                while proc.poll() is None:
                    if time.monotonic() > deadline:
                        timed_out = True
                        break
                    if watch_pid is not None and not _alive(watch_pid):
                        orphaned = True
                        break
                    try:
                        proc.wait(1.0)
                    except subprocess.TimeoutExpired:
                        pass
            finally:
                _kill_group(proc)
        seconds = time.monotonic() - t0

        def read(name: str) -> str:
            p = job / name
            return p.read_text(errors="replace") if p.exists() else ""

        console_text, setup, output = read("console.txt"), read("setup.log"), read("output.txt")
        rc_text = read("rc").strip()
    rc = int(rc_text) if rc_text.lstrip("-").isdigit() else None
    problem = None
    if orphaned:
        problem = f"the test run (pid {watch_pid}) ended before the lane; UML was killed"
        rc = None
    elif timed_out:
        problem = f"User-Mode Linux run exceeded {timeout:g} s and was killed"
        rc = None
    elif rc == 125:
        lines = [ln for ln in setup.splitlines() if ln.startswith("uml-init:")]
        problem = (lines[-1] if lines else "SocketCAN setup inside UML failed") + " (UML)"
        rc = None
    elif rc is None:
        lines = [ln for ln in console_text.splitlines() if ln.strip()]
        panic = [ln for ln in lines if "panic" in ln.lower()]
        last = (panic or lines or ["no console output"])[-1]
        problem = f"User-Mode Linux did not run the job (exit {proc.returncode}): {last[:200]}"
    return UmlResult(rc, output, problem, console_text, setup, seconds)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _kill_group(proc: subprocess.Popen) -> None:
    """Kill what is left of UML's process group (only this run's processes)."""
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass
    try:
        proc.wait(10)
    except subprocess.TimeoutExpired:
        pass


def main(argv: Sequence[str] | None = None) -> int:
    """``python tests/uml/runner.py [--timeout S] [-e NAME=VALUE]... -- CMD ...``: run CMD inside
    UML, print its output, exit with its status (or 3 and one line if UML could not run it)."""
    import argparse

    ap = argparse.ArgumentParser(
        prog="tests/uml/runner.py", description=__doc__.split("\n\n")[0], allow_abbrev=False
    )
    ap.add_argument("--timeout", type=float, default=300.0, help="wall-time limit, s")
    ap.add_argument("-e", "--env", action="append", default=[], help="NAME=VALUE for the job")
    ap.add_argument("--result", help="also write the result as JSON to this file")
    ap.add_argument("--watch-pid", type=int, help="kill UML when this process is gone")
    ap.add_argument("cmd", nargs=argparse.REMAINDER, help="-- command and arguments")
    args = ap.parse_args(argv)
    cmd = args.cmd[1:] if args.cmd[:1] == ["--"] else args.cmd
    if not cmd:
        ap.error("no command given")
    env = dict(e.split("=", 1) for e in args.env)
    res = run_in_uml(cmd, timeout=args.timeout, env=env, watch_pid=args.watch_pid)
    if args.result:
        out = Path(args.result)
        tmp = out.with_suffix(".part")
        fields = ("rc", "output", "problem", "seconds", "setup")
        tmp.write_text(json.dumps({k: getattr(res, k) for k in fields}))
        tmp.replace(out)  # atomic: a reader never sees half a file
    sys.stdout.write(res.output)
    if res.problem:
        print(f"socketcan-lane: {res.problem}", file=sys.stderr)
        return 3
    print(f"socketcan-lane: exit {res.rc} after {res.seconds:.1f} s in UML", file=sys.stderr)
    return int(res.rc or 0)


if __name__ == "__main__":
    sys.exit(main())
