"""One gain-apply path (drive_link.workflows.gains.apply_gains) with one force policy: an unstable
set is never applied, not even with --force/force; poor margins only with it. `drive-link set-gains`
goes through it (the dashboard's PUT /api/gains too: tests/test_dashboard_api.py).

Truth: the closed-loop poles of the paper's PI loop (eq. 22 on eq. 8) from python-control
(test-only oracle), and the drive's own objects read back for "nothing applied".
"""

from __future__ import annotations

import contextlib
import io
import math
import uuid

import can
import control
import numpy as np
import pytest

from drive_link import Drive, InvalidValue, cli
from drive_link.workflows.gains import GainsRefused, apply_gains, check_gains

pytestmark = [pytest.mark.timeout(90), pytest.mark.unit]

R, L, TS = 6.2e-3, 14.8e-6, 20e-6
UNSTABLE_PI = {"type": 1, "k_p": 2.0, "k_i": 0.0492}  # 4.3 x the paper's k_p


def pi_poles(k_p: float, k_i: float) -> np.ndarray:
    Phi = math.exp(-R * TS / L)
    P = control.tf([(1 - Phi) / (2 * R)], [1, -Phi, 0], TS)
    C = control.tf([k_p + k_i, -k_p], [1, -1], TS)
    return control.poles(control.feedback(C * P, 1))


@pytest.fixture(scope="module")
def node():
    from virtual_drive.node import VirtualDrive

    ch = f"lg-{uuid.uuid4().hex}"
    b_drive = can.Bus(interface="virtual", channel=ch)
    b_host = can.Bus(interface="virtual", channel=ch)
    vd = VirtualDrive(b_drive, node_id=5).start()
    d = Drive.connect(bus=b_host, node_id=5, heartbeat_ms=None)
    try:
        yield ch, d
    finally:
        d.close()
        vd.stop()
        b_drive.shutdown()
        b_host.shutdown()


def set_gains(ch: str, *args: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    argv = ["set-gains", "--interface", "virtual", "--channel", ch, "--node", "5", *args]
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli.main(argv)
    return rc, out.getvalue(), err.getvalue()


def test_the_oracle_calls_the_pi_set_unstable_and_the_check_refuses_it_even_forced():
    assert np.max(np.abs(pi_poles(2.0, 0.0492))) > 1.0
    assert np.max(np.abs(pi_poles(0.4647, 0.0492))) < 1.0
    c = check_gains({"type": 1, "L_c": L, "R_c": R, "k_p": 2.0, "k_i": 0.0492}, R, L)
    assert not c.figures["current_loop_stable"] and c.refusals
    assert not c.allowed(force=True) and not c.allowed(force=False)
    ok = check_gains({"type": "pi", "L_c": L, "R_c": R, "k_p": 0.4647, "k_i": 0.0492}, R, L)
    assert ok.ok and ok.figures["phase_margin_deg"] == pytest.approx(45.6, abs=0.05)


def test_cli_set_gains_force_never_applies_an_unstable_pi_set(node):
    ch, d = node
    before = d.read_gains()
    rc, out, err = set_gains(ch, "type=1", "k_p=2.0", "--force")
    # exit 8 (refused by the host before sending), not 6 (the drive's SDO abort) nor 0
    assert rc == 8, err
    assert out == "" and err.count("\n") == 1 and "unstable" in err and "--force" not in err
    assert d.read_gains() == before  # nothing applied
    rc, out, err = set_gains(ch, "type=pi", "k_p=0.4647", "--json")  # the paper's PI: applied
    assert rc == 0, err
    assert d.read("current_controller.type") == 1
    rc, out, err = set_gains(ch, "type=deadbeat")
    assert rc == 0 and d.read("current_controller.type") == 0


def test_apply_gains_force_overrides_margins_only(node):
    _, d = node
    before = d.read_gains()
    with pytest.raises(GainsRefused) as exc:
        apply_gains(d, {"L_c": 1.8 * L})  # stable, GM 0.9 dB: needs force
    assert not exc.value.unstable and "force" in str(exc.value)
    with pytest.raises(GainsRefused) as exc:
        apply_gains(d, {"L_c": 2.2 * L}, force=True)  # unstable: never
    assert exc.value.unstable
    with pytest.raises(GainsRefused):
        apply_gains(d, UNSTABLE_PI, force=True)
    assert d.read_gains() == before
    res = apply_gains(d, {"L_c": 1.8 * L}, force=True)
    assert res.forced and res.gains["L_c"] == pytest.approx(1.8 * L, rel=1e-6)
    assert res.previous["L_c"] == pytest.approx(before.L_c)
    assert d.read("current_controller.L_c") == pytest.approx(1.8 * L, rel=1e-6)
    res = apply_gains(d, {"L_c": L})
    assert not res.forced and res.check.ok
    with pytest.raises(ValueError, match="unknown gain"):
        apply_gains(d, {"Lc": L})
    with pytest.raises(ValueError, match="finite"):
        apply_gains(d, {"k_p": float("nan")})


def test_a_library_write_of_a_gain_object_is_refused_for_the_one_gain_path(node):
    """Drive.write of an active gain sends nothing and names the one gain path (apply_gains),
    good margins or not; the OD's rules are checked first; applying a staged set is only the gain
    path's."""
    _, d = node
    before = d.read_gains()
    with pytest.raises(InvalidValue, match="apply_gains") as exc:  # good margins: still refused
        d.write("current_controller.L_c", 0.9 * L)
    assert not isinstance(exc.value, GainsRefused) and "set-gains L_c=" in str(exc.value)
    with pytest.raises(InvalidValue, match="does not hold"):
        d.write("current_controller.L_c", 2.2 * L)  # unstable: L_c < 2 L (eq. 17) first
    with pytest.raises(InvalidValue, match="apply_gains"):
        d.write("gain_set_apply", 1)
    assert d.read_gains() == before  # nothing applied


def test_drive_link_write_of_a_gain_object_takes_the_one_gain_path(node):
    """`drive-link write` of an active gain is judged by the same policy as apply_gains (the
    margin rule too, not only stability): refused with exit 7 and nothing applied, or applied
    as one set."""
    ch, d = node
    before = d.read_gains()

    def write(name: str, value: float) -> tuple[int, str, str]:
        out, err = io.StringIO(), io.StringIO()
        argv = ["write", "--interface", "virtual", "--channel", ch, "--node", "5", name,
                repr(value)]
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            rc = cli.main(argv)
        return rc, out.getvalue(), err.getvalue()

    rc, out, err = write("current_controller.L_c", 1.8 * L)  # stable, GM 0.9 dB: refused
    assert rc == 7 and out == "" and "apply_gains" in err and "--force" in err
    rc, out, err = write("current_controller.L_c", 2.2 * L)  # unstable: L_c < 2 L (eq. 17)
    assert rc == 7 and "does not hold" in err
    assert d.read_gains() == before  # nothing applied
    rc, out, err = write("current_controller.L_c", 0.9 * L)  # good margins: applied as one set
    assert rc == 0, err
    assert d.read("current_controller.L_c") == pytest.approx(0.9 * L, rel=1e-6)
    apply_gains(d, {"L_c": before.L_c})
