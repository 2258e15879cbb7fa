"""The parameters of one current loop and one speed loop, each as one object (motulator's
``*Pars`` shape): the design functions take them instead of seven loose keywords.

Valle et al., IEEE Access 2020: plant eq. (6)-(8) with R, L; the laws eq. (15) deadbeat with the
estimates L_c, R_c, eq. (22) PI with k_p, k_i, eq. (23) predictive with L_c; the IP speed loop
eq. (27) on the speed model ``G(z) = b/(z - a)`` (eq. 26). The keyword functions of
:mod:`drive_link.workflows.design` (``current_loop_tf(controller, R=..., ...)``) build these and
stay the README's API.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

from ._common import (
    FS_DEFAULT,
    L_TABLE2,
    PI_KI_PAPER,
    PI_KP_PAPER,
    R_TABLE2,
    ControllerName,
)

__all__ = ["CurrentLoopPars", "SpeedLoopPars"]


@dataclass(frozen=True)
class CurrentLoopPars:
    """One current loop.

    ``controller``: "deadbeat" (eq. 15), "pi" (eq. 22) or "predictive" (eq. 23);
    ``R`` [Ω], ``L`` [H]: the motor (the plant, eq. 6); ``L_c`` [H], ``R_c`` [Ω]: the law's
    estimates (None: equal to L, R; see :meth:`resolved`); ``k_p``, ``k_i`` [V/A]: the PI gains;
    ``fs`` [Hz]: the sampling rate (Ts = 1/fs).
    """

    controller: ControllerName = "deadbeat"
    R: float = R_TABLE2
    L: float = L_TABLE2
    L_c: float | None = None
    R_c: float | None = None
    k_p: float = PI_KP_PAPER
    k_i: float = PI_KI_PAPER
    fs: float = FS_DEFAULT

    @property
    def L_c_used(self) -> float:
        """The estimate L_c the law uses [H] (L when not given)."""
        return self.L if self.L_c is None else self.L_c

    @property
    def R_c_used(self) -> float:
        """The estimate R_c the law uses [Ω] (R when not given)."""
        return self.R if self.R_c is None else self.R_c

    def resolved(self) -> CurrentLoopPars:
        """The same loop with L_c, R_c filled in."""
        return replace(self, L_c=self.L_c_used, R_c=self.R_c_used)

    def setup(self) -> dict[str, Any]:
        """R, L, L_c, R_c (resolved), k_p, k_i, fs as keywords (JSON-ready)."""
        return {
            "R": self.R,
            "L": self.L,
            "L_c": self.L_c_used,
            "R_c": self.R_c_used,
            "k_p": self.k_p,
            "k_i": self.k_i,
            "fs": self.fs,
        }


@dataclass(frozen=True)
class SpeedLoopPars:
    """One IP speed loop (eq. 27) on the speed model ``G(z) = b/(z - a)`` (eq. 26).

    ``a`` (per loop sample), ``b`` [rpm/A per sample]; ``k_p`` [A/rpm], ``k_i`` [1/sample]: the
    IP gains; ``fs`` [Hz]: the loop rate.
    """

    a: float
    b: float
    k_p: float
    k_i: float
    fs: float = FS_DEFAULT
