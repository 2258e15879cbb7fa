"""Parameter store behind 0x1010 (save) and 0x1011 (restore defaults).

The file holds raw little-endian OD values keyed ``"IIII:SS"`` (hex index and sub-index) in JSON
with a SHA-256 over the canonical parameter text, so a damaged or truncated file is detected.
Writes are atomic: temporary file in the same directory, ``fsync``, ``os.replace``, ``fsync`` of
the directory — a kill at any instant leaves either the old or the new file, never a torn one.
The temporary file has a unique name (``.<name>.<random>.tmp``) and is removed when the write
fails; one left behind by a kill is removed by :func:`remove_stale_temps` when the drive starts.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import tempfile
from pathlib import Path

from firmware_protocol.cia301 import LOAD_SIGNATURE, SAVE_SIGNATURE
from firmware_protocol.enums import StoreStatus

__all__ = [
    "FORMAT",
    "LOAD_SIGNATURE",
    "SAVE_SIGNATURE",
    "VERSION",
    "StoreCorruptError",
    "StoreUnreadableError",
    "load",
    "load_with_status",
    "remove_stale_temps",
    "save",
    "write_atomic",
]

logger = logging.getLogger(__name__)

FORMAT = "bldc-bench-drive-parameters"
VERSION = 1



class StoreCorruptError(ValueError):
    """The parameter file exists but cannot be trusted."""


class StoreUnreadableError(OSError):
    """The parameter file exists (or may) but cannot be read (I/O error, permissions)."""


def _temp_prefix(path: Path) -> str:
    return f".{path.name}."


def remove_stale_temps(path: str | os.PathLike) -> int:
    """Remove temporary files an interrupted :func:`write_atomic` of ``path`` left behind.

    Call it while no other writer of the same store runs (the drive does at start). Returns the
    number of files removed; errors are logged, not raised.
    """
    path = Path(path)
    directory = path.parent if str(path.parent) else Path(".")
    removed = 0
    try:
        names = os.listdir(directory)
    except OSError as exc:
        logger.warning("cannot list %s for stale temporary files: %s", directory, exc)
        return 0
    prefix = _temp_prefix(path)
    for name in names:
        if name.startswith(prefix) and name.endswith(".tmp"):
            try:
                os.unlink(directory / name)
                removed += 1
            except FileNotFoundError:
                pass
            except OSError as exc:
                logger.warning("cannot remove stale %s: %s", name, exc)
    if removed:
        logger.info("removed %d stale temporary file(s) of %s", removed, path)
    return removed


def _key(index: int, subindex: int) -> str:
    return f"{index:04X}:{subindex:02X}"


def _digest(params: dict[str, str]) -> str:
    text = json.dumps(params, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def write_atomic(path: str | os.PathLike, data: bytes) -> None:
    """Replace ``path`` by ``data`` atomically and durably."""
    path = Path(path)
    directory = path.parent if str(path.parent) else Path(".")
    fd, tmp = tempfile.mkstemp(prefix=_temp_prefix(path), suffix=".tmp", dir=directory)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
    dir_fd = os.open(directory, os.O_RDONLY)
    try:
        os.fsync(dir_fd)
    finally:
        os.close(dir_fd)


def save(path: str | os.PathLike, values: dict[tuple[int, int], bytes]) -> None:
    """Store raw OD values ``{(index, sub): bytes}``; an empty dict means "defaults"."""
    params = {_key(i, s): v.hex() for (i, s), v in sorted(values.items())}
    doc = {"format": FORMAT, "version": VERSION, "params": params, "sha256": _digest(params)}
    write_atomic(path, (json.dumps(doc, indent=1, sort_keys=True) + "\n").encode())


def load(path: str | os.PathLike) -> dict[tuple[int, int], bytes]:
    """Stored raw values; ``{}`` if the file does not exist.

    :raises StoreCorruptError: unreadable JSON, wrong format or a checksum mismatch.
    :raises StoreUnreadableError: the file cannot be read (I/O error, permissions, a directory).
    """
    path = Path(path)
    try:
        text = path.read_bytes()
    except FileNotFoundError:
        return {}
    except OSError as exc:
        raise StoreUnreadableError(exc.errno, f"{path}: {exc.strerror or exc}") from exc
    try:
        doc = json.loads(text)
        if doc.get("format") != FORMAT or doc.get("version") != VERSION:
            raise StoreCorruptError(f"{path}: not a parameter file of this drive")
        params = doc["params"]
        if not isinstance(params, dict) or doc.get("sha256") != _digest(params):
            raise StoreCorruptError(f"{path}: checksum mismatch")
        out = {}
        for key, hexval in params.items():
            index, sub = key.split(":")
            out[(int(index, 16), int(sub, 16))] = bytes.fromhex(hexval)
        return out
    except StoreCorruptError:
        raise
    except (ValueError, KeyError, TypeError, AttributeError) as exc:
        raise StoreCorruptError(f"{path}: {exc}") from exc


def load_with_status(
    path: str | os.PathLike | None,
) -> tuple[dict[tuple[int, int], bytes], StoreStatus, str | None]:
    """The store's values, its 0x2060 status and the error text (None if fine): no file
    configured or an empty store -> DEFAULTS, a damaged file -> DAMAGED, an unreadable one ->
    UNREADABLE (both with no values: the defaults apply)."""
    if path is None:
        return {}, StoreStatus.DEFAULTS, None
    try:
        stored = load(path)
    except StoreCorruptError as exc:
        logger.error("parameter file damaged, defaults used: %s", exc)
        return {}, StoreStatus.DAMAGED, str(exc)
    except OSError as exc:
        logger.error("parameter file unreadable, defaults used: %s", exc)
        return {}, StoreStatus.UNREADABLE, str(exc)
    return stored, (StoreStatus.OK if stored else StoreStatus.DEFAULTS), None
