"""Run the README's shell blocks line by line, as a user types them (issue 23).

One :class:`ShellSession` is one user's shell: each line runs in ``bash`` with the variables the
lines before it left (``. .venv/bin/activate``, ``H=…``, ``export …``), in a scratch folder
whose ``.venv`` is the venv running the tests, so ``drive-link``, ``virtual-drive`` and
``drive-dashboard`` are its console scripts and ``python`` its interpreter. Each line gets its
own exit status, stdout and stderr (:class:`Result`), checked by ``tests/readme_expect.py``.

- ``cmd &`` starts in the background; the session goes on once it printed that it is ready
  (:data:`READY`, e.g. ``virtual-drive: node 1 ready on …``), as a user waits for that line;
  :meth:`ShellSession.close` stops it with SIGTERM (``kill %1``) and reports an unclean end.
- Lines that need a terminal or run until stopped are driven as a user would
  (:func:`interactive`): ``drive-link shell`` on a pseudo-terminal, typing the session the
  README shows in the comment lines under it (TAB completion included) and ending with Ctrl-D;
  ``drive-link live --plot`` on a pseudo-terminal, quit with ``x``; ``drive-dashboard`` until
  it prints its URL, which must answer, then Ctrl-C.
- Fixed TCP ports of the README (``--hub-port 29600``) become free ports for the run
  (:meth:`ShellSession.localize`): tests never bind fixed ports (several run at once).

``python tests/readme_session.py MARKER`` runs one listed block this way and prints the
results as JSON (the SocketCAN test runs it inside User-Mode Linux).
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
import pty
import re
import signal
import socket
import struct
import subprocess
import sys
import termios
import threading
import time
import urllib.request
from dataclasses import asdict, dataclass, field
from pathlib import Path

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parent))
from conftest import RunQueueProbe
from readme_blocks import LINE_NOT_HERE, ROOT, Block, Line, lines_of

#: First word of a background command → what it prints when it is ready (once per node or
#: worker it starts, :func:`ready_count`): ``virtual-drive: node 1 ready on …``, ``virtual-drive:
#: node 2 ready (pid …)`` of ``hub --nodes``, ``… unconfigured drive(s) … ready on``; Dask's
#: scheduler and each worker process.
READY = {
    "virtual-drive": re.compile(r"\bready\b"),
    "dask scheduler": re.compile(r"Scheduler at:"),
    "dask worker": re.compile(r"Registered to:"),
}


def ready_pattern(cmd: str) -> re.Pattern | None:
    words = cmd.split()
    return READY.get(" ".join(words[:2])) or READY.get(words[0] if words else "")


def ready_count(cmd: str) -> int:
    """How many ready lines a background command prints: one per node of ``--nodes 1-2`` /
    ``--nodes 1,2``, one per worker process of ``--nworkers N``, else one."""
    m = re.search(r"--nodes[ =](\d+)-(\d+)", cmd)
    if m:
        return int(m[2]) - int(m[1]) + 1
    m = re.search(r"--nodes[ =]([\d,]+)", cmd)
    if m:
        return len(m[1].split(","))
    m = re.search(r"--nworkers[ =](\d+)", cmd)
    return int(m[1]) if m else 1


#: Wall-time limit of one foreground line (s); `check` and `record --seconds 10s` take 10-30 s.
LINE_TIMEOUT = 180.0
#: How long a background command may take to say it is ready (s; a loaded host is slow).
READY_TIMEOUT = 90.0
#: Variables of the caller's environment that would change what a README line does.
_CLEAN = (
    "DRIVE_LINK_HOST",
    "DRIVE_LINK_PORT",
    "DRIVE_LINK_NODE",
    "CAN_INTERFACE",
    "CAN_CHANNEL",
    "CAN_BITRATE",
    "VIRTUAL_ENV",
    "DRIVE_DASHBOARD_TOKEN",
)


@dataclass
class Result:
    """What one line did: ``rc`` (None: it did not end), ``out``/``err`` (text), ``seconds``,
    ``problem`` (one line when the harness itself had to give up on it)."""

    cmd: str
    comment: str
    rc: int | None
    out: str = ""
    err: str = ""
    seconds: float = 0.0
    problem: str = ""
    extra: dict = field(default_factory=dict)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _strip_ansi(text: str) -> str:
    return re.sub(r"\x1b(\[[0-9;?]*[ -/]*[@-~]|[()][0-9A-Za-z]|[=>])", " ", text)


class _Reader(threading.Thread):
    """Collects a pipe or pty master in the background (``text``)."""

    def __init__(self, fd: int) -> None:
        super().__init__(daemon=True)
        self.fd, self.buf, self.lock = fd, bytearray(), threading.Lock()
        self.start()

    def run(self) -> None:
        while True:
            try:
                data = os.read(self.fd, 65536)
            except OSError:
                return
            if not data:
                return
            with self.lock:
                self.buf += data

    @property
    def text(self) -> str:
        with self.lock:
            return self.buf.decode(errors="replace")

    def wait_for(self, pattern: re.Pattern, timeout: float, proc=None) -> re.Match | None:
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            m = pattern.search(_strip_ansi(self.text))
            if m:
                return m
            if proc is not None and proc.poll() is not None:
                time.sleep(0.2)
                return pattern.search(_strip_ansi(self.text))
            time.sleep(0.1)
        return None


class ShellSession:
    """One user's shell in ``cwd`` (see the module's docstring)."""

    def __init__(self, cwd: Path, venv: Path | None = None, fresh: bool = False) -> None:
        """``fresh``: a new user's shell in a checkout without a venv (the "Set up" block):
        no ``.venv`` link, the test run's venv taken off PATH."""
        self.cwd = Path(cwd)
        self.cwd.mkdir(parents=True, exist_ok=True)
        venv = Path(venv or sys.prefix)
        env = {k: v for k, v in os.environ.items() if k not in _CLEAN}
        path = [d for d in env.get("PATH", "").split(os.pathsep) if Path(d) != venv / "bin"]
        if not fresh:
            link = self.cwd / ".venv"
            if not link.exists():
                link.symlink_to(venv)
            path.insert(0, str(venv / "bin"))
            # the README's lines run in the checkout: its example files (sweep specs)
            ex = self.cwd / "examples"
            if not ex.exists():
                ex.symlink_to(ROOT / "examples")
        env["PATH"] = os.pathsep.join(path)
        env["PYTHONUNBUFFERED"] = "1"
        self.env = env
        self.ports: dict[str, str] = {}
        self.ready_timeout = READY_TIMEOUT
        self.background: list[tuple[Result, subprocess.Popen, _Reader, _Reader]] = []
        self.history: list[str] = []

    def history_cmd(self, part: str) -> str:
        """The last line run in this session that contains ``part`` (as localized), or ""."""
        return next((c for c in reversed(self.history) if part in c), "")

    def localize(self, cmd: str) -> str:
        """The README's fixed ports replaced by free ones (the same one all session): a hub's
        ``--hub-port N``, and ``--port N`` of a command started in the background (``virtual-drive
        hub``, ``dask scheduler``); later lines (``H="--port N"``, ``tcp://…:N``) get the same."""
        ports = re.findall(r"--hub-port[ =](\d+)", cmd)
        if cmd.rstrip().endswith("&") and not cmd.rstrip().endswith("&&"):
            ports += re.findall(r"(?<![\w-])--port[ =](\d+)", cmd)
        for n in ports:
            self.ports.setdefault(n, str(free_port()))
        for readme, here in self.ports.items():
            cmd = re.sub(rf"\b{readme}\b", here, cmd)
        if re.search(r"drive-dashboard\b", cmd) and "--port" not in cmd:
            # its defaults are fixed ports (API 8000, GUI 8080)
            extra = f" --port {free_port()} --gui-port {free_port()}"
            cmd = re.sub(r"(drive-dashboard\b[^&;|]*)", lambda m: m[1].rstrip() + extra, cmd)
        return cmd

    def _script(self, cmd: str, envfile: Path) -> str:
        return f"set -a\n{cmd}\n__rc=$?\nenv -0 > '{envfile}'\nexit $__rc\n"

    def _take_env(self, envfile: Path) -> None:
        if envfile.exists():
            pairs = [p.split("=", 1) for p in envfile.read_text().split("\0") if "=" in p]
            self.env = {k: v for k, v in pairs if k not in ("_", "__rc", "SHLVL")}
            envfile.unlink()

    def run(self, line: Line) -> Result:
        cmd = self.localize(line.cmd)
        self.history.append(cmd)
        if line.background:
            return self._start(line, cmd[:-1].rstrip())
        if re.fullmatch(r"kill(\s+%[%+\-\d]*)+", cmd.strip()):
            return self._kill_jobs(line, cmd.split()[1:])
        handler = interactive(cmd)
        if handler is not None:
            return handler(self, line, cmd)
        envfile = self.cwd / ".readme-env"
        t0 = time.monotonic()
        probes = [RunQueueProbe(p.pid) for _, p, _, _ in self.background if p.poll() is None]
        try:
            p = subprocess.run(
                ["bash", "-c", self._script(cmd, envfile)],
                cwd=self.cwd,
                env=self.env,
                capture_output=True,
                text=True,
                stdin=subprocess.DEVNULL,
                timeout=LINE_TIMEOUT,
            )
        except subprocess.TimeoutExpired as exc:
            return Result(
                line.cmd,
                line.comment,
                None,
                str(exc.stdout or ""),
                str(exc.stderr or ""),
                LINE_TIMEOUT,
                f"no end in {LINE_TIMEOUT:g} s",
            )
        self._take_env(envfile)
        wait = max([pr.stop() for pr in probes], default=0.0)
        res = Result(
            line.cmd, line.comment, p.returncode, p.stdout, p.stderr, time.monotonic() - t0
        )
        # run-queue wait of the background drive meanwhile, s/s (tests/conftest.py)
        res.extra["drive_wait"] = wait
        return res

    def run_text(self, cmd: str) -> Result:
        """A further command in this session (a check's own probe)."""
        return self.run(Line(cmd, ""))

    def _kill_jobs(self, line: Line, specs: list[str]) -> Result:
        """``kill %%`` / ``kill %2 %1``: SIGTERM to those background jobs of this session (bash's
        job numbers: %1 the first started, %% and %+ the last, %- the one before); their ends
        are reported by :meth:`close`."""
        t0 = time.monotonic()
        res = Result(line.cmd, line.comment, 0)
        jobs = [p for _, p, _, _ in self.background]
        for spec in specs:
            n = {"%": len(jobs), "%%": len(jobs), "%+": len(jobs), "%-": len(jobs) - 1}.get(
                spec, int(spec[1:]) if spec[1:].isdigit() else 0
            )
            if not 1 <= n <= len(jobs) or jobs[n - 1].poll() is not None:
                res.rc, res.err = 1, f"bash: kill: {spec}: no such job\n"
                continue
            jobs[n - 1].send_signal(signal.SIGTERM)
        for spec in specs:
            with contextlib.suppress(subprocess.TimeoutExpired, ValueError, IndexError):
                n = len(jobs) if spec in ("%", "%%", "%+") else int(spec[1:])
                jobs[n - 1].wait(20)
        res.seconds = time.monotonic() - t0
        return res

    def _start(self, line: Line, cmd: str) -> Result:
        simple = not re.search(r"[;&|]", cmd)
        p = subprocess.Popen(
            ["bash", "-c", f"set -a\n{'exec ' if simple else ''}{cmd}"],
            cwd=self.cwd,
            env=self.env,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
        )
        assert p.stdout is not None and p.stderr is not None
        out, err = _Reader(p.stdout.fileno()), _Reader(p.stderr.fileno())
        res = Result(line.cmd, line.comment, None)
        self.background.append((res, p, out, err))
        ready, count = ready_pattern(cmd), ready_count(cmd)
        t0 = time.monotonic()
        if ready is not None:
            end = t0 + READY_TIMEOUT
            while time.monotonic() < end and p.poll() is None:
                if len(ready.findall(out.text)) + len(ready.findall(err.text)) >= count:
                    break
                time.sleep(0.1)
            else:
                res.problem = (
                    f"exited {p.returncode} before it was ready"
                    if p.poll() is not None
                    else f"not ready in {READY_TIMEOUT:g} s"
                )
        res.out, res.err, res.seconds = out.text, err.text, time.monotonic() - t0
        res.extra["ready"] = not res.problem
        return res

    def close(self) -> list[Result]:
        """Stop the background commands (SIGTERM, as ``kill %1``); their results with the exit
        status (a clean stop is 0, or -15 if the program keeps SIGTERM's default)."""
        done = []
        for res, p, out, err in self.background:
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
                try:
                    p.wait(20)
                except subprocess.TimeoutExpired:
                    p.kill()
                    p.wait(10)
                    res.problem = "did not stop within 20 s of SIGTERM (killed)"
            time.sleep(0.2)
            res.rc, res.out, res.err = p.returncode, out.text, err.text
            done.append(res)
        self.background.clear()
        return done


