"""The runner boots real UML kernels: a kernel that stops is reported by its cause in one line,
and a system kernel that does not boot is followed by the fallback kernel (about 5 s).

Truths: the kernel's own console (a real panic: init exits at once), the job's output inside
(``uname -r`` of the kernel that ran it).
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent

pytestmark = pytest.mark.timeout(180)


def _runner():
    if "uml_runner" not in sys.modules:
        spec = importlib.util.spec_from_file_location("uml_runner", HERE / "runner.py")
        assert spec and spec.loader
        mod = importlib.util.module_from_spec(spec)
        sys.modules["uml_runner"] = mod
        spec.loader.exec_module(mod)
    return sys.modules["uml_runner"]


uml = _runner()


@pytest.fixture
def system_kernel():
    if uml.unavailable():
        pytest.skip(f"SocketCAN lane tools missing: {uml.unavailable()}")
    try:
        return uml.kernels.system_kernel()
    except uml.kernels.KernelError as exc:
        pytest.skip(str(exc))


def test_a_kernel_that_panics_is_reported_by_its_reason(system_kernel, monkeypatch):
    """init exits at once (``/bin/false``): the kernel panics and dumps its stack; the one line
    is the panic's reason with the kernel's name, never a stack frame."""
    monkeypatch.setenv("SOCKETCAN_LANE_KERNEL", "system")
    monkeypatch.setattr(uml, "INIT", Path("/bin/false"))
    res = uml.run_in_uml(["true"], timeout=120)
    assert res.rc is None and "[<" in res.console  # a real stack dump was printed
    assert res.problem is not None and "\n" not in res.problem
    assert "[<" not in res.problem, res.problem
    assert res.problem.startswith(f"{system_kernel.label} did not boot (exit "), res.problem
    assert res.problem.endswith(
        ": Kernel panic - not syncing: Attempted to kill init! exitcode=0x00000100"
    ), res.problem


def test_a_system_kernel_that_does_not_boot_is_followed_by_the_fallback(
    system_kernel, monkeypatch, tmp_path
):
    """``auto``: the system's kernel is a stand-in for bookworm's UML on an AMX host (prints
    that console, then aborts as UML does after a panic); the fallback is the real system kernel
    in the place of Debian sid's (no download in the suite). The job runs in the fallback, and
    the report names both: the kernel that ran and why the system's did not."""
    amx = tmp_path / "linux.uml"
    amx.write_text(f"#!/bin/sh\ncat {HERE / 'consoles' / 'amx-6.1.176.txt'}\nkill -ABRT $$\n")
    amx.chmod(0o755)
    stand_in = uml.kernels.Kernel(str(amx), system_kernel.modules, "6.1.176", "AMX host")
    monkeypatch.setenv("SOCKETCAN_LANE_KERNEL", "auto")
    monkeypatch.setattr(uml.kernels, "system_kernel", lambda: stand_in)
    monkeypatch.setattr(uml.kernels, "sid_kernel", lambda: system_kernel)
    res = uml.run_in_uml(["uname", "-r"], timeout=120)
    assert res.problem is None and res.rc == 0, (res.problem, res.setup)
    assert res.output.strip() == system_kernel.version
    assert res.kernel == (
        f"{system_kernel.label}; the system's UML 6.1.176 (AMX host) did not boot: "
        "userspace - ptrace set fp regs failed, errno = 14; "
        "Kernel panic - not syncing: Attempted to kill init! exitcode=0x0000000b"
    )


def test_forced_kernel_that_does_not_boot_is_not_replaced(system_kernel, monkeypatch, tmp_path):
    """``SOCKETCAN_LANE_KERNEL=system``: no fallback; the one line names the console's cause."""
    amx = tmp_path / "linux.uml"
    amx.write_text(f"#!/bin/sh\ncat {HERE / 'consoles' / 'amx-6.1.176.txt'}\nkill -ABRT $$\n")
    amx.chmod(0o755)
    stand_in = uml.kernels.Kernel(str(amx), system_kernel.modules, "6.1.176", "AMX host")
    monkeypatch.setenv("SOCKETCAN_LANE_KERNEL", "system")
    monkeypatch.setattr(uml.kernels, "system_kernel", lambda: stand_in)
    monkeypatch.setattr(uml.kernels, "sid_kernel", lambda: pytest.fail("fallback used"))
    res = uml.run_in_uml(["true"], timeout=60)
    assert res.rc is None
    assert res.problem == (
        "UML 6.1.176 (AMX host) did not boot (exit -6): "
        "userspace - ptrace set fp regs failed, errno = 14; "
        "Kernel panic - not syncing: Attempted to kill init! exitcode=0x0000000b"
    )
