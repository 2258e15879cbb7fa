"""The packages listed in :data:`CLEAN` type-check without an error under the checked-in mypy
configuration (``[tool.mypy]`` in pyproject.toml, python-can's settings); a regression fails
with mypy's own messages.

Truth: mypy itself (``mypy.api.run``, in this process, with a cache in a temporary directory),
and a probe module with one error of each kind the configuration promises to find, so that a
configuration that checks nothing cannot pass.
"""

from __future__ import annotations

import textwrap
import time
from pathlib import Path

import pytest
from mypy import api

pytestmark = [pytest.mark.unit, pytest.mark.timeout(240)]

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "pyproject.toml"

#: the packages mypy checks (each with what it imports): all four, under [tool.mypy]
CLEAN = ("firmware_protocol", "virtual_drive", "drive_link", "dashboard")


@pytest.fixture(scope="module")
def cache(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One mypy cache for both tests (the standard library's stubs are read once)."""
    return tmp_path_factory.mktemp("mypy_cache")


def _mypy(args: list[str], cache: Path) -> tuple[str, int]:
    stdout, stderr, status = api.run(
        ["--config-file", str(CONFIG), "--cache-dir", str(cache), *args]
    )
    return stdout + stderr, status


def test_clean_packages_have_no_type_errors(cache: Path, monkeypatch: pytest.MonkeyPatch):
    monkeypatch.chdir(ROOT)  # the configuration's paths are relative to the repository
    t0 = time.monotonic()
    out, status = _mypy([arg for pkg in CLEAN for arg in ("-p", pkg)], cache)
    assert status == 0, f"mypy found type errors in {', '.join(CLEAN)}:\n{out}"
    assert "Success: no issues found" in out, out
    # (about 2.5 s cold on an idle host; the bound only catches a runaway check)
    assert time.monotonic() - t0 < 120


def test_the_configuration_finds_what_it_promises(
    cache: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
):
    """python-can's settings: a wrong return type, a function returning Any where a type is
    declared (warn_return_any), a half-annotated function (disallow_incomplete_defs), an
    implicit Optional (no_implicit_optional) and an unused ``type: ignore``
    (warn_unused_ignores) are all reported."""
    monkeypatch.chdir(ROOT)
    probe = tmp_path / "typing_probe.py"
    probe.write_text(
        textwrap.dedent(
            """
            import json


            def wrong() -> str:
                return 1


            def any_back(text: str) -> int:
                return json.loads(text)


            def half(x: int, y):  # missing annotations
                return x


            def implicit(x: int = None) -> int:
                return 0


            def clean() -> int:
                return 2  # type: ignore[return-value]
            """
        )
    )
    out, status = _mypy([str(probe)], cache)
    assert status == 1, out
    for code in ("return-value", "no-any-return", "no-untyped-def", "assignment", "unused-ignore"):
        assert f"[{code}]" in out, (code, out)
