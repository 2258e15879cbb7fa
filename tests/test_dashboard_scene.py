"""The 3D rotor view: stator yoke mesh geometry, six-step table, rotor angle and status label
on a real viser server (no browser)."""

from __future__ import annotations

import math
import time
from types import SimpleNamespace

import numpy as np
import pytest
import viser

from dashboard._gui_scene import (
    ANCHOR_PERIOD_S,
    DIM,
    PHASE_COLORS,
    ROOT,
    SIX_STEP,
    RotorScene,
    _tube,
    background,
)

pytestmark = pytest.mark.timeout(60)


@pytest.mark.unit
def test_yoke_mesh_is_closed_and_has_the_tube_volume():
    n, r_in, r_out, h = 48, 0.99, 1.12, 0.62
    v, f = _tube(r_in, r_out, h, n)
    # closed and consistently oriented: every directed edge appears once, its reverse once
    edges = {}
    for a, b, c in f:
        for e in ((a, b), (b, c), (c, a)):
            edges[e] = edges.get(e, 0) + 1
    assert all(k == 1 for k in edges.values())
    assert all((b, a) in edges for a, b in edges)
    # divergence theorem: V = Σ (p0 · (p1 × p2)) / 6, positive for outward normals
    p = v[f].astype(np.float64)
    vol = np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6
    ngon = n / 2 * math.sin(2 * math.pi / n)  # area of the regular n-gon of radius 1
    assert vol == pytest.approx(ngon * (r_out**2 - r_in**2) * h, rel=1e-5)


@pytest.mark.unit
def test_six_step_table():
    """Each 60° sector drives two different phases; each phase is driven + for 120° and − for
    120° per electrical turn; successive sectors (wrapping) change exactly one phase."""
    for plus, minus in SIX_STEP:
        assert plus != minus
    for ph in range(3):
        assert sum(p == ph for p, _ in SIX_STEP) == 2
        assert sum(m == ph for _, m in SIX_STEP) == 2
    for k in range(6):
        a, b = SIX_STEP[k], SIX_STEP[(k + 1) % 6]
        assert (a[0] != b[0]) + (a[1] != b[1]) == 1


@pytest.mark.unit
def test_background_is_a_neutral_gradient():
    img = background()
    assert img.dtype == np.uint8 and img.ndim == 3 and img.shape[2] == 3
    spread = img.max(axis=2).astype(int) - img.min(axis=2)
    assert spread.max() < 30  # greyish, no strong colour
    assert img[0].mean() < img[-1].mean()  # darker at the top


@pytest.fixture(scope="module")
def server():
    s = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield s
    s.stop()


def _wxyz_angle(w) -> float:
    """The rotation about z of a quaternion (w, x, y, z), rad in [0, 2π)."""
    return 2 * math.atan2(w[3], w[0]) % (2 * math.pi)


