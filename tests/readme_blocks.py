"""The fenced code blocks of the README and docs/, as a new user reads them (issue 23).

:func:`blocks` parses every Markdown file of the checkout (README.md, docs/*.md, the packages'
READMEs) and returns each fenced block with its file, line, language, section and the HTML
comment marker right above it (``<!-- scripting-example -->``). The tests run every ``sh``/
``bash``/``console`` block through the installed console scripts and every ``python`` block
with the venv's ``python``, except the blocks in :data:`NOT_HERE` (each with its reason and
where it runs instead, if anywhere). :data:`NOT_HERE` is keyed by a block's content hash
(:attr:`Block.key`) or its marker, so a listed block that changes or disappears fails the
inventory test instead of being silently skipped, and a new block is run automatically.

:func:`sessions` cuts the host-run shell blocks into shell sessions: a block that starts no
``virtual-drive … &`` of its own continues the previous block's session (the README's "Tools"
block: "same bus options and environment as above").
"""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

SHELL = frozenset({"sh", "bash", "console", "shell"})
PYTHON = frozenset({"python", "py", "python3"})
#: Languages that hold no command (diagrams, listings). An untagged block must not look like one.
PROSE = frozenset({"", "text", "txt"})
#: Lines of an untagged block that would be a command (it should be tagged sh / python then).
_COMMANDISH = re.compile(
    r"^\s*(\$ |drive-link|virtual-drive|drive-dashboard|python3? |pip |sudo |\. \.venv)"
)


@dataclass(frozen=True)
class Block:
    """One fenced block: ``path`` relative to the checkout, ``line`` of its opening fence
    (1-based), ``lang``, ``text`` (without fences, indentation of the fence removed),
    ``section`` (the nearest heading above it) and ``marker`` (an ``<!-- name -->`` line
    directly above the fence, else "")."""

    path: str
    line: int
    lang: str
    text: str
    section: str
    marker: str

    @property
    def key(self) -> str:
        """Content hash: the first 12 hex digits of the SHA-1 of the block's text."""
        return hashlib.sha1(self.text.encode()).hexdigest()[:12]

    @property
    def where(self) -> str:
        return f"{self.path}:{self.line} [{self.lang or 'untagged'}] ({self.section})"

    def looks_like_commands(self) -> bool:
        return any(_COMMANDISH.match(ln) for ln in self.text.splitlines())


_FENCE = re.compile(r"^(?P<indent>\s*)(?P<fence>`{3,}|~{3,})\s*(?P<lang>[\w+-]*)")
_HEADING = re.compile(r"^#{1,6}\s+(.*?)\s*#*\s*$")
_MARKER = re.compile(r"^\s*<!--\s*([\w.-]+)\s*-->\s*$")


def parse(path: Path) -> list[Block]:
    """The fenced blocks of one Markdown file, in order."""
    rel = path.relative_to(ROOT).as_posix()
    lines = path.read_text(encoding="utf-8").splitlines()
    out: list[Block] = []
    section, i = "", 0
    while i < len(lines):
        ln = lines[i]
        m = _FENCE.match(ln)
        if m is None:
            h = _HEADING.match(ln)
            if h:
                section = h.group(1)
            i += 1
            continue
        fence, indent = m["fence"], len(m["indent"])
        closing = re.compile(rf"^\s*{re.escape(fence[0])}{{{len(fence)},}}\s*$")
        body, j = [], i + 1
        while j < len(lines) and not closing.match(lines[j]):
            body.append(lines[j][indent:] if lines[j][:indent].strip() == "" else lines[j])
            j += 1
        above = lines[i - 1] if i > 0 else ""
        mk = _MARKER.match(above)
        text = "\n".join(body) + "\n"
        out.append(Block(rel, i + 1, m["lang"].lower(), text, section, mk[1] if mk else ""))
        i = j + 1
    return out


def markdown_files() -> list[Path]:
    """README.md, docs/*.md and every other Markdown file of the checkout (no venv, no
    build or hidden folders)."""
    skip = {".venv", "build", "dist", "node_modules", "__pycache__"}
    files = [
        p
        for p in ROOT.rglob("*.md")
        if not any(part in skip or part.startswith(".") for part in p.relative_to(ROOT).parts)
    ]
    return sorted(files, key=lambda p: (p.name != "README.md" or p.parent != ROOT, str(p)))


def blocks() -> list[Block]:
    return [b for p in markdown_files() for b in parse(p)]


# ------------------------------------------------------------------------------------------
# Blocks not run by the generic runner, each with its reason (keyed by Block.key or marker)
# ------------------------------------------------------------------------------------------

