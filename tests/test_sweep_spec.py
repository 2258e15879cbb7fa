"""Issue 28: the sweep spec (DCF gain set, units, seeded draws), stop/resume of the results log,
re-running one run alone, the metrics against python-control's step_info, and bad input."""

from __future__ import annotations

import json
import math

import control as ct
import numpy as np
import pytest

from drive_link.workflows.config_dcf import dcf_text
from virtual_drive.cli import main as cli_main
from virtual_drive.sim.params import Ts
from virtual_drive.sweep import SpecError, load_spec, run_sweep
from virtual_drive.sweep.metrics import compute_metrics
from virtual_drive.sweep.scenarios import Scenario, Trace

pytestmark = pytest.mark.timeout(120)

STEP = """
[[scenarios]]
kind = "current_step"
from = "10 A"
to = "15 A"
at = "0.2 ms"
duration = "2 ms"
settle = "0.2 ms"
"""


def _spec(tmp_path, text, name="s.toml"):
    p = tmp_path / name
    p.write_text(text)
    return load_spec(p)


@pytest.mark.unit
def test_gain_set_from_a_dcf_saved_by_drive_link(tmp_path, capsys):
    values = {
        "motor.L": 18e-6, "motor.R": 7e-3, "current_controller.type": 1,
        "current_controller.L_c": 21e-6, "current_controller.k_p": 0.5,
        "current_controller.k_i": 0.06, "speed_controller.k_p": 0.25,
        "speed_controller.current_limit": 80.0, "protection.overcurrent_trip": 250.0,
    }  # fmt: skip
    (tmp_path / "drive.dcf").write_text(dcf_text(values, 3))
    spec = _spec(tmp_path, '[gains]\ndcf = "drive.dcf"\nR_c = "5 mOhm"\n' + STEP)
    nom = spec.nominal
    assert nom["controller"] == "pi"
    assert nom["L"] == 18e-6 and nom["R"] == 7e-3 and nom["L_c"] == 21e-6
    assert (nom["k_p"], nom["k_i"], nom["speed_k_p"]) == (0.5, 0.06, 0.25)
    assert nom["current_limit"] == 80.0 and nom["overcurrent_trip"] == 250.0
    assert nom["R_c"] == pytest.approx(5e-3)  # inline overrides the DCF
    assert cli_main(["sweep", str(tmp_path / "s.toml"), "--run", "0", "--json"]) == 0
    row = json.loads(capsys.readouterr().out)
    assert row["controller"] == "pi" and row["L_c/L"] == pytest.approx(21 / 18)


@pytest.mark.unit
def test_units_relative_spread_and_seeded_draws(tmp_path):
    spec = _spec(tmp_path, """
[sweep]
seed = 7
samples = 50
[parameters]
L = { values = [10, 20], unit = "uH" }
R = { dist = "uniform", low = -40, high = 60, unit = "%" }
V_dc = { dist = "normal", mean = 48, std = 4, clip = [40, 56], unit = "V" }
controller = { dist = "choice", values = ["deadbeat", "pi"] }
""" + STEP)  # fmt: skip
    assert spec.n_runs == 100
    jobs = [spec.job(i) for i in range(100)]
    assert {j.inputs["L"] for j in jobs} == {10e-6, 20e-6}
    assert [j.inputs["L"] for j in jobs[:50]] == [10e-6] * 50  # first parameter slowest
    R = np.array([j.inputs["R"] for j in jobs]) / spec.nominal["R"]
    assert R.min() >= 0.6 and R.max() <= 1.6 and R.max() - R.min() > 0.7
    V = np.array([j.inputs["V_dc"] for j in jobs])
    assert V.min() >= 40 and V.max() <= 56 and 46 < V.mean() < 50
    assert {j.inputs["controller"] for j in jobs} == {"deadbeat", "pi"}
    # the same run, asked alone and in another order, has the same inputs and seed
    again = _spec(tmp_path, (tmp_path / "s.toml").read_text(), "t.toml")
    for i in (99, 3, 50):
        assert again.job(i).inputs == jobs[i].inputs and again.job(i).seed == jobs[i].seed
    assert len({j.seed for j in jobs}) == 100
    other = _spec(tmp_path, (tmp_path / "s.toml").read_text().replace("seed = 7", "seed = 8"))
    assert other.job(0).inputs["R"] != jobs[0].inputs["R"]


