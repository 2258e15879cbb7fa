"""`drive-link design` / `drive-link identify` through cli_design.run_cli and the console script."""

from __future__ import annotations

import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import signal

from drive_link.cli.design import run_cli

#: the console script of this interpreter's environment (pytest does not put the venv's bin on
#: PATH: it sits next to sys.executable)
DRIVE_LINK = shutil.which("drive-link", path=str(Path(sys.executable).parent)) or shutil.which(
    "drive-link"
)

pytestmark = pytest.mark.timeout(120)

L = 14.8e-6


def _json(capsys, argv):
    rc = run_cli(argv)
    out, err = capsys.readouterr()
    assert rc == 0, err
    assert err == ""
    return json.loads(out)


@pytest.mark.unit
@pytest.mark.parametrize(
    ("Lc", "gm", "pm_abs", "s_inf"),
    [(0.5 * L, 12.0, 73.6, 1.33), (L, 6.0, 60.0, 1.99), (1.5 * L, 2.5, 41.6, 3.97)],
)
def test_design_json_reproduces_table1(capsys, Lc, gm, pm_abs, s_inf):
    d = _json(capsys, ["design", "--Lc", repr(Lc), "--json"])
    for key in (
        "stable",
        "gain_margin_db",
        "phase_margin_deg",
        "sensitivity_peak",
        "overshoot_pct",
    ):
        assert key in d
    assert d["stable"] is True
    assert d["gain_margin_db"] == pytest.approx(gm, abs=0.1)
    # one convention: the smallest margin, a positive angle (was -41.37° for 1.5 L)
    assert d["phase_margin_deg"] > 0
    assert d["phase_margin_deg"] == pytest.approx(pm_abs, abs=0.3)
    assert len(d["crossovers"]) == 2  # both crossovers listed with their margins
    assert d["phase_margin_deg"] == min(c["phase_margin_deg"] for c in d["crossovers"])
    assert d["sensitivity_peak"] == pytest.approx(s_inf, rel=0.01)


@pytest.mark.unit
def test_design_overshoot_orders_like_fig8(capsys):
    """Fig. 8: L_c = L deadbeat (no overshoot), 0.5 L overdamped-ish, 1.5 L underdamped."""
    os_ = {
        k: _json(capsys, ["design", "--Lc", repr(k * L), "--json"])["overshoot_pct"]
        for k in (0.5, 1.0, 1.5)
    }
    assert os_[1.0] == pytest.approx(0.0, abs=1e-6)
    assert os_[1.5] > 20.0
    assert os_[0.5] < 5.0
    d = _json(capsys, ["design", "--json"])
    assert d["settling_time_s"] == pytest.approx(2 * 20e-6, abs=1e-9)  # two samples


@pytest.mark.unit
def test_design_pi_and_unstable(capsys):
    d = _json(
        capsys, ["design", "--controller", "pi", "--kp", "0.4647", "--ki", "0.0492", "--json"]
    )
    assert d["gain_margin_db"] == pytest.approx(9.14, abs=0.02)
    assert d["phase_margin_deg"] == pytest.approx(45.6, abs=0.05)
    assert d["sensitivity_peak"] == pytest.approx(1.72, abs=0.01)
    u = _json(capsys, ["design", "--Lc", repr(2.2 * L), "--json"])
    assert u["stable"] is False
    assert u["jury_stable"] is False
    assert u["overshoot_pct"] is None


@pytest.mark.unit
def test_design_pi_from_spec(capsys):
    d = _json(
        capsys, ["design", "--controller", "pi", "--crossover-hz", "1000", "--pm", "60", "--json"]
    )
    assert d["phase_margin_deg"] == pytest.approx(60.0, abs=1e-3)
    assert d["gain_crossover_hz"] == pytest.approx(1000.0, rel=1e-4)


@pytest.mark.unit
def test_design_ip_gains(capsys):
    d = _json(
        capsys,
        ["design", "--a", "0.9999785", "--b", "3.33715e-4", "--xi", "1", "--wn", "2.3", "--json"],
    )
    assert d["kp"] == pytest.approx(0.2113, rel=5e-4)
    assert d["ki"] == pytest.approx(2.9994e-5, rel=1e-3)
    assert d["stable"] is True
    assert 1.5 < d["settling_time_s"] < 3.0


@pytest.mark.unit
def test_design_text_output(capsys):
    assert run_cli(["design", "--Lc", repr(1.5 * L)]) == 0
    out = capsys.readouterr().out
    assert "stable" in out and "2.50 dB" in out and "‖S‖∞ = 4.000" in out


@pytest.mark.unit
@pytest.mark.parametrize(
    ("argv", "code"),  # README exit-code table: 7 a value refused, 2 the command line's form
    [
        (["design", "--L", "-1e-6"], 7),
        (["design", "--L", "nan"], 7),
        (["design", "--fs", "0"], 7),
        (["design", "--R", "abc"], 7),
        (["design", "--Lc", "-2e-6"], 7),
        (["design", "--controller", "pi", "--crossover-hz", "20000", "--pm", "80"], 7),
        (["design", "--a", "1.2", "--b", "3e-4"], 7),
        (["design", "--a", "0.99998"], 2),
        (["design", "--a", "0.99998", "--b", "3e-4", "--wn", "-1"], 7),
        (["design", "--step-from", "5", "--step-to", "5"], 7),
        (["design", "--L", "-1"], 7),
        (["design", "--controller", "bang-bang"], 2),
        (["design", "--L"], 2),
        (["design", "--samples", "3"], 7),
    ],
)
def test_design_bad_input_one_line_exit_code(capsys, argv, code):
    assert run_cli(argv) == code
    out, err = capsys.readouterr()
    assert out == ""
    assert len(err.strip().splitlines()) == 1
    assert err.startswith("drive-link design: error:")


