"""The README's "Using drive-link" session and the "Tools" block that continues it (same drive,
same environment), run as written: see tests/test_readme_commands.py. In a file of its own so
that pytest-xdist runs it beside the other README session."""

from __future__ import annotations

import pytest
import readme_blocks as rb
from test_readme_commands import ELSEWHERE, run_session

pytestmark = pytest.mark.timeout(600)

_MINE = [s for s in rb.sessions() if ELSEWHERE.get(s[0].section) == "tests/test_readme_using.py"]


@pytest.mark.parametrize("session", _MINE, ids=rb.session_id)
def test_readme_session_runs_as_written(session, tmp_path):
    run_session(session, tmp_path)