@pytest.mark.unit
def test_stop_and_resume_skips_done_runs_and_repairs_a_cut_line(tmp_path):
    spec = _spec(tmp_path, """
[sweep]
samples = 60
[parameters]
"L_c/L" = { dist = "uniform", low = 0.5, high = 2.4 }
""" + STEP)  # fmt: skip
    full = run_sweep(spec, tmp_path / "full", workers=1, progress=False, plots=False)

    class StopSweepError(Exception):
        pass

    def stop(done, total, failures):
        if done >= 20:
            raise StopSweepError

    with pytest.raises(StopSweepError):
        run_sweep(spec, tmp_path / "part", workers=1, progress=False, on_progress=stop)
    csv_path = tmp_path / "part" / "runs.csv"
    n_first = len(csv_path.read_text().splitlines()) - 1
    assert 20 <= n_first < 60
    with csv_path.open("a") as fh:
        fh.write("59,59,current_step,123,0.1")  # a line cut by a kill
    res = run_sweep(spec, tmp_path / "part", workers=1, progress=False, plots=False)
    assert res.skipped == n_first and res.executed == 60 - n_first
    lines = csv_path.read_text().splitlines()
    assert len(lines) == 61 and len({ln.split(",")[0] for ln in lines[1:]}) == 60
    assert sorted(lines[1:], key=lambda s: int(s.split(",")[0])) == sorted(
        (tmp_path / "full" / "runs.csv").read_text().splitlines()[1:],
        key=lambda s: int(s.split(",")[0]),
    )
    again = run_sweep(spec, tmp_path / "part", workers=1, progress=False, plots=False)
    assert again.executed == 0 and len(again.rows) == 60
    assert full.summary["runs"] == 60
    # another spec in the same folder is refused, nothing written
    other = _spec(tmp_path, (tmp_path / "s.toml").read_text().replace("2.4", "2.3"), "o.toml")
    with pytest.raises(SpecError, match="another spec"):
        run_sweep(other, tmp_path / "part", workers=1, progress=False)
    assert csv_path.read_text().splitlines() == lines


@pytest.mark.unit
@pytest.mark.parametrize("zeta", [0.3, 0.6, 1.2])
def test_overshoot_and_settling_against_step_info(zeta):
    wn = 2 * math.pi * 400.0
    sys_d = ct.c2d(ct.tf([wn**2], [1, 2 * zeta * wn, wn**2]), Ts)
    n, k0 = 1000, 100
    t = np.arange(n - k0) * Ts
    y0 = ct.step_response(sys_d, t).outputs
    y = np.concatenate([np.zeros(k0), y0]) * 5.0 + 10.0
    r = np.where(np.arange(n) >= k0, 15.0, 10.0)
    sc = Scenario(name="s", kind="current_step", duration=n * Ts, at=k0 * Ts, initial=10.0,
                  final=15.0)  # fmt: skip
    z = np.zeros(n)
    tr = Trace(y=y, r=r, i_peak=np.abs(y), speed=z, e_i=z, k_event=k0, n_planned=n)
    m = compute_metrics(tr, sc)
    info = ct.step_info(y0, t, SettlingTimeThreshold=0.02)
    assert m["overshoot"] == pytest.approx(info["Overshoot"], abs=0.05)
    assert m["settling"] == pytest.approx(info["SettlingTime"], abs=1.5 * Ts)
    assert m["stable"] and m["peak_phase_current"] == pytest.approx(y.max())


@pytest.mark.unit
@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("[parameters]\nX = [1]\n" + STEP, "unknown input"),
        ('[parameters]\nL = { values = [1], unit = "V" }\n' + STEP, "not convertible"),
        ('[parameters]\nR = { dist = "gauss", mean = 1 }\n' + STEP, "dist must be"),
        ('[limits]\nsettling = "5 A"\n' + STEP, "limits.settling"),
        ('[gains]\ndcf = "missing.dcf"\n' + STEP, "cannot read"),
        ("[parameters]\n", "no scenario"),
    ],
    ids=["name", "unit", "dist", "limit-unit", "dcf", "no-scenario"],
)
def test_bad_spec_is_one_line_and_exit_2_with_nothing_written(tmp_path, capsys, text, message):
    (tmp_path / "bad.toml").write_text(text)
    with pytest.raises(SpecError, match=message):
        load_spec(tmp_path / "bad.toml")
    out = tmp_path / "out"
    assert cli_main(["sweep", str(tmp_path / "bad.toml"), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and message.split()[0] in err
    assert not out.exists()
