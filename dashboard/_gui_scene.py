"""3D view: the rotor turning at the measured speed, the two conducting phases lit.

The rotor's mechanical angle is the drive's electrical angle θ_e (0x2040:0E, read by SDO when a
browser shows the view and every ANCHOR_PERIOD_S while one does) divided by the pole pairs,
advanced between reads by the measured speed (rpm) integrated over the live stream's samples.
The conducting phase pair follows the six-step table from θ_e. An illustration of the drive's
state, refreshed at most every ``min_period_s``.

Cost: each browser has its own copy of the view in its own scene (viser ``client.scene``) and a
"3D rotor" checkbox in its control panel. Unchecked, that browser's rotor nodes are removed: the
server sends it no scene message and its canvas draws only the background (viser renders on
demand). With no browser showing the rotor, :meth:`RotorScene.update` sends nothing at all.
Checked again, the view is rebuilt at the present angle (θ_e read again).
"""

from __future__ import annotations

import contextlib
import math
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import viser

__all__ = [
    "ANCHOR_PERIOD_S",
    "DIM",
    "MAGNET_COLORS",
    "PHASE_COLORS",
    "ROOT",
    "SIX_STEP",
    "TOGGLE_LABEL",
    "RotorScene",
    "RotorView",
    "background",
    "frame_camera",
]

#: six-step commutation: sector 0..5 → (phase driven +, phase driven −), 60° electrical each.
SIX_STEP = ((0, 1), (0, 2), (1, 2), (1, 0), (2, 0), (2, 1))
PHASE_COLORS = ((220, 60, 60), (60, 170, 60), (60, 90, 220))
DIM = (176, 128, 90)  #: copper: a coil that carries no current
MAGNET_COLORS = ((58, 60, 72), (205, 208, 216))  #: N dark, S light (apart from the phases)
ROOT = "/motor"  #: every node of the view lies under this scene path
TOGGLE_LABEL = "3D rotor"  #: the per-browser checkbox that shows / hides the view
ANCHOR_PERIOD_S = 10.0  #: while shown, θ_e is read again this often (s)

#: reads the drive's electrical angle: () → (θ_e rad, time.time() of the read) or None, or
#: (θ_e, time, pole pairs of the drive's motor)
ThetaReader = Callable[[], "tuple[float, float] | tuple[float, float, int] | None"]


def _wxyz_z(angle: float) -> tuple[float, float, float, float]:
    return (math.cos(angle / 2), 0.0, 0.0, math.sin(angle / 2))


