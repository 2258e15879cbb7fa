"""Signal names recorded by the simulator (= OD 0x2040 ``measurements`` sub names) and units.

Every signal is sampled at the sample instants t_k = k Ts (fs = 50 kHz, the middle of the PWM
zero vector) and returned as float32; ``"t"`` (s) is float64 so that 20 us stays resolvable
after hours of simulated time.

Sign convention: i_p is the signed pseudo current, (s+ i+ + s- i- + s_o i_o) / 2 with the
sector's "+" and "-" phases and the open phase signed as in the previous sector; it equals
eq. (1), (|i_a| + |i_b| + |i_c|) / 2, when motoring (i_p >= 0) and is negative when braking.
Phase currents are positive into the motor.  v_L = m V_dc is the commanded line voltage
between the sector's "+" and "-" phases; e_L the back-EMF between the same phases.

i_p_min, i_p_max and i_p_peaks describe i_p over the PWM period that ends at t_k (the exact
switching model's i_p at every switching edge, diode current zero and the period's ends, where
its extremes lie): its least and largest value and the number of its local maxima (ripple
cycles: 2 per period for unipolar PWM, i.e. 100 kHz). The averaged model has no ripple.
"""

from __future__ import annotations

__all__ = ["OVERSAMPLED", "SIGNALS", "UNITS"]

SIGNALS: tuple[str, ...] = (
    "i_p",
    "i_a",
    "i_b",
    "i_c",
    "speed",
    "v_L",
    "e_L",
    "m",
    "hall_sector",
    "i_p_ref",
    "speed_ref",
    "V_dc",
    "T_e",
    "theta_e",
    "i_p_min",
    "i_p_max",
    "i_p_peaks",
)
"""Order matches the C loop's SIG_* indices (csrc/loop.h)."""

UNITS: dict[str, str] = {
    "i_p": "A",
    "i_a": "A",
    "i_b": "A",
    "i_c": "A",
    "speed": "rpm",
    "v_L": "V",
    "e_L": "V",
    "m": "1",
    "hall_sector": "1..6",
    "i_p_ref": "A",
    "speed_ref": "rpm",
    "V_dc": "V",
    "T_e": "N m",
    "theta_e": "rad",
    "i_p_min": "A",
    "i_p_max": "A",
    "i_p_peaks": "1",
    "t": "s",
}

OVERSAMPLED: tuple[str, ...] = ("os_t", "os_i_a", "os_i_b", "os_i_c", "os_i_p")
"""Keys of the optional oversampled record (``run(n, oversample=N)``), float64."""
