"""The lane's kernel choice and the sid fetch's archive, without booting or fetching anything.

Truths: the values the README documents for ``SOCKETCAN_LANE_KERNEL``; apt's two sources
formats (deb822 ``.sources`` files and one-line ``sources.list``, sources.list(5)).
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.unit

HERE = Path(__file__).resolve().parent


def _kernels():
    if "uml_kernels" not in sys.modules:
        spec = importlib.util.spec_from_file_location("uml_kernels", HERE / "kernels.py")
        assert spec and spec.loader
        mod = importlib.util.module_from_spec(spec)
        sys.modules["uml_kernels"] = mod
        spec.loader.exec_module(mod)
    return sys.modules["uml_kernels"]


k = _kernels()


@pytest.mark.parametrize(
    ("value", "want"), [("", "auto"), ("auto", "auto"), ("SID", "sid"), (" system ", "system")]
)
def test_choice_reads_the_documented_values(monkeypatch, value, want):
    monkeypatch.setenv("SOCKETCAN_LANE_KERNEL", value)
    assert k.choice() == want


def test_choice_refuses_anything_else_in_one_line(monkeypatch):
    monkeypatch.setenv("SOCKETCAN_LANE_KERNEL", "trixie")
    with pytest.raises(k.KernelError) as err:
        k.choice()
    assert str(err.value) == "SOCKETCAN_LANE_KERNEL='trixie': use one of auto, system, sid"


def test_sid_comes_from_the_systems_own_debian_mirror(tmp_path):
    """deb822: the first Debian archive, not the security one (it has no sid)."""
    (tmp_path / "sources.list.d").mkdir()
    (tmp_path / "sources.list.d" / "debian.sources").write_text(
        "Types: deb\n# http://snapshot.example/archive/debian/20250520T000000Z\n"
        "URIs: http://mirror.example/debian-security\nSuites: bookworm-security\n\n"
        "Types: deb\nURIs: http://mirror.example/debian/\nSuites: bookworm\nComponents: main\n"
    )
    assert k.debian_archive(tmp_path) == "http://mirror.example/debian"


def test_one_line_sources_and_the_default(tmp_path):
    (tmp_path / "sources.list").write_text(
        "# deb http://old.example/debian buster main\n"
        "deb [signed-by=/usr/share/keyrings/debian-archive-keyring.gpg] "
        "https://mirror.example/debian bookworm main\n"
    )
    assert k.debian_archive(tmp_path) == "https://mirror.example/debian"
    assert k.debian_archive(tmp_path / "none") == k.DEFAULT_ARCHIVE


def test_cache_is_per_user(monkeypatch, tmp_path):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert k.cache_root() == tmp_path / "bldc-bench" / "uml-sid"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert k.cache_root() == tmp_path / "home" / ".cache" / "bldc-bench" / "uml-sid"


def test_the_label_names_version_and_origin():
    kern = k.Kernel("/usr/bin/linux.uml", Path("/m"), "6.1.176", "system, /usr/bin/linux.uml")
    assert kern.label == "UML 6.1.176 (system, /usr/bin/linux.uml)"
