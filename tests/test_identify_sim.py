"""Fig. 16 end to end: a 15 A -> 30 A current step on the virtual drive's C simulator, traced every
10 ms, identified with `drive-link identify`; the simulator's shaft is built from the paper's
a = 0.9999785, b = 3.33715e-4, which the fit must recover through commutation, back-EMF and the
current loop it ignores.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from drive_link.cli.design import run_cli
from drive_link.workflows.identify import fit_first_order

sim_mod = pytest.importorskip("virtual_drive.sim")

pytestmark = [pytest.mark.timeout(120), pytest.mark.unit]

A_PAPER = 0.9999785
B_PAPER = 3.33715e-4


@pytest.fixture(scope="module")
def trace():
    sim = sim_mod.Simulator(model="averaged")
    sim.set_mode("current")
    sim.set_current_ref(15.0)
    sim.run_seconds(10.0)  # settle near the 15 A speed
    before = sim.run(50_000)
    sim.set_current_ref(30.0)
    after = sim.run(13 * 50_000)
    D = 500  # trace divider: one sample every 10 ms, 1400 samples over 14 s
    i_p = np.concatenate([before["i_p"], after["i_p"]])[::D].astype(float)
    speed = np.concatenate([before["speed"], after["speed"]])[::D].astype(float)
    t = (np.arange(i_p.size) - 100) * D * 20e-6
    return t, i_p, speed, D


def test_fit_recovers_the_paper_model(trace):
    _, i_p, speed, D = trace
    fit = fit_first_order(i_p, speed, D * 20e-6)
    assert 1 - fit.a == pytest.approx(1 - A_PAPER, rel=0.05)
    assert fit.b == pytest.approx(B_PAPER, rel=0.03)
    assert fit.r2 > 0.999
    assert speed[-1] > 1.8 * speed[0]  # the step doubled the speed (Fig. 16: ~230 -> ~460 rpm)


def test_identify_command_on_a_trace_capture_csv(trace, tmp_path, capsys):
    t, i_p, speed, _ = trace
    f = tmp_path / "fig16.csv"
    rows = ["t [s],measurements.i_p [A],measurements.speed [rpm]"]
    rows += [f"{a:.9g},{b:.9g},{c:.9g}" for a, b, c in zip(t, i_p, speed, strict=True)]
    f.write_text("\n".join(rows) + "\n")
    assert run_cli(["identify", "--csv", str(f), "--xi", "1", "--wn", "2.3", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["D"] == 500
    assert 1 - d["a"] == pytest.approx(1 - A_PAPER, rel=0.05)
    # the IP gains designed on the identified model stay near the paper's
    assert d["kp"] == pytest.approx(0.2113, rel=0.05)