# ------------------------------------------------------------------------------------------
# Lines that need a terminal or run until stopped
# ------------------------------------------------------------------------------------------


def _pty_spawn(session: ShellSession, cmd: str) -> tuple[subprocess.Popen, int, _Reader]:
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 40, 120, 0, 0))
    env = {**session.env, "TERM": "xterm", "HOME": str(session.cwd)}
    p = subprocess.Popen(
        ["bash", "-c", f"exec {cmd}"],
        cwd=session.cwd,
        env=env,
        stdin=slave,
        stdout=slave,
        stderr=slave,
        start_new_session=True,
        preexec_fn=lambda: fcntl.ioctl(0, termios.TIOCSCTTY, 0),
    )
    os.close(slave)
    return p, master, _Reader(master)


def _pty_end(p: subprocess.Popen, master: int, res: Result, timeout: float = 20.0) -> None:
    try:
        res.rc = p.wait(timeout)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        p.wait(10)
        res.problem = res.problem or f"did not end within {timeout:g} s"
    with contextlib.suppress(OSError):
        os.close(master)


def _shell(session: ShellSession, line: Line, cmd: str) -> Result:
    """``drive-link shell`` on a terminal: type the session its comment lines show."""
    t0 = time.monotonic()
    p, master, reader = _pty_spawn(session, cmd)
    res = Result(line.cmd, line.comment, None)
    prompt = re.compile(r"drive-link\[\d+\]> ")
    typed: list[str] = []
    try:
        for shown in line.shown:
            m = re.match(r"(drive-link\[\d+\]>)\s+(.*)$", shown)
            if m is None:
                continue
            text = re.split(r"\s{2,}", m[2])[0]
            completes = re.search(r"→\s*(\S+)", m[2])
            before = len(prompt.findall(_strip_ansi(reader.text)))
            if (
                reader.wait_for(
                    re.compile(rf"(?:{prompt.pattern}.*){{{max(before, 1)}}}", re.S), 60, p
                )
                is None
            ):
                res.problem = f"no prompt before {text!r}"
                break
            if "<TAB>" in text:
                os.write(master, text.replace("<TAB>", "\t").encode())
                want = completes[1] if completes else ""
                if want and reader.wait_for(re.compile(re.escape(want)), 10, p) is None:
                    res.problem = f"TAB did not complete {text!r} to {want}"
                    break
            else:
                os.write(master, text.encode())
            os.write(master, b"\r")
            typed.append(text)
            time.sleep(0.3)
        if not res.problem:
            n = len(typed) + 1
            if reader.wait_for(re.compile(rf"(?:{prompt.pattern}.*){{{n}}}", re.S), 60, p) is None:
                res.problem = "no prompt after the last line"
        os.write(master, b"\x04")  # Ctrl-D ends the session
    finally:
        _pty_end(p, master, res)
    res.out, res.seconds = _strip_ansi(reader.text), time.monotonic() - t0
    res.extra["typed"] = typed
    return res


