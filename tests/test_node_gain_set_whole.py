"""The staged gain set 0x20F0 is checked as a whole, against itself, when 0x20F1 applies it.

Through canopen's own SdoClient (``canopen.RemoteNode.sdo``, no drive_link code). Truths: the
paper (Valle et al. 2020, Sec. III-C: "the predictive controller cannot be implemented without
feed-forward action"; eq. 17: the deadbeat loop is unstable for L_c >= 2 L), the closed loops
built here with python-control from the paper's transfer functions (plant eq. 8
P(z) = Gamma / (z (z - Phi)), deadbeat eq. 15, predictive eq. 23 C(z) = 2 L_c f_s z / (z + 1)),
and CiA 301's abort code 0x06090031 "value of parameter written too high".
"""

from __future__ import annotations

import math

import control
import numpy as np
import pytest
from canopen.sdo import SdoAbortedError
from test_node_support import Bench

pytestmark = pytest.mark.timeout(60)

TS = 20e-6
R, L = 0.0062, 14.8e-6  #: Table 2, the drive's default motor
KEYS = ("type", "L_c", "R_c", "k_p", "k_i", "T_BT", "T_DD", "T_SD", "V_G", "emf_feedforward")
VALUE_TOO_HIGH = 0x06090031  #: CiA 301


def _closed_loop_poles(kind: str, L_c: float, R_c: float = R) -> np.ndarray:
    phi = math.exp(-R * TS / L)
    gamma = -math.expm1(-R * TS / L) / (2 * R)
    plant = control.tf([gamma], [1, -phi, 0], TS)
    if kind == "predictive":
        ctrl = control.tf([2 * L_c / TS, 0], [1, 1], TS)
    else:  # deadbeat, eq. (15) with the estimates L_c, R_c
        phi_c = math.exp(-R_c * TS / L_c)
        gamma_c = -math.expm1(-R_c * TS / L_c) / (2 * R_c)
        ctrl = control.tf([1, -phi_c, 0], [gamma_c, 0, -gamma_c], TS)
    return np.asarray(control.poles(control.feedback(ctrl * plant, 1)))


@pytest.fixture
def bench():
    b = Bench(speed=1.0)
    yield b
    b.close()


def _active(b: Bench) -> dict:
    return {k: b.read(f"current_controller.{k}") for k in KEYS}


def _stage(b: Bench, values: dict) -> None:
    for k, v in values.items():
        b.write(f"gain_set.{k}", v)


def test_predictive_with_feedforward_applied_as_one_set(bench):
    b = bench
    assert b.read("current_controller.type") == 0  # deadbeat ...
    assert b.read("current_controller.emf_feedforward") == 0  # ... without feed-forward
    # the set the paper's Fig. 14 needs: predictive law with the back-EMF feed-forward
    assert np.all(np.abs(_closed_loop_poles("predictive", L)) < 1.0)
    _stage(b, {"type": 2, "emf_feedforward": 1, "L_c": L})
    b.write("gain_set_apply", 1)
    back = _active(b)
    assert back["type"] == 2 and back["emf_feedforward"] == 1
    assert back["L_c"] == pytest.approx(L, rel=1e-6)
    assert b.drive.sim.current.type == "predictive"


def test_inadmissible_staged_set_refused_when_applied_and_nothing_changes(bench):
    b = bench
    before = _active(b)
    assert np.max(np.abs(_closed_loop_poles("deadbeat", 2.5 * L))) > 1.0  # eq. 17
    # staging takes any value within the object's own range, in any order (scratch space)
    _stage(b, {"type": 0, "L_c": 2.5 * L, "R_c": R})
    assert b.read("gain_set.L_c") == pytest.approx(2.5 * L, rel=1e-6)
    with pytest.raises(SdoAbortedError) as exc:
        b.write("gain_set_apply", 1)
    assert exc.value.code == VALUE_TOO_HIGH
    assert _active(b) == before
    assert b.drive.sim.current.L_c == pytest.approx(L, rel=1e-6)
    # a value outside the staged object's own range is still refused when written
    with pytest.raises(SdoAbortedError) as exc:
        b.write("gain_set.type", 3)
    assert exc.value.code == VALUE_TOO_HIGH
