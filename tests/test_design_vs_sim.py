"""Predicted current steps against the virtual drive's C simulator (an independent implementation).

The rotor is held (huge inertia) so the back-EMF stays constant and no commutation happens in the
window: the linear prediction of eq. (6) with the same law must then match the simulated i_p
sample by sample, for the averaged and the PWM-exact inverter models.
"""

from __future__ import annotations

import numpy as np
import pytest

from drive_link import design

sim_mod = pytest.importorskip("virtual_drive.sim")

pytestmark = [pytest.mark.timeout(60), pytest.mark.unit]

L = design.L_TABLE2

CASES = [
    ("deadbeat", 1.0, {}),
    ("deadbeat", 0.5, {}),
    ("deadbeat", 1.5, {}),
    ("deadbeat", 1.9, {}),
    ("pi", 1.0, {}),
    ("pi", 1.0, {"k_p": 0.2, "k_i": 0.02}),
    ("predictive", 1.0, {"emf_feedforward": False}),
    ("predictive", 1.0, {"emf_feedforward": True}),
]


@pytest.mark.parametrize("model", ["averaged", "pwm"])
@pytest.mark.parametrize(("controller", "kL", "extra"), CASES)
def test_simulated_step_matches_prediction(model, controller, kL, extra):
    cur = sim_mod.CurrentControllerParams(type=controller, L_c=kL * L, **extra)
    load = sim_mod.LoadParams(J=1e3)  # held rotor: constant e_L, no commutation
    sim = sim_mod.Simulator(current=cur, load=load, model=model)
    sim.set_mode("current")
    sim.set_current_ref(15.0)
    sim.run(3000)
    e_L = float(sim.state["e_L"])
    sim.set_current_ref(20.0)
    n = 300
    rec = sim.run(n)
    assert np.all(rec["hall_sector"] == rec["hall_sector"][0])
    pred = design.predicted_step(
        controller,
        n_samples=n,
        i_start=15.0,
        i_final=20.0,
        L_c=kL * L,
        k_p=cur.k_p,
        k_i=cur.k_i,
        e_L=e_L,
        feedforward=bool(extra.get("emf_feedforward", False)),
    )
    # float32 arithmetic in the C core and PWM ripple sampled at the period centre: 20 mA
    np.testing.assert_allclose(rec["i_p"], pred.i_p, atol=0.02)
