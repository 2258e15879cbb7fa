"""Robustness sweeps of a gain set over the motor's spread (issue 28).

A TOML spec (:mod:`.spec`) names the gain set (a DCF or inline), the parameters (grids and
seeded distributions with units), the scenarios (:mod:`.scenarios`) and the limits
(:mod:`.limits`); :func:`run_sweep` runs every run on a local process pool or a Dask cluster
(:mod:`.engine_local`, :mod:`.engine_dask`), one C-core call per chunk (:mod:`.runner`), and
writes the rows, summary and plots (:mod:`.results`, :mod:`.plots`). The command is
``virtual-drive sweep SPEC`` (:mod:`.cli`).
"""

from virtual_drive.sweep.driver import SweepResult, run_sweep
from virtual_drive.sweep.spec import RunJob, Spec, load_spec, parse_spec
from virtual_drive.sweep.units import SpecError

__all__ = ["RunJob", "Spec", "SpecError", "SweepResult", "load_spec", "parse_spec", "run_sweep"]
