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

#: six-step commutation: sector 0..5 → (phase driven +, phase driven −), 60° electrical each.
SIX_STEP = ((0, 1), (0, 2), (1, 2), (1, 0), (2, 0), (2, 1))
PHASE_COLORS = ((220, 60, 60), (60, 170, 60), (60, 90, 220))
DIM = (70, 70, 70)


def _wxyz_z(angle: float) -> tuple[float, float, float, float]:
    return (math.cos(angle / 2), 0.0, 0.0, math.sin(angle / 2))


class RotorScene:
    """Rotor (4 pole pairs → 8 magnets) inside 3 phase coil groups."""

    min_period_s = 0.1

    def __init__(self, server: viser.ViserServer, pole_pairs: int = 4) -> None:
        self.pole_pairs = pole_pairs
        self.angle = 0.0
        self._t = time.monotonic()
        self._sector = -1
        sc = server.scene
        sc.set_up_direction("+z")
        self.rotor = sc.add_frame("/rotor", show_axes=False)
        sc.add_cylinder("/rotor/core", radius=0.45, height=0.6, color=(150, 150, 160))
        for k in range(2 * pole_pairs):
            a = 2 * math.pi * k / (2 * pole_pairs)
            sc.add_box(
                f"/rotor/magnet{k}",
                dimensions=(0.12, 0.3, 0.58),
                color=(200, 50, 50) if k % 2 == 0 else (50, 50, 200),
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
        sc.add_label(
            "/stator/label",
            "phases a (red) · b (green) · c (blue) lit when conducting",
            position=(0.0, -1.2, 0.4),
        )

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
