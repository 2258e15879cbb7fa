"""Every command the README and docs/ show runs as written (issue 23, item 2).

The blocks come from parsing the Markdown (``tests/readme_blocks.py``), so a new block is run
without anyone adding it here. Each shell session (``readme_blocks.sessions``) runs line by
line through the installed console scripts against the virtual drive the README starts
(``tests/readme_session.py``); each line must exit as the README's exit-code table and its
comment say (``tests/readme_expect.py``). Each python block runs with the venv's ``python``.
Blocks that run elsewhere or cannot run here are listed in ``readme_blocks.NOT_HERE`` with
their reason; the inventory tests fail when a listed block is gone, when a block's language is
unknown, or when a commented claim has no check.

The sessions of :data:`ELSEWHERE` run in their own test file, so that pytest-xdist runs them
beside this one (tests/conftest.py groups by file).
"""

from __future__ import annotations

import ast
import re
import subprocess
import sys

import pytest
import readme_blocks as rb
import readme_expect as rx
import readme_session as rs

pytestmark = pytest.mark.timeout(600)

#: Section of a session's first block → the test file that runs it.
ELSEWHERE = {
    "Using drive-link": "tests/test_readme_using.py",
    "Robustness sweeps (`virtual-drive sweep`)": "tests/test_readme_sweeps.py",
    "Loopback hub and several drives": "tests/test_readme_nodes.py",
    "Drives without a node-ID: LSS (CiA 305)": "tests/test_readme_nodes.py",
}


def report(results: list[tuple[rs.Result, list[str]]]) -> str:
    """One paragraph per failing line: the line as written, what went wrong, its output."""
    out = []
    for r, bad in results:
        if bad:
            tail = (r.err.strip() or r.out.strip())[-600:]
            out.append(f"$ {r.cmd}\n  " + "\n  ".join(bad) + f"\n  [output] {tail}")
    return "\n".join(out)


def run_session(session: list[rb.Block], tmp_path) -> None:
    results = rs.run_blocks(session, tmp_path, rx.judge)
    assert results, "no line ran"
    failed = report(results)
    assert not failed, f"{len([1 for _, b in results if b])} of {len(results)} lines:\n{failed}"


def _here() -> list[list[rb.Block]]:
    return [s for s in rb.sessions() if s[0].section not in ELSEWHERE]


@pytest.mark.parametrize("session", _here(), ids=rb.session_id)
def test_readme_session_runs_as_written(session, tmp_path):
    run_session(session, tmp_path)


#: Python blocks no other test runs (today none: each is listed in ``NOT_HERE`` with the test
#: that runs it); a block added without one is run here, as written.
_PYTHON_HERE = [b for b in rb.blocks() if b.lang in rb.PYTHON and rb.runnable(b)]

if _PYTHON_HERE:  # (no test rather than an empty parameter set: pytest reports that skipped)

    @pytest.mark.parametrize("block", _PYTHON_HERE, ids=lambda b: f"{b.path}:{b.line}")
    def test_readme_python_block_runs(block, tmp_path):
        p = subprocess.run(
            [sys.executable, "-"],
            input=block.text,
            cwd=tmp_path,
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert p.returncode == 0, f"{block.where}:\n{p.stderr[-3000:]}"


# ------------------------------------------------------------------------------------------
# The inventory (no process: unit)
# ------------------------------------------------------------------------------------------


@pytest.mark.unit
def test_every_block_is_run_or_listed():
    blocks = rb.blocks()
    assert any(b.path == "README.md" for b in blocks)
    bad = []
    for b in blocks:
        if b.lang not in rb.SHELL | rb.PYTHON | rb.PROSE:
            bad.append(f"{b.where}: unknown language; tag it sh, bash, console or python")
        elif b.lang in rb.PROSE and b.looks_like_commands():
            bad.append(f"{b.where}: untagged block with commands; tag it sh or python")
        elif b.lang in rb.PYTHON and rb.runnable(b):
            try:
                ast.parse(b.text)
            except SyntaxError as exc:
                bad.append(f"{b.where}: not Python ({exc}); fix it or list it in NOT_HERE")
    for key, why in rb.NOT_HERE.items():
        found = [b for b in blocks if key in (b.key, b.marker)]
        if len(found) != 1:
            bad.append(f"NOT_HERE lists {key!r} ({why[:40]}…): {len(found)} blocks have it")
    for s, file in ELSEWHERE.items():
        if not any(ses[0].section == s for ses in rb.sessions(blocks)):
            bad.append(f"no session starts in section {s!r} ({file} runs it)")
    assert not bad, "\n".join(bad)


@pytest.mark.unit
def test_every_claim_has_its_check():
    """A line whose comment claims something (a refusal, a value) is checked, and every
    checked line is still in a block."""
    lines = [
        ln
        for b in rb.blocks()
        if b.lang in rb.SHELL and (rb.runnable(b) or "run by" in rb.NOT_HERE.get(b.marker, ""))
        for ln in rb.lines_of(b)
    ]
    unchecked = [
        f"{ln.cmd}  # {ln.comment}"
        for ln in lines
        if ln.comment and rx.CLAIM.search(ln.comment) and ln.cmd not in rx.EXPECT
    ]
    assert not unchecked, "add these to tests/readme_expect.py EXPECT:\n" + "\n".join(unchecked)
    gone = set(rx.EXPECT) - {ln.cmd for ln in lines}
    assert not gone, f"EXPECT checks lines no README block has any more: {sorted(gone)}"
    assert set(rb.LINE_NOT_HERE) <= {ln.cmd for ln in lines}, "LINE_NOT_HERE lists a gone line"


@pytest.mark.unit
def test_the_parser_reads_what_a_reader_sees():
    """The README's own structure, by another route (a plain regex over the file): as many
    fenced sh/python blocks as the parser returns, and the session lines split at comments."""
    text = (rb.ROOT / "README.md").read_text(encoding="utf-8")
    fences = re.findall(r"^```(sh|bash|console|python)$", text, re.M)
    parsed = [b for b in rb.parse(rb.ROOT / "README.md") if b.lang in rb.SHELL | rb.PYTHON]
    assert len(parsed) == len(fences)
    ln = rb.lines_of(rb.Block("x", 1, "sh", "a 'b # c' d   # e\n#   f> g\n", "s", ""))
    assert ln == [rb.Line("a 'b # c' d", "e", ("f> g",))]


@pytest.mark.unit
def test_synopsis_imports_exist():
    """The API synopses of docs/contracts.md are not programs, but the names they import exist."""
    bad = []
    for b in rb.blocks():
        if not b.marker.startswith("api-synopsis"):
            continue
        stmts = re.findall(r"^(from [\w.]+ import (?:\([^)]*\)|[^\n]*))", b.text, re.M)
        assert stmts, b.where
        for stmt in stmts:
            try:
                exec(compile(stmt, b.where, "exec"), {})
            except Exception as exc:
                bad.append(f"{b.where}: {stmt.splitlines()[0]} … {type(exc).__name__}: {exc}")
    assert not bad, "\n".join(bad)