def test_rotor_turns_with_the_speed_and_lights_the_pair(server):
    theta_e0 = 2.5  # rad, what the drive reports when the view is shown
    t0 = time.time()
    scene = RotorScene(server, pole_pairs=4, read_theta_e=lambda: (theta_e0, t0))
    browser = SimpleNamespace(client_id=7, gui=server.gui, scene=server.scene)
    cam = server.initial_camera
    d = np.asarray(cam.position) - np.asarray(cam.look_at)
    assert 2.0 < np.linalg.norm(d) < 4.0  # framed on the motor (outer radius 1.12)
    scene.attach(browser)
    view = scene.views[7]
    # shown at the drive's angle: mechanical angle = θ_e / pole pairs
    assert (_wxyz_angle(view.rotor.wxyz) * 4) % (2 * math.pi) == pytest.approx(theta_e0)
    # the live stream: 1 kHz samples, the speed ramping 0 → 120 rpm over 1 s after t0
    t = t0 + np.arange(1, 1001) * 1e-3
    speed = 120.0 * (t - t0)
    scene._sent = -math.inf  # not rate limited
    scene.update(float(speed[-1]), {"t": t, "measurements.speed": speed})
    # ∫ speed dt = 60 rpm·s = 1 turn (the samples are held to the next: + 0.5 ms × 120 rpm)
    turned = (120.0 * 1.0**2 / 2 + 120.0 * 0.5e-3) / 60.0 * 2 * math.pi
    want = (theta_e0 / 4 + turned) % (2 * math.pi)
    assert scene.angle == pytest.approx(want, abs=1e-6)
    assert _wxyz_angle(view.rotor.wxyz) == pytest.approx(want, abs=1e-5)
    sector = int((want * 4 % (2 * math.pi)) // (math.pi / 3))
    on = SIX_STEP[sector]
    for ph in range(3):
        want_color = PHASE_COLORS[ph] if ph in on else DIM
        assert all(tuple(h.color) == want_color for h in view.coils[ph])
    scene._sent = -math.inf
    scene.update(0.0)  # standing still: every coil dark
    assert all(tuple(h.color) == DIM for c in view.coils for h in c)
    scene.show_status("500 rpm · OPERATION ENABLED · i_p 32.4 A")
    assert view.status_label.text == "500 rpm · OPERATION ENABLED · i_p 32.4 A"
    scene.set_shown(browser, False)
    assert scene.shown == 0
    scene.detach(7)


def test_hidden_everywhere_sends_nothing_and_theta_e_is_asked_rarely(server, monkeypatch):
    """What viser is asked to send (its queue, wrapped): nothing for the rotor while no browser
    shows it, though the drive turns; a drive that cannot tell θ_e is asked once per
    ANCHOR_PERIOD_S at most, and the angle then follows the speed alone."""
    asked = []

    def no_theta_e():
        asked.append(time.monotonic())
        raise OSError("SDO abort 0x06020000: object does not exist")

    scene = RotorScene(server, pole_pairs=4, read_theta_e=no_theta_e)
    browser = SimpleNamespace(client_id=8, gui=server.gui, scene=server.scene)
    scene.attach(browser, shown=False)
    assert scene.shown == 0 and asked == []
    queued = []
    ws = server._websock_server
    orig = ws.queue_message
    monkeypatch.setattr(ws, "queue_message", lambda m: (queued.append(m), orig(m))[1])
    t = time.time() + np.arange(1, 101) * 1e-3
    for k in range(5):  # 500 rpm, five pushes 0.1 s apart (the rate limit lifted)
        scene._sent = -math.inf
        scene.update(500.0, {"t": t + 0.1 * k, "measurements.speed": np.full(100, 500.0)})
    scene.show_status("500 rpm")
    assert [m for m in queued if str(getattr(m, "name", "")).startswith(ROOT)] == []
    assert scene.angle != 0.0  # the angle kept up meanwhile
    scene.set_shown(browser, True)  # shown: θ_e asked (and refused), the view built
    assert len(asked) == 1 and scene.shown == 1
    assert any(str(getattr(m, "name", "")).startswith(ROOT) for m in queued)  # the probe sees
    for _ in range(20):
        scene.maybe_anchor()  # the status loop's 0.25 s tick
    assert len(asked) == 1  # not again before ANCHOR_PERIOD_S
    scene._anchored -= ANCHOR_PERIOD_S
    scene.maybe_anchor()
    assert len(asked) == 2
    scene.set_shown(browser, False)
    scene.detach(8)


def test_rotor_angle_uses_the_drives_pole_pairs(server):
    """The mechanical angle is θ_e / p with p the drive's motor.pole_pairs (0x2000:4) when
    the reader gives it, not the drawing's default of 4."""
    theta_e0 = 3.0
    scene = RotorScene(server, pole_pairs=4, read_theta_e=lambda: (theta_e0, time.time(), 2))
    assert scene.anchor()
    assert scene.pole_pairs == 2
    assert scene.angle == pytest.approx(theta_e0 / 2)