def _live_terminal(session: ShellSession, line: Line, cmd: str, key: bytes = b"x") -> Result:
    """``drive-link live --plot …`` on a terminal: wait for its panels, then ``key`` (``x``
    quits leaving the drive as it is)."""
    t0 = time.monotonic()
    p, master, reader = _pty_spawn(session, cmd)
    res = Result(line.cmd, line.comment, None)
    signals = cmd.split("--plot", 1)[1].split()
    try:
        if reader.wait_for(re.compile(r"dropped"), 60, p) is None:
            res.problem = "no frame drawn in 60 s"
        time.sleep(1.0)
        res.extra["screen"] = _strip_ansi(reader.text)
        res.extra["signals"] = signals
        os.write(master, key)
    finally:
        _pty_end(p, master, res)
    res.out, res.seconds = _strip_ansi(reader.text), time.monotonic() - t0
    return res


def _until_stopped(session: ShellSession, line: Line, cmd: str) -> Result:
    """A server that runs until Ctrl-C (``drive-dashboard``): its URL must answer."""
    t0 = time.monotonic()
    simple = not re.search(r"[;&|]", cmd)
    p = subprocess.Popen(
        ["bash", "-c", f"set -a\n{'exec ' if simple else ''}{cmd}"],
        cwd=session.cwd,
        env=session.env,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        start_new_session=True,  # its own group, as a terminal's foreground job
    )
    assert p.stdout is not None and p.stderr is not None
    out, err = _Reader(p.stdout.fileno()), _Reader(p.stderr.fileno())
    res = Result(line.cmd, line.comment, None)
    m = out.wait_for(re.compile(r"open (http://\S+)"), session.ready_timeout, p)
    if m is None:
        res.problem = "printed no URL to open"
    else:
        try:
            with urllib.request.urlopen(m[1], timeout=30) as r:
                res.extra.update(url=m[1], status=r.status, page=r.read(4096).decode("latin-1"))
        except OSError as exc:
            res.problem = f"{m[1]} did not answer: {exc}"
    with contextlib.suppress(ProcessLookupError):
        os.killpg(p.pid, signal.SIGINT)  # Ctrl-C reaches the terminal's foreground group
    try:
        res.rc = p.wait(30)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        p.wait(10)
        res.problem = res.problem or "did not stop within 30 s of Ctrl-C (killed)"
    time.sleep(0.2)
    res.out, res.err, res.seconds = out.text, err.text, time.monotonic() - t0
    return res


