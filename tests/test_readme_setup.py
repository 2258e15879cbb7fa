"""The README's first "Set up" command runs as written on a fresh copy of the checkout (issue 23).

``python3 -m venv .venv && .venv/bin/pip install -e . && .venv/bin/drive-dashboard --virtual``
runs in a temporary copy of the checkout's files (no venv, no build products) with the test
run's venv off PATH, as a new user's shell: the venv is created, the package (with its C
extension) is installed, and the dashboard starts its virtual bench and prints the URL to open,
which must serve the bench's page; Ctrl-C then stops it with exit status 0. The dashboard's
fixed default ports (8000, 8080) are replaced by free ones (``readme_session.localize``).
pip uses its cache and PIP_FIND_LINKS as the user's pip would (about 20 s on an idle host).
"""

from __future__ import annotations

import shutil
import subprocess

import pytest
import readme_blocks as rb
import readme_expect as rx
import readme_session as rs

pytestmark = pytest.mark.timeout(600)

SKIP_DIRS = {".venv", ".git", "build", "dist", "__pycache__", ".ruff_cache", ".pytest_cache"}


def _copy_checkout(dst) -> None:
    """The checkout's tracked and new (not ignored) files, as a fresh clone would have them
    (plus uncommitted edits)."""
    p = subprocess.run(
        ["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
        cwd=rb.ROOT,
        capture_output=True,
        text=True,
        timeout=60,
    )
    if p.returncode == 0:
        for rel in filter(None, p.stdout.split("\0")):
            src = rb.ROOT / rel
            if src.is_file():
                (dst / rel).parent.mkdir(parents=True, exist_ok=True)
                shutil.copy2(src, dst / rel)
    else:  # no git: a source tree
        shutil.copytree(
            rb.ROOT,
            dst,
            dirs_exist_ok=True,
            ignore=lambda d, names: [
                n for n in names if n in SKIP_DIRS or n.endswith((".so", ".o", ".egg-info"))
            ],
        )


def test_setup_block_installs_and_serves_the_bench(tmp_path):
    block = rb.block_by_key("setup-venv")
    copy = tmp_path / "checkout"
    _copy_checkout(copy)
    assert (copy / "pyproject.toml").exists() and not (copy / ".venv").exists()
    session = rs.ShellSession(copy, fresh=True)
    session.ready_timeout = 480.0  # a venv and a build on a loaded host
    try:
        results = rs.run_blocks([block], copy, rx.judge, session=session)
        [(r, bad)] = results
        assert not bad, f"$ {r.cmd}\n{bad}\n{r.err[-2000:]}"
        assert r.extra.get("status") == 200, r.extra
        assert "<html" in r.extra["page"].lower(), r.extra["page"][:300]
        installed = copy / ".venv" / "bin"
        assert all((installed / exe).exists() for exe in ("drive-link", "virtual-drive"))
    finally:
        shutil.rmtree(copy, ignore_errors=True)  # a whole venv: not kept in pytest's tmp
