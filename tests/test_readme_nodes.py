"""The README's two-drive session (``virtual-drive hub --nodes 1-2``) and its LSS session
(``virtual-drive run --unconfigured 2``, ``drive-link lss``), each run as written on its own hub:
see tests/test_readme_commands.py. In a file of its own so that pytest-xdist runs it beside the
other README sessions."""

from __future__ import annotations

import pytest
import readme_blocks as rb
from test_readme_commands import ELSEWHERE, run_session

pytestmark = pytest.mark.timeout(600)

_MINE = [s for s in rb.sessions() if ELSEWHERE.get(s[0].section) == "tests/test_readme_nodes.py"]


@pytest.mark.parametrize("session", _MINE, ids=rb.session_id)
def test_readme_session_runs_as_written(session, tmp_path):
    run_session(session, tmp_path)