def interactive(cmd: str):
    """The handler of a line that needs a terminal or runs until stopped, else None."""
    words = cmd.split()
    if words[:2] == ["drive-link", "shell"]:
        return _shell
    if words[:2] == ["drive-link", "live"] and "--plot" in words and "--frames" not in words:
        return _live_terminal
    if re.search(r"(^|/)drive-dashboard\b", cmd):
        return _until_stopped
    return None


def run_blocks(blocks: list[Block], cwd: Path, judge=None, session: ShellSession | None = None):
    """Every line of ``blocks`` in one session; ``judge(result, session) -> [problems]`` looks
    at each line right after it ran (the session still open); the background commands' ends
    come last (judged with session None); ``judge.before(line, session)``, if the judge has
    one, looks before the line runs (its answer in ``result.extra["before"]``). Returns
    [(result, problems)]."""
    session = session or ShellSession(cwd)
    out: list[tuple[Result, list[str]]] = []
    before = getattr(judge, "before", None)
    try:
        for b in blocks:
            for line in lines_of(b):
                if line.cmd in LINE_NOT_HERE:
                    continue
                seen = before(line, session) if before else None
                r = session.run(line)
                if seen is not None:
                    r.extra["before"] = seen
                out.append((r, judge(r, session) if judge else []))
    finally:
        for r in session.close():
            out.append((r, judge(r, None) if judge else []))
    return out


def main(argv: list[str]) -> int:
    """``python tests/readme_session.py MARKER CWD``: run that block, print JSON results."""
    from readme_blocks import block_by_key
    from readme_expect import judge

    results = run_blocks([block_by_key(argv[0])], Path(argv[1]), judge)
    print("READMESESSION " + json.dumps([[asdict(r), bad] for r, bad in results]))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
