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
failure, timeout); then ``rc`` is None. ``kernel`` names the kernel that ran (version and origin).

Which kernel (``tests/uml/kernels.py``): the system's ``user-mode-linux``; where that does not boot
(hosts whose CPU has AMX: ``userspace - ptrace set fp regs failed, errno = 14`` at the first user
process), Debian sid's, fetched once into the user's cache without changing the system.
``SOCKETCAN_LANE_KERNEL=system|sid`` forces one. A kernel that does not boot is told by the
console (:func:`boot_failure`): the cause, never a stack frame.
"""

from __future__ import annotations

import importlib.util
import json
import os
import re
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


def _load(name: str, path: Path):
    if name not in sys.modules:  # loaded by path: this file also runs as a script
        spec = importlib.util.spec_from_file_location(name, path)
        assert spec and spec.loader
        mod = importlib.util.module_from_spec(spec)
        sys.modules[name] = mod
        spec.loader.exec_module(mod)
    return sys.modules[name]


kernels = _load("uml_kernels", HERE / "kernels.py")
#: TPDO1..4 event timers (ms) for drives inside UML (defaults 10, 1, 1, 10 ms): UML spends about
#: 38 µs per system call and moves about 800 frames/s, the default streams are 2,200 frames/s.
#: Given to the job as BENCH_TPDO_EVENT_TIMERS_MS (the scenario bench and vcan_checks apply it).
TPDO_EVENT_TIMERS_MS = (100, 50, 50, 100)
#: drive_link's shortest heartbeat consumer time inside UML (s; DRIVE_LINK_CONSUMER_MIN_S,
#: default 2): at host load 8-9 a drive there fell silent for 2.0-2.3 s during a 64 KiB block
#: upload, and drive_link rightly called it gone (ci34, ci37, ci38)
CONSUMER_MIN_S = 5.0
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
    (wall time of the whole boot-run-poweroff), ``kernel`` (the kernel that ran: version and
    where it came from, see :class:`kernels.Kernel`; empty when none was found), ``booted``
    (False when the kernel stopped before PID 1 ran: the sign for trying Debian sid's)."""

    rc: int | None
    output: str
    problem: str | None
    console: str
    setup: str
    seconds: float
    kernel: str = ""
    booted: bool = True


#: A call-trace line of a kernel stack dump (``[<6069304e>] ? panic+0x0/0x376``): never a cause.
_FRAME = re.compile(r"^\s*\[<[0-9a-fA-F]+>\]")
#: The kernel's ``Run /path/init.sh as init process`` (what follows is what PID 1 met).
_INIT = re.compile(r"^Run \S+ as init process")
#: A host system call that failed, as UML reports it (``..., errno = 14``).
_ERRNO = re.compile(r"\berrno\s*=\s*-?\d+")
_PANIC = "Kernel panic"
#: Bound of :func:`boot_failure`'s line.
CAUSE_CHARS = 300


def boot_failure(console: str) -> str:
    """One line naming why the kernel stopped, from its console: the failure it reported (the
    line with ``errno =``, else the last line after ``Run ... as init process``) and the panic
    line, e.g. ``userspace - ptrace set fp regs failed, errno = 14; Kernel panic - not syncing:
    Attempted to kill init! exitcode=0x0000000b``. Stack dumps and the argument/environment
    listing of init (indented lines) are never the cause."""
    lines = [ln.rstrip() for ln in console.splitlines() if ln.strip() and not _FRAME.match(ln)]
    panic = next((i for i, ln in enumerate(lines) if _PANIC in ln), None)
    before = lines if panic is None else lines[:panic]
    init = max((i for i, ln in enumerate(before) if _INIT.match(ln)), default=None)
    after_init = [] if init is None else [ln for ln in before[init + 1 :] if ln[:1] != " "]
    errnos = [ln for ln in (after_init or before) if _ERRNO.search(ln)]
    cause = (errnos or after_init)[-1:]
    if panic is not None:
        cause.append(lines[panic][lines[panic].index(_PANIC) :])
    if not cause:
        cause = lines[-1:] or ["no console output"]
    text = "; ".join(ln.strip() for ln in cause)
    return text if len(text) <= CAUSE_CHARS else text[: CAUSE_CHARS - 3] + "..."


