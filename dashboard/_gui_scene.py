"""3D view: the rotor turning at the measured speed, the two conducting phases lit.

The angle is integrated from the measured speed (rpm) at the GUI's refresh rate; the conducting
phase pair follows the six-step table from the electrical angle (pole_pairs × mechanical angle).
It is an illustration of the measured speed, not a measurement of the rotor angle.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
import viser

__all__ = [
    "DIM",
    "MAGNET_COLORS",
    "PHASE_COLORS",
    "SIX_STEP",
    "RotorScene",
    "background",
    "frame_camera",
]

#: six-step commutation: sector 0..5 → (phase driven +, phase driven −), 60° electrical each.
SIX_STEP = ((0, 1), (0, 2), (1, 2), (1, 0), (2, 0), (2, 1))
PHASE_COLORS = ((220, 60, 60), (60, 170, 60), (60, 90, 220))
DIM = (176, 128, 90)  #: copper: a coil that carries no current
MAGNET_COLORS = ((58, 60, 72), (205, 208, 216))  #: N dark, S light (apart from the phases)


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


class RotorScene:
    """Rotor (4 pole pairs → 8 magnets) inside 3 phase coil groups, a stator yoke, a shaft, a
    floor grid and a status label (speed, CiA 402 state, i_p) updated with the plots."""

    min_period_s = 0.1

    def __init__(self, server: viser.ViserServer, pole_pairs: int = 4) -> None:
        self.pole_pairs = pole_pairs
        self.angle = 0.0
        self._t = time.monotonic()
        self._sector = -1
        self._status = ""
        sc = server.scene
        sc.set_up_direction("+z")
        sc.set_background_image(background())
        frame_camera(server)
        sc.add_grid(
            "/floor",
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
        sc.add_mesh_simple("/stator/yoke", v, f, color=(120, 128, 140), flat_shading=False)
        sc.add_cylinder("/shaft", radius=0.07, height=1.3, color=(190, 190, 200))
        self.rotor = sc.add_frame("/rotor", show_axes=False)
        sc.add_cylinder("/rotor/core", radius=0.45, height=0.6, color=(150, 150, 160))
        sc.add_box(
            "/rotor/key", dimensions=(0.3, 0.05, 0.61), color=(240, 200, 60), position=(0.2, 0, 0)
        )  # shows the turning even where magnets look alike
        for k in range(2 * pole_pairs):
            a = 2 * math.pi * k / (2 * pole_pairs)
            sc.add_box(
                f"/rotor/magnet{k}",
                dimensions=(0.12, 0.3, 0.58),
                color=MAGNET_COLORS[k % 2],
                position=(0.5 * math.cos(a), 0.5 * math.sin(a), 0.0),
                wxyz=_wxyz_z(a),
            )
        self.coils: list[list[Any]] = [[], [], []]
        n_slots = 12
        for s in range(n_slots):
            a = 2 * math.pi * s / n_slots
            ph = s % 3
            h = sc.add_box(
                f"/stator/coil{s}",
                dimensions=(0.18, 0.22, 0.6),
                color=DIM,
                position=(0.85 * math.cos(a), 0.85 * math.sin(a), 0.0),
                wxyz=_wxyz_z(a),
            )
            self.coils[ph].append(h)
        for ph, name in enumerate(("a (red)", "b (green)", "c (blue)")):
            a = 2 * math.pi * ph / n_slots
            sc.add_label(
                f"/stator/phase_{name[0]}",
                f"phase {name}",
                position=(1.3 * math.cos(a), 1.3 * math.sin(a), 0.33),
                font_screen_scale=0.9,
            )
        sc.add_label(
            "/legend",
            "conducting phase pair lit (six-step) · rotor angle integrated from the measured speed",
            position=(0.0, -1.45, -0.42),
            font_screen_scale=0.8,
        )
        self.status_label = sc.add_label(
            "/status", "speed – rpm", position=(0.0, 0.0, 0.85), font_screen_scale=1.3
        )

    def show_status(self, text: str) -> None:
        """Set the status label above the motor (sent only when it changes)."""
        if text != self._status:
            self._status = text
            self.status_label.text = text

    def update(self, speed_rpm: float, live: dict[str, np.ndarray] | None = None) -> None:
        """Advance the rotor by the measured speed since the last call and light the phases."""
        now = time.monotonic()
        if now - self._t < self.min_period_s:
            return  # each scene change is a 3D re-render in the browser: ≤ 10 per second
        dt, self._t = now - self._t, now
        if not math.isfinite(speed_rpm):
            return
        if abs(speed_rpm) < 0.5:  # standing still: send nothing (no re-render)
            if self._sector != -1:
                self._light(-1)
            return
        self.angle = (self.angle + speed_rpm / 60.0 * 2 * math.pi * dt) % (2 * math.pi)
        self.rotor.wxyz = _wxyz_z(self.angle)
        theta_e = (self.angle * self.pole_pairs) % (2 * math.pi)
        sector = int(theta_e // (math.pi / 3)) % 6
        if sector != self._sector:
            self._light(sector)

    def _light(self, sector: int) -> None:
        self._sector = sector
        on = SIX_STEP[sector] if sector >= 0 else ()
        for ph in range(3):
            color = PHASE_COLORS[ph] if ph in on else DIM
            for h in self.coils[ph]:
                h.color = color