#: marker (the ``<!-- name -->`` line above the block) or content hash → where the block runs
#: instead ("run by …") or why it is not run ("not run: …").
NOT_HERE: dict[str, str] = {
    "setup-venv": "run by tests/test_readme_setup.py: in a temporary copy of the checkout, as "
    "written (a new venv, `pip install -e .`, `drive-dashboard --virtual` serving its URL), "
    "with free ports added for the dashboard instead of its fixed defaults 8000/8080",
    "setup-test-command": "not run: it is the test suite itself (pytest inside pytest) and "
    "installs system packages with sudo apt-get",
    "scripting-example": "run by tests/test_link_readme_example.py as written (the CSV it writes "
    "checked against the 50 kHz loop)",
    "socketcan-vcan0": "run by tests/test_readme_socketcan.py inside User-Mode Linux (this "
    "host's kernel has no AF_CAN): its first line is done there by tests/uml/init.sh (PID 1, "
    "root), the other lines run as written",
    "real-can0": "not run: needs a USB-CAN adapter (can0) and root to configure it",
    "api-synopsis-sim": 'not a program: the simulator\'s API synopsis (`sim.set_mode("off" | '
    '"current" | "speed")`); its imports are run (test_synopsis_imports_exist)',
    "api-synopsis-drive-link": "not a program: drive_link's API synopsis "
    "(`drive.nmt_state -> str`); its imports are run (test_synopsis_imports_exist)",
}

#: Lines of a shell block run elsewhere or replaced, as written in the block → why.
LINE_NOT_HERE: dict[str, str] = {
    "sudo modprobe vcan && sudo ip link add dev vcan0 type vcan && sudo ip link set up vcan0": (
        "inside User-Mode Linux tests/uml/init.sh (PID 1, root) loads vcan and brings vcan0 up"
    ),
}


def is_listed(b: Block) -> bool:
    return b.key in NOT_HERE or (b.marker != "" and b.marker in NOT_HERE)


def runnable(b: Block) -> bool:
    """A shell or python block the generic runner runs on this host."""
    return (b.lang in SHELL or b.lang in PYTHON) and not is_listed(b)


def block_by_key(key: str) -> Block:
    found = [b for b in blocks() if key in (b.key, b.marker)]
    assert len(found) == 1, f"no single README/docs block {key!r} ({len(found)} found)"
    return found[0]


# ------------------------------------------------------------------------------------------
# Shell lines and sessions
# ------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Line:
    """One command line of a shell block: ``cmd`` (as written, without its comment),
    ``comment`` (what the README says about it, "" if nothing) and ``shown`` (the comment-only
    lines right after it: an interactive session shown as text)."""

    cmd: str
    comment: str
    shown: tuple[str, ...] = ()

    @property
    def background(self) -> bool:
        return self.cmd.endswith("&") and not self.cmd.endswith("&&")


def _split_comment(ln: str) -> tuple[str, str]:
    """``cmd  # comment`` → (cmd, comment); a ``#`` inside quotes or a word is kept."""
    quote = ""
    for i, ch in enumerate(ln):
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "'\"":
            quote = ch
        elif ch == "#" and (i == 0 or ln[i - 1].isspace()):
            return ln[:i].rstrip(), ln[i + 1 :].strip()
    return ln.rstrip(), ""


def lines_of(b: Block) -> list[Line]:
    """The command lines of a shell block (``$ `` prompts of console blocks removed)."""
    out: list[Line] = []
    for raw in b.text.splitlines():
        ln = raw[2:] if b.lang == "console" and raw.startswith("$ ") else raw
        cmd, comment = _split_comment(ln)
        if cmd.strip():
            out.append(Line(cmd.strip(), comment))
        elif comment and out:  # a comment-only line shows what the line above does
            prev = out[-1]
            shown = ln.split("#", 1)[1].strip()
            out[-1] = Line(prev.cmd, prev.comment, (*prev.shown, shown))
    return out


def starts_drive(b: Block) -> bool:
    return any(ln.background and "virtual-drive" in ln.cmd for ln in lines_of(b))


def uses_drive(b: Block) -> bool:
    """A block with a ``drive-link`` line talks to a drive (else it stands alone: sweeps)."""
    return any(re.match(r"(\S+/)?drive-link\b", ln.cmd) for ln in lines_of(b))


def sessions(bs: list[Block] | None = None) -> list[list[Block]]:
    """The runnable shell blocks in shell sessions: a block that starts no virtual drive of its
    own continues the session of the shell block before it (same file), if both talk to a
    drive or neither does (the sweep blocks need none and share their own session)."""
    out: list[list[Block]] = []
    for b in bs if bs is not None else blocks():
        if b.lang not in SHELL or not runnable(b):
            continue
        prev = out[-1] if out else []
        if (
            prev
            and not starts_drive(b)
            and prev[-1].path == b.path
            and uses_drive(b) == any(uses_drive(p) or starts_drive(p) for p in prev)
        ):
            prev.append(b)
        else:
            out.append([b])
    return out


def session_id(s: list[Block]) -> str:
    return f"{s[0].path}:{s[0].line}"