def unavailable() -> str | None:
    """Why UML cannot run here (one line) before any kernel is chosen, or None."""
    try:
        kernels.choice()
    except kernels.KernelError as exc:
        return str(exc)
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
    extra_args: Sequence[str] = (),
    pass_fds: Sequence[int] = (),
) -> UmlResult:
    """Boot UML, run ``argv`` (in ``cwd``, with ``env`` added to a small clean environment),
    power off; at most ``timeout`` s of wall time (then UML is killed). With ``watch_pid``, UML
    is also killed as soon as that process is gone (the test run that wanted the result).
    ``extra_args`` go on UML's command line (e.g. ``ssl1=fd:5``: a serial line on a host file
    descriptor, which ``pass_fds`` hands to UML; tests/uml/slcan_bridge.py).

    The kernel: ``SOCKETCAN_LANE_KERNEL`` (see the module docstring). With ``auto``, a system
    kernel that does not boot (PID 1 never ran) is followed by Debian sid's."""
    t0 = time.monotonic()
    why = unavailable()
    if why:
        return UmlResult(None, "", why, "", "", 0.0)
    which = kernels.choice()
    try:
        k = kernels.sid_kernel() if which == "sid" else kernels.system_kernel()
    except kernels.KernelError as exc:
        return UmlResult(None, "", str(exc), "", "", time.monotonic() - t0)
    res = _boot(k, argv, timeout, Path(cwd), env or {}, watch_pid, extra_args, pass_fds)
    if res.booted or which != "auto":
        res.seconds = time.monotonic() - t0
        return res
    first = f"{k.label} did not boot: {boot_failure(res.console)}"
    try:
        sid = kernels.sid_kernel()
    except kernels.KernelError as exc:
        res.problem = f"{first}; Debian sid's UML cannot be had: {exc}"
        res.seconds = time.monotonic() - t0
        return res
    left = timeout - (time.monotonic() - t0)
    res = _boot(sid, argv, left, Path(cwd), env or {}, watch_pid, extra_args, pass_fds)
    res.kernel = f"{sid.label}; the system's {first}"
    if not res.booted:
        res.problem = f"no User-Mode Linux boots here: {first}; {res.problem}"
    res.seconds = time.monotonic() - t0
    return res


def _boot(
    k,
    argv: Sequence[str],
    timeout: float,
    cwd: Path,
    env: Mapping[str, str],
    watch_pid: int | None,
    extra_args: Sequence[str] = (),
    pass_fds: Sequence[int] = (),
) -> UmlResult:
    """One boot of kernel ``k`` (a :class:`kernels.Kernel`) running ``argv``."""
    t0 = time.monotonic()
    base = {
        "PYTHONUNBUFFERED": "1",
        "PYTHONDONTWRITEBYTECODE": "1",
        "VIRTUAL_ENV": str(ROOT / ".venv"),
        "BENCH_TPDO_EVENT_TIMERS_MS": ",".join(map(str, TPDO_EVENT_TIMERS_MS)),
        "VIRTUAL_DRIVE_TICK_MS": str(TICK_MS),
        "DRIVE_LINK_CONSUMER_MIN_S": str(CONSUMER_MIN_S),
        "PATH": f"{ROOT / '.venv' / 'bin'}:/usr/local/bin:/usr/bin:/bin:/usr/sbin:/sbin",
    }
    with tempfile.TemporaryDirectory(prefix="uml-job-") as tmp:
        job = Path(tmp)
        (job / "job.sh").write_text(_job_script(argv, cwd, {**base, **env}))
        cmd = [
            k.path,
            f"mem={MEM}",
            "root=/dev/root",
            "rootfstype=hostfs",
            "rootflags=/",
            "rw",
            f"init={INIT}",
            "con=null",
            "con0=fd:0,fd:1",
            f"UML_JOB={job}",
            f"UML_MODULES={k.modules}",
            *extra_args,
        ]
        if any(" " in a for a in cmd):
            problem = f"a path on UML's command line has a space: {' '.join(cmd)}"
            return UmlResult(None, "", problem, "", "", 0.0, k.label)
        console_path = job / "console.txt"
        with open(console_path, "wb") as console:
            try:
                proc = subprocess.Popen(
                    cmd,
                    stdin=subprocess.DEVNULL,
                    stdout=console,
                    stderr=subprocess.STDOUT,
                    start_new_session=True,  # UML's host processes share this group
                    pass_fds=tuple(pass_fds),
                    # UML keeps its run directory in $HOME/.uml and its RAM file in $TMPDIR
                    env={"PATH": os.environ.get("PATH", "/bin"), "HOME": tmp, "TMPDIR": tmp},
                )
            except OSError as exc:
                return UmlResult(None, "", f"cannot start {k.path}: {exc}", "", "", 0.0, k.label)
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
    booted = setup.startswith("uml-init: started")
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
        what = "stopped before the job ended" if booted else "did not boot"
        cause = boot_failure(console_text)
        problem = f"{k.label} {what} (exit {proc.returncode}): {cause}"
    booted = booted or timed_out or orphaned  # a boot still under way is not a boot failure
    return UmlResult(rc, output, problem, console_text, setup, seconds, k.label, booted)


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
        fields = ("rc", "output", "problem", "seconds", "setup", "kernel")
        tmp.write_text(json.dumps({k: getattr(res, k) for k in fields}))
        tmp.replace(out)  # atomic: a reader never sees half a file
    sys.stdout.write(res.output)
    if res.problem:
        print(f"socketcan-lane: {res.problem}", file=sys.stderr)
        return 3
    print(f"socketcan-lane: exit {res.rc} after {res.seconds:.1f} s", file=sys.stderr)
    print(f"socketcan-lane: kernel {res.kernel}", file=sys.stderr)
    return int(res.rc or 0)


if __name__ == "__main__":
    sys.exit(main())
