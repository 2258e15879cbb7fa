"""The house as docs/architecture.md draws it (issue 25).

- import-linter (its own import graph, built by grimp; the contracts in ``[tool.importlinter]``
  of pyproject.toml) keeps the layering (dashboard over drive_link and virtual_drive, both over
  firmware_protocol; drive_link never imports virtual_drive) and finds no import circle between
  the modules of any package at any depth, imports made only for the type checker included
  (``lint-imports`` on the command line runs the same contracts).
- No module reaches into another object's private fields (``obj._x`` where ``obj`` is not
  ``self``/``cls`` or an imported module), read from the source with :mod:`ast`; the only
  reaches left are into two libraries that have no public way to do what is needed
  (:data:`LIBRARY_PRIVATES`, each with its reason).
- No hand-written module is longer than 600 lines (the generated C header aside).
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

pytestmark = [pytest.mark.unit, pytest.mark.timeout(300)]

ROOT = Path(__file__).resolve().parents[1]
COUNTER = ROOT / "benchmarks" / "architecture_counts.py"
#: private names of libraries the project reaches, because the library has no public way
LIBRARY_PRIVATES = {
    "_actions": "argparse: a parser's list of actions (the shell's completion, the bus options)",
    "_choices_actions": "argparse: a sub-parser group's commands (the shell's completion)",
    "_negative_number_matcher": "argparse: let '-1e30' be a value, not an option",
    "_parse_optional": "argparse: the strict parser (no abbreviations) overrides it",
    "_get_value": "argparse: the strict parser's one-line value errors override it",
    "_websock_server": "viser: its websocket server, to refuse share-URL tunnels",
}


def _counter():
    """benchmarks/architecture_counts.py (the one home of the reach finder and the line count),
    loaded by path."""
    spec = importlib.util.spec_from_file_location("architecture_counts", COUNTER)
    assert spec and spec.loader
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_import_contracts_hold(capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch):
    from importlinter.cli import lint_imports

    monkeypatch.chdir(ROOT)  # the contracts are read from ./pyproject.toml
    status = lint_imports(no_cache=True)
    out = capsys.readouterr().out
    assert status == 0, out[out.find("Contracts"):]
    assert "0 broken" in out, out


def test_no_module_reaches_into_another_objects_private_fields():
    counter = _counter()
    found = [r for p in counter.modules().values() for r in counter.reaches(p)]
    ours = [r for r in found if r.rsplit(".", 1)[1] not in LIBRARY_PRIVATES]
    assert not ours, f"{len(ours)} private-field reaches:\n" + "\n".join(ours)
    used = {r.rsplit(".", 1)[1] for r in found}
    assert used == set(LIBRARY_PRIVATES), f"no longer reached: {set(LIBRARY_PRIVATES) - used}"


def test_no_hand_written_module_over_600_lines():
    long = _counter().long_files()
    assert not long, long


def test_the_reach_finder_sees_a_reach(tmp_path: Path):
    """The finder is not blind: ``d._param`` and ``self.drive._ramp`` are reaches; ``self._x``,
    ``cls._y`` and a module's ``os._exit`` are not."""
    probe = ROOT / "drive_link" / "_probe_for_test.py"
    src = "import os\n\nclass A:\n    def f(self, d):\n        self._x = d._param\n" \
          "        cls_ = type(self)\n        os._exit\n        return self.drive._ramp\n"
    probe.write_text(src)
    try:
        found = _counter().reaches(probe)
    finally:
        probe.unlink()
    assert [f.split(": ", 1)[1] for f in found] == ["d._param", "self.drive._ramp"], found
