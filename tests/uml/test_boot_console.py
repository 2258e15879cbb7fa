"""The runner's one line for a kernel that stopped: the cause from the console, never a frame.

Truth: real UML consoles (``tests/uml/consoles/``):

* ``boot-6.1.176.txt``, ``boot-7.2.7.txt``: normal boots of the lane's init on this machine kind
  (AMD EPYC, host kernel 6.18): bookworm's system UML and Debian sid's, both powered off cleanly;
* ``init-exit-6.1.176.txt``, ``init-exit-7.2.7.txt``: the same kernels with ``init=/bin/false``:
  the kernel panics when init exits and dumps its stack (the 6.1 dump holds the very frame the old
  runner reported, ``[<6069304e>] ? panic+0x0/0x376``);
* ``amx-6.1.176.txt``: what bookworm's UML prints on an Intel Xeon with AMX
  (``../shared/notes/socketcan-in-uml.md``, "Hosts where Debian bookworm's UML does not boot"):
  the note's two lines, ``userspace - ptrace set fp regs failed, errno = 14`` and ``Kernel panic
  - not syncing: Attempted to kill init! exitcode=0x0000000b``, in place of the init-exit panic
  line of ``init-exit-6.1.176.txt`` (that host is not this one; the rest is this host's console).
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.unit

HERE = Path(__file__).resolve().parent
CONSOLES = HERE / "consoles"


def _runner():
    if "uml_runner" not in sys.modules:
        spec = importlib.util.spec_from_file_location("uml_runner", HERE / "runner.py")
        assert spec and spec.loader
        mod = importlib.util.module_from_spec(spec)
        sys.modules["uml_runner"] = mod
        spec.loader.exec_module(mod)
    return sys.modules["uml_runner"]


def console(name: str) -> str:
    return (CONSOLES / name).read_text()


def test_amx_host_names_the_ptrace_failure_and_the_panic():
    line = _runner().boot_failure(console("amx-6.1.176.txt"))
    assert line == (
        "userspace - ptrace set fp regs failed, errno = 14; "
        "Kernel panic - not syncing: Attempted to kill init! exitcode=0x0000000b"
    )


@pytest.mark.parametrize(
    "name",
    ["init-exit-6.1.176.txt", "init-exit-7.2.7.txt"],
)
def test_a_panic_is_named_by_its_reason_not_a_stack_frame(name):
    text = console(name)
    assert "[<" in text and "panic+0x0/" in text  # the dump the old runner quoted from
    line = _runner().boot_failure(text)
    assert line == "Kernel panic - not syncing: Attempted to kill init! exitcode=0x00000100"


@pytest.mark.parametrize("name", ["boot-6.1.176.txt", "boot-7.2.7.txt"])
def test_a_normal_boot_has_no_invented_cause(name):
    """A normal boot prints "failed" lines that are no fault (``mmapper_init - find_iomem
    failed``, ``Failed to initialize ubd device 0``): none is taken for a cause; the line is
    the console's last (the kernel powered off)."""
    text = console(name)
    assert "Failed to initialize ubd device 0" in text
    line = _runner().boot_failure(text)
    assert line == text.strip().splitlines()[-1]
    assert line in ("reboot: System halted", "reboot: Power down")


def test_a_console_cut_short_in_boot_names_its_last_line():
    """Killed during boot (no init yet, no panic): the last line it printed, not a frame."""
    text = console("amx-6.1.176.txt").split("Run /bin/false", 1)[0]
    last = "This architecture does not have kernel memory protection."
    assert _runner().boot_failure(text) == last


def test_no_console_at_all():
    assert _runner().boot_failure("") == "no console output"


def test_the_line_is_one_bounded_line():
    r = _runner()
    text = console("amx-6.1.176.txt").replace("errno = 14", "errno = 14 " + "x" * 1000)
    line = r.boot_failure(text)
    assert "\n" not in line and len(line) <= r.CAUSE_CHARS
