"""The public API of the host packages (issue 13): typed, ``__all__`` everywhere, private
``_modules`` used only inside their own package, and no protocol fact copied as a literal.

The truth for the last point is the EDS (``firmware_protocol.load_od``: every object index) and
the EMCY code table the drive sends (``firmware_protocol.emcy_codes.EMCY_CODES``) and the CiA 301
store/restore signatures (``firmware_protocol.cia301``): a hex literal in ``drive_link`` or
``dashboard`` code equal to one of them is a copy of a fact that has a home.
"""

from __future__ import annotations

import ast
import importlib
import io
import pkgutil
import tokenize
from pathlib import Path

import pytest

from firmware_protocol import cia301, emcy_codes, load_od

pytestmark = pytest.mark.unit

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("firmware_protocol", "drive_link", "dashboard")
HOST = ("drive_link", "dashboard")


def _modules(package: str) -> list[str]:
    pkg = importlib.import_module(package)
    return [package] + [m.name for m in pkgutil.walk_packages(pkg.__path__, package + ".")]


def _sources(*dirs: str) -> list[Path]:
    return sorted(p for d in dirs for p in (ROOT / d).rglob("*.py"))


@pytest.mark.parametrize("package", PACKAGES)
def test_package_is_typed_and_every_module_declares_its_public_names(package: str) -> None:
    assert (ROOT / package / "py.typed").is_file()
    for name in _modules(package):
        mod = importlib.import_module(name)
        names = getattr(mod, "__all__", None)
        assert isinstance(names, list) and names, f"{name} has no __all__"
        missing = [n for n in names if not hasattr(mod, n)]
        assert not missing, f"{name}.__all__ names missing attributes: {missing}"
        assert len(set(names)) == len(names), f"{name}.__all__ repeats a name"


def _imports(path: Path) -> list[tuple[str, list[str]]]:
    """(module, imported names) of every absolute import in ``path``."""
    out: list[tuple[str, list[str]]] = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            out.append((node.module, [a.name for a in node.names]))
        elif isinstance(node, ast.Import):
            out.extend((a.name, []) for a in node.names)
    return out


def test_no_package_reaches_into_another_packages_private_modules() -> None:
    """Packages use each other's public names only (tests and benchmarks may measure internals)."""
    bad = []
    for path in _sources(*PACKAGES, "virtual_drive"):
        own = path.relative_to(ROOT).parts[0]
        for module, names in _imports(path):
            parts = module.split(".")
            if parts[0] not in PACKAGES or parts[0] == own:
                continue
            if any(p.startswith("_") for p in parts[1:] + names):
                bad.append(f"{path.relative_to(ROOT)}: {module} {names}")
    assert not bad, "private names used outside their package:\n" + "\n".join(bad)


def _hex_literals(path: Path) -> list[tuple[int, int]]:
    """(line, value) of every hexadecimal integer literal in code (not comments or strings)."""
    out = []
    toks = tokenize.generate_tokens(io.StringIO(path.read_text(encoding="utf-8")).readline)
    for tok in toks:
        if tok.type == tokenize.NUMBER and tok.string.lower().startswith("0x"):
            out.append((tok.start[0], int(tok.string.replace("_", ""), 16)))
    return out


def test_host_code_takes_object_indices_and_emcy_codes_from_firmware_protocol() -> None:
    indices = {e.index for e in load_od() if e.index >= 0x1000}
    codes = set(emcy_codes.EMCY_CODES) | {cia301.SAVE_SIGNATURE, cia301.LOAD_SIGNATURE}
    found = []
    for path in _sources(*HOST):
        for line, value in _hex_literals(path):
            if value in indices or value in codes:
                found.append(f"{path.relative_to(ROOT)}:{line}: 0x{value:04X}")
    assert not found, "literal protocol facts in host code:\n" + "\n".join(found)