def _tube(r_in: float, r_out: float, height: float, n: int = 48) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and triangles of a hollow cylinder (axis z, centred on the origin), units of the
    scene (1 = stator bore radius scale)."""
    a = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    ring = np.stack([np.cos(a), np.sin(a)], axis=1)
    z0, z1 = -height / 2, height / 2
    v = np.concatenate(
        [
            np.c_[ring * r_out, np.full(n, z0)],
            np.c_[ring * r_out, np.full(n, z1)],
            np.c_[ring * r_in, np.full(n, z0)],
            np.c_[ring * r_in, np.full(n, z1)],
        ]
    ).astype(np.float32)
    i = np.arange(n)
    j = (i + 1) % n
    oz0, oz1, iz0, iz1 = i, i + n, i + 2 * n, i + 3 * n
    pz0, pz1, jz0, jz1 = j, j + n, j + 2 * n, j + 3 * n
    faces = np.concatenate(
        [
            np.c_[oz0, pz0, pz1],
            np.c_[oz0, pz1, oz1],  # outer wall
            np.c_[iz0, iz1, jz1],
            np.c_[iz0, jz1, jz0],  # inner wall
            np.c_[oz1, pz1, jz1],
            np.c_[oz1, jz1, iz1],  # top
            np.c_[oz0, iz0, jz0],
            np.c_[oz0, jz0, pz0],  # bottom
        ]
    ).astype(np.uint32)
    return v, faces


def background(width: int = 8, height: int = 256) -> np.ndarray:
    """A neutral vertical gradient (light grey-blue at the top to white), RGB uint8."""
    t = np.linspace(0.0, 1.0, height)[:, None, None]
    top, bottom = np.array([214, 222, 232]), np.array([250, 251, 253])
    img = (top * (1 - t) + bottom * t).astype(np.uint8)
    return np.repeat(img, width, axis=1)


def frame_camera(server: viser.ViserServer) -> None:
    """Initial camera for new browsers: looking down at about 35° onto the motor so that it
    fills the canvas left of the docked panel."""
    cam = server.initial_camera
    cam.up = (0.0, 0.0, 1.0)
    cam.look_at = (0.0, 0.0, -0.05)
    cam.position = (1.35, -2.05, 1.75)


class RotorView:
    """One browser's rotor: 4 pole pairs → 8 magnets inside 3 phase coil groups, a stator yoke,
    a shaft, a floor grid and a status label, all under :data:`ROOT` in ``scene`` (that
    browser's ``client.scene``; a server's scene in tests)."""

    def __init__(self, scene: Any, pole_pairs: int, angle: float, status: str) -> None:
        sc = scene
        self.root = sc.add_frame(ROOT, show_axes=False)
        sc.add_grid(
            f"{ROOT}/floor",
            width=6.0,
            height=6.0,
            cell_size=0.25,
            section_size=1.0,
            cell_color=(205, 210, 218),
            section_color=(160, 168, 180),
            position=(0.0, 0.0, -0.42),
            shadow_opacity=0.2,
        )
        v, f = _tube(0.99, 1.12, 0.62)
        sc.add_mesh_simple(f"{ROOT}/stator/yoke", v, f, color=(120, 128, 140), flat_shading=False)
        sc.add_cylinder(f"{ROOT}/shaft", radius=0.07, height=1.3, color=(190, 190, 200))
        self.rotor = sc.add_frame(f"{ROOT}/rotor", show_axes=False, wxyz=_wxyz_z(angle))
        sc.add_cylinder(f"{ROOT}/rotor/core", radius=0.45, height=0.6, color=(150, 150, 160))
        sc.add_box(
            f"{ROOT}/rotor/key",
            dimensions=(0.3, 0.05, 0.61),
            color=(240, 200, 60),
            position=(0.2, 0, 0),
        )  # shows the turning even where magnets look alike
        for k in range(2 * pole_pairs):
            a = 2 * math.pi * k / (2 * pole_pairs)
            sc.add_box(
                f"{ROOT}/rotor/magnet{k}",
                dimensions=(0.12, 0.3, 0.58),
                color=MAGNET_COLORS[k % 2],
                position=(0.5 * math.cos(a), 0.5 * math.sin(a), 0.0),
                wxyz=_wxyz_z(a),
            )
        self.coils: list[list[Any]] = [[], [], []]
        n_slots = 12
        for s in range(n_slots):
            a = 2 * math.pi * s / n_slots
            self.coils[s % 3].append(
                sc.add_box(
                    f"{ROOT}/stator/coil{s}",
                    dimensions=(0.18, 0.22, 0.6),
                    color=DIM,
                    position=(0.85 * math.cos(a), 0.85 * math.sin(a), 0.0),
                    wxyz=_wxyz_z(a),
                )
            )
        for ph, name in enumerate(("a (red)", "b (green)", "c (blue)")):
            a = 2 * math.pi * ph / n_slots
            sc.add_label(
                f"{ROOT}/stator/phase_{name[0]}",
                f"phase {name}",
                position=(1.3 * math.cos(a), 1.3 * math.sin(a), 0.33),
                font_screen_scale=0.9,
            )
        sc.add_label(
            f"{ROOT}/legend",
            "conducting phase pair lit (six-step) · rotor angle: the drive's θ_e / pole pairs",
            position=(0.0, -1.45, -0.42),
            font_screen_scale=0.8,
        )
        self.status_label = sc.add_label(
            f"{ROOT}/status", status or "speed – rpm", position=(0.0, 0.0, 0.85),
            font_screen_scale=1.3,
        )
        self.status = status
        self.angle = angle
        self.sector = -1

    def show(self, angle: float, sector: int, status: str) -> None:
        """Send what changed since the last call: rotor orientation, lit coils, status text."""
        if angle != self.angle:
            self.angle = angle
            self.rotor.wxyz = _wxyz_z(angle)
        if sector != self.sector:
            self.sector = sector
            on = SIX_STEP[sector] if sector >= 0 else ()
            for ph in range(3):
                color = PHASE_COLORS[ph] if ph in on else DIM
                for h in self.coils[ph]:
                    h.color = color
        if status and status != self.status:
            self.status = status
            self.status_label.text = status

    def remove(self) -> None:
        """Remove every node of the view (one message: the root; the rest follows it)."""
        self.root.remove()


class RotorScene:
    """The rotor's state (angle, lit sector, status text) and one :class:`RotorView` per
    browser that shows it.

    ``server``: the viser server (camera and up direction for new browsers). ``read_theta_e``:
    reads the drive's electrical angle (None: the angle is only integrated from the speed)."""

    min_period_s = 0.1  #: each scene change is a 3D re-render in the browser: ≤ 10 per second

    def __init__(
        self,
        server: viser.ViserServer,
        pole_pairs: int = 4,
        read_theta_e: ThetaReader | None = None,
    ) -> None:
        self.pole_pairs = pole_pairs
        self.read_theta_e = read_theta_e
        self.angle = 0.0  #: mechanical angle, rad
        self.sector = -1  #: six-step sector 0..5 of θ_e, -1 standing still (all coils dark)
        self.status = ""
        self.views: dict[int, RotorView] = {}  #: client id → its view (only browsers showing it)
        self.toggles: dict[int, Any] = {}  #: client id → its "3D rotor" checkbox
        self.sends = 0  #: updates sent to browsers (each one a re-render there)
        self._t: float | None = None  # host time (stream stamp) the angle refers to
        self._mono = time.monotonic()  # without a live window: monotonic time of the angle
        self._sent = 0.0  # time.monotonic() of the last update sent
        self._anchored = -math.inf  # time.monotonic() of the last θ_e read
        self._lock = threading.RLock()
        server.scene.set_up_direction("+z")
        server.scene.set_background_image(background())
        frame_camera(server)

    # ------------------------------------------------------------------ browsers
    def attach(self, client: viser.ClientHandle, shown: bool = True) -> None:
        """Give a new browser its "3D rotor" checkbox (end of its control panel) and, if
        ``shown``, its view."""
        box = client.gui.add_checkbox(
            TOGGLE_LABEL, shown, hint="the turning rotor; unchecked it costs nothing"
        )
        box.on_update(lambda e: self.set_shown(client, bool(box.value)))
        with self._lock:
            self.toggles[client.client_id] = box
        if shown:
            self.set_shown(client, True)

    def detach(self, client_id: int) -> None:
        """A browser left: forget its view (its nodes went with its connection)."""
        with self._lock:
            self.views.pop(client_id, None)
            self.toggles.pop(client_id, None)

    def set_shown(self, client: viser.ClientHandle, shown: bool) -> None:
        """Show (at the drive's present angle) or remove the view of one browser."""
        if shown:
            self.anchor()
        with self._lock:
            view = self.views.pop(client.client_id, None)
            if view is not None:
                with contextlib.suppress(Exception):  # the browser may be gone meanwhile
                    view.remove()
            if shown and client.client_id in self.toggles:
                view = RotorView(client.scene, self.pole_pairs, self.angle, self.status)
                view.show(self.angle, self.sector, self.status)
                self.views[client.client_id] = view

    @property
    def shown(self) -> int:
        """How many browsers show the rotor."""
        return len(self.views)

    # ------------------------------------------------------------------ state
    def anchor(self) -> bool:
        """Set the angle from the drive's θ_e (one SDO read); False if it could not be read."""
        if self.read_theta_e is None:
            return False
        self._anchored = time.monotonic()  # tried: a drive without θ_e is asked again only later
        got = None
        with contextlib.suppress(Exception):
            got = self.read_theta_e()
        if got is None or not math.isfinite(got[0]):
            return False
        theta_e, t = got[0], got[1]
        with self._lock:
            if len(got) > 2 and int(got[2]) >= 1:  # the drive's motor.pole_pairs (0x2000:4)
                self.pole_pairs = int(got[2])  # (the magnets drawn follow on the next show)
            self.angle = (theta_e / self.pole_pairs) % (2 * math.pi)
            self._t = t
            self._mono = time.monotonic()
            if self.sector != -1:
                self.sector = self._sector()
        return True

    def maybe_anchor(self) -> None:
        """Read θ_e again if a browser shows the rotor and the last read is ANCHOR_PERIOD_S old."""
        if self.views and time.monotonic() - self._anchored >= ANCHOR_PERIOD_S:
            self.anchor()

    def _sector(self) -> int:
        theta_e = (self.angle * self.pole_pairs) % (2 * math.pi)
        return int(theta_e // (math.pi / 3)) % 6

    def show_status(self, text: str) -> None:
        """Set the status label above the motor (sent to browsers showing it, when it changes)."""
        with self._lock:
            if text == self.status:
                return
            self.status = text
            for view in self.views.values():
                view.show(view.angle, view.sector, text)

    def update(self, speed_rpm: float, live: dict[str, np.ndarray] | None = None) -> None:
        """Advance the angle by the measured speed since the last call (the samples of ``live``,
        "t" in s host time and "measurements.speed" in rpm, when given; else ``speed_rpm`` over
        the time since the last call) and show it to the browsers that show the rotor."""
        with self._lock:
            self._advance(speed_rpm, live)
            if not self.views:
                return  # nobody shows the rotor: nothing to send
            now = time.monotonic()
            if now - self._sent < self.min_period_s:
                return
            if not math.isfinite(speed_rpm):
                return
            self.sector = -1 if abs(speed_rpm) < 0.5 else self._sector()
            changed = False
            for view in self.views.values():
                angle = view.angle if self.sector == -1 else self.angle  # still: leave it
                if view.sector != self.sector or view.angle != angle:
                    view.show(angle, self.sector, self.status)
                    changed = True
            if changed:  # standing still: nothing sent (no re-render)
                self._sent = now
                self.sends += 1

    def _advance(self, speed_rpm: float, live: dict[str, np.ndarray] | None) -> None:
        now = time.monotonic()
        t = speed = None
        if live is not None and "measurements.speed" in live:
            t = np.asarray(live["t"], dtype=np.float64)
            speed = np.asarray(live["measurements.speed"], dtype=np.float64)
        if t is None or speed is None or not len(t):
            if math.isfinite(speed_rpm):
                self.angle = (self.angle + speed_rpm / 60.0 * 2 * math.pi * (now - self._mono)) % (
                    2 * math.pi
                )
            self._mono = now
            return
        self._mono = now
        if self._t is None:
            self._t = float(t[-1])
            return
        k = int(np.searchsorted(t, self._t, side="right"))
        if k >= len(t):
            return
        ts, sp = t[k:], speed[k:]
        edges = np.concatenate(([self._t], ts))
        ok = np.isfinite(sp)
        turned = float(np.sum(sp[ok] * np.diff(edges)[ok])) / 60.0 * 2 * math.pi  # rpm·s → rad
        self.angle = (self.angle + turned) % (2 * math.pi)
        self._t = float(ts[-1])