@pytest.mark.unit
def test_identify_requires_csv(capsys):
    assert run_cli(["identify"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1
    assert "--csv" in err


def _write_trace(path, D=500, n=1400, header=("t", "i_p", "speed"), noise=0.0, seed=0):
    a, b = 0.9999785, 3.33715e-4
    i = np.full(n * D, 15.0)
    i[(n // 10) * D :] = 30.0
    # simulated at the loop rate (lfilter == dlsim, see test_identify_ls.py), then decimated
    y, _ = signal.lfilter([0.0, 1.0], [1.0, -a], b * i, zi=[230.0])
    rng = np.random.default_rng(seed)
    t = np.arange(n) * D * 20e-6 - 1.0
    w = y[::D] + rng.normal(0.0, noise, n)
    lines = ["# captured by a test", ",".join(header)]
    lines += [f"{tt:.9g},{ii:.9g},{ww:.9g}" for tt, ii, ww in zip(t, i[::D], w, strict=True)]
    path.write_text("\n".join(lines) + "\n")
    return a, b


@pytest.mark.unit
def test_identify_plain_csv(tmp_path, capsys):
    f = tmp_path / "trace.csv"
    a, b = _write_trace(f)
    d = _json(capsys, ["identify", "--csv", str(f), "--json"])
    assert d["D"] == 500
    assert 1 - d["a"] == pytest.approx(1 - a, rel=1e-3)
    assert d["b"] == pytest.approx(b, rel=1e-3)
    assert d["r2"] > 0.9999
    assert "rms" in d


@pytest.mark.unit
def test_identify_trace_capture_format_with_ip_gains(tmp_path, capsys):
    f = tmp_path / "trace.csv"
    a, _ = _write_trace(
        f, D=50, n=1200, header=("t [s]", "measurements.i_p [A]", "measurements.speed [rpm]")
    )
    d = _json(capsys, ["identify", "--csv", str(f), "--xi", "1", "--wn", "2.3", "--json"])
    assert d["D"] == 50
    assert 1 - d["a"] == pytest.approx(1 - a, rel=1e-3)
    assert d["kp"] == pytest.approx(0.2113, rel=2e-3)
    assert run_cli(["identify", "--csv", str(f)]) == 0
    assert "a = 0.99997" in capsys.readouterr().out


@pytest.mark.unit
@pytest.mark.parametrize(
    ("content", "match"),
    [
        ("t,i_p\n0,1\n", "no column 'speed'"),
        ("t,i_p,speed\n", "no data rows"),
        ("t,i_p,speed\n0,1,2\n2e-5,x,3\n", "line 3"),
        ("t,i_p,speed\n" + "".join(f"{k * 3e-5},15,230\n" for k in range(10)), "multiple"),
        ("t,i_p,speed\n" + "".join(f"{k * 2e-5},15,230\n" for k in range(10)), "excite"),
        ("t,i_p,speed\n0,1,2\n0,1,2\n0,1,2\n0,1,2\n0,1,2\n", "increasing"),
    ],
)
def test_identify_bad_csv_one_line_exit_7(tmp_path, capsys, content, match):
    f = tmp_path / "bad.csv"
    f.write_text(content)
    assert run_cli(["identify", "--csv", str(f)]) == 7  # invalid value
    out, err = capsys.readouterr()
    assert out == ""
    assert len(err.strip().splitlines()) == 1
    assert match in err


@pytest.mark.unit
def test_identify_missing_file(tmp_path, capsys):
    assert run_cli(["identify", "--csv", str(tmp_path / "nope.csv")]) == 7
    assert "cannot read" in capsys.readouterr().err


@pytest.mark.skipif(
    DRIVE_LINK is None, reason="drive-link console script not installed"
)
def test_console_script(tmp_path):
    p = subprocess.run(
        [DRIVE_LINK, "design", "--Lc", repr(1.5 * L), "--json"],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert p.returncode == 0, p.stderr
    d = json.loads(p.stdout)
    assert d["gain_margin_db"] == pytest.approx(2.5, abs=0.1)
    assert math.isfinite(d["overshoot_pct"])
    bad = subprocess.run(
        [DRIVE_LINK, "design", "--L", "-1"],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert bad.returncode == 7  # invalid value (README's exit-code table)
    assert len(bad.stderr.strip().splitlines()) == 1
    f = tmp_path / "trace.csv"
    _write_trace(f, D=50, n=1200)
    ok = subprocess.run(
        [DRIVE_LINK, "identify", "--csv", str(f), "--json"],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert ok.returncode == 0, ok.stderr
    assert json.loads(ok.stdout)["D"] == 50
