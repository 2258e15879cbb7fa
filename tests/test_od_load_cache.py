"""load_od's cache (issue 28): a repeated call neither parses nor resolves the path again, one
view per file whatever the spelling, and a file changed or replaced under the same name is
read again."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

from firmware_protocol.od import EDS_PATH, load_od

pytestmark = pytest.mark.unit


def test_repeated_call_resolves_nothing(monkeypatch) -> None:
    first = load_od()
    calls = []
    real = Path.resolve

    def counting(self: Path, *a: object, **k: object) -> Path:
        calls.append(self)
        return real(self, *a, **k)

    monkeypatch.setattr(Path, "resolve", counting)
    for _ in range(5):
        assert load_od() is first
        assert load_od(EDS_PATH) is first
    assert calls == []  # the sweep validates ~28 parameters per run through load_od


def test_one_view_per_file_whatever_the_spelling(tmp_path, monkeypatch) -> None:
    eds = tmp_path / "drive.eds"
    shutil.copy(EDS_PATH, eds)
    (tmp_path / "link.eds").symlink_to(eds)
    monkeypatch.chdir(tmp_path)
    view = load_od(eds)
    assert load_od("drive.eds") is view
    assert load_od(str(eds)) is view
    assert load_od("link.eds") is view
    assert view.path == eds.resolve()


def test_replaced_file_with_same_size_and_mtime_is_read_again(tmp_path) -> None:
    eds = tmp_path / "drive.eds"
    text = EDS_PATH.read_text(encoding="utf-8")
    eds.write_text(text, encoding="utf-8")
    before = load_od(eds)
    st = os.stat(eds)
    # the same length, another product name, then moved over the old file (a new inode)
    old_name = before.device_info["ProductName"]
    new_name = ("X" * len(old_name))[: len(old_name)]
    new = tmp_path / "new.eds"
    new.write_text(
        text.replace(f"ProductName={old_name}", f"ProductName={new_name}", 1), encoding="utf-8"
    )
    os.utime(new, ns=(st.st_atime_ns, st.st_mtime_ns))
    os.replace(new, eds)
    assert os.stat(eds).st_size == st.st_size and os.stat(eds).st_mtime_ns == st.st_mtime_ns
    after = load_od(eds)
    assert after.device_info["ProductName"] == new_name
    assert load_od(eds) is after


def test_edited_file_is_read_again_and_errors_name_the_file(tmp_path) -> None:
    eds = tmp_path / "drive.eds"
    shutil.copy(EDS_PATH, eds)
    assert load_od(eds).device_info
    eds.write_text("[1000]\nParameterName=broken\n", encoding="utf-8")
    with pytest.raises(ValueError, match="is not a valid drive EDS") as exc:
        load_od(eds)
    assert str(eds.resolve()) in str(exc.value)
    with pytest.raises(FileNotFoundError):
        load_od(tmp_path / "missing.eds")
