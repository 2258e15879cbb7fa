"""Discrete LTI responses for the tests' oracles, at C speed.

python-control's ``forced_response`` steps a discrete system in a Python loop (about 1.5 s for
150,000 samples on this host class); the same rational function run through
``scipy.signal.lfilter`` (a C difference equation) gives the response in milliseconds. The
system is still built with python-control from the paper's equations; only the stepping moves.
"""

from __future__ import annotations

import control
import numpy as np
from scipy import signal

__all__ = ["discrete_response"]


def discrete_response(sys: control.LTI, U: np.ndarray) -> np.ndarray:
    """Output (n,) of the discrete single-output ``sys`` from zero state for inputs ``U``
    ((n,) for one input, (m, n) for m inputs; superposition of each input's transfer function)."""
    if not sys.isdtime(strict=True):
        raise ValueError("discrete_response needs a discrete-time system")
    tf = control.tf(sys) if isinstance(sys, control.StateSpace) else sys
    U = np.atleast_2d(np.asarray(U, dtype=float))
    if tf.noutputs != 1 or tf.ninputs != U.shape[0]:
        raise ValueError(f"{tf.noutputs} outputs / {tf.ninputs} inputs for {U.shape[0]} input rows")
    y = np.zeros(U.shape[1])
    for j in range(U.shape[0]):
        num = np.atleast_1d(np.asarray(tf.num[0][j], dtype=float))
        den = np.atleast_1d(np.asarray(tf.den[0][j], dtype=float))
        # coefficients of z^n .. z^0 -> of z^0 .. z^-n: pad the numerator to the denominator's order
        num = np.concatenate([np.zeros(len(den) - len(num)), num])
        y += signal.lfilter(num, den, U[j])
    return y
