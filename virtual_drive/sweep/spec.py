"""The sweep spec (TOML) and its expansion into runs.

```toml
[sweep]
name = "table1"
seed = 1            # per-run seeds derive from it and the point index, never from scheduling
samples = 1         # random draws per grid point (Monte Carlo)
model = "pwm"       # or "averaged"
stability_band = 0.25
batch = 0           # runs per task (0: chosen from the run length)
map = ["L_c/L", "R_c/R"]   # the two parameters of the pass/fail and overshoot maps

[gains]             # the gain set: a DCF saved by `drive-link config save`, and/or inline
dcf = "drive.dcf"   # relative to this file
L_c = "14.8 uH"

[motor]             # nominal motor, supply and load (defaults: the paper's Table 2 motor)
V_dc = 48

[parameters]        # grids and seeded distributions, each with an optional unit
"L_c/L" = { linspace = [0.25, 2.5, 20] }
R = { dist = "uniform", low = -40, high = 60, unit = "%" }    # % of the nominal value
V_dc = { dist = "uniform", low = 40, high = 56, unit = "V" }
controller = { values = ["deadbeat", "pi"] }

[limits]
overshoot = 20
settling = "3 ms"

[[scenarios]]
kind = "current_step"
from = "10 A"
to = "15 A"
at = "1 ms"
duration = "10 ms"
```

Grid forms: ``values = [...]``, ``linspace = [start, stop, num]``, ``geomspace = [start, stop,
num]``, a bare list, or a bare number (one value). Distributions: ``uniform`` (low, high),
``loguniform`` (low, high), ``normal`` (mean, std, optional clip = [lo, hi]), ``choice``
(values). The points are the grid's Cartesian product (first parameter slowest) times
``samples``; run ``i`` is point ``i // n_scenarios`` under scenario ``i % n_scenarios``, and a
point's random draws come from ``numpy.random.default_rng(seed_p)``, ``seed_p`` derived from
(``seed``, point) by :class:`numpy.random.SeedSequence` (the row's ``seed``), so the same run
gets the same inputs on any machine, in any order, and alone (``--run``).
"""

from __future__ import annotations

import hashlib
import json
import math
import sys
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from virtual_drive.sweep.dcf import read_gain_set
from virtual_drive.sweep.inputs import INPUTS, RATIOS, derived_k_e, k_rpm_of, nominal_inputs
from virtual_drive.sweep.limits import resolve_limits
from virtual_drive.sweep.scenarios import Scenario, parse_scenario
from virtual_drive.sweep.units import SpecError, clean, scale_to, to_si

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["Param", "RunJob", "Spec", "load_spec", "parse_spec"]

_GAIN_KEYS = ("controller", "L_c", "R_c", "k_p", "k_i", "emf_feedforward", "speed_k_p",
              "speed_k_i", "current_limit")  # fmt: skip
_MOTOR_KEYS = ("R", "L", "K_rpm", "k_e", "pole_pairs", "J", "B", "k_gen", "T_load", "V_dc")
_PROT_KEYS = ("overcurrent_trip", "overvoltage_trip", "undervoltage_trip")
_DISTS = ("uniform", "loguniform", "normal", "choice")
_CONTROLLERS = ("deadbeat", "pi", "predictive")


@dataclass(frozen=True)
class Param:
    """A swept input: a grid (``values``) or a distribution (``dist`` with ``args``); numbers
    in the input's SI unit, or in % of its nominal value when ``relative``."""

    name: str
    values: tuple[Any, ...] = ()
    dist: str = ""
    args: dict[str, Any] = field(default_factory=dict)
    relative: bool = False

    @property
    def is_grid(self) -> bool:
        return not self.dist


@dataclass(frozen=True)
class RunJob:
    """Everything a worker needs for one run (picklable, no file access)."""

    run: int
    point: int
    seed: int
    inputs: dict[str, Any]
    swept: tuple[str, ...]
    scenario: Scenario
    limits: dict[str, Any]
    model: str
    band: float


@dataclass(frozen=True)
class Spec:
    """A parsed sweep spec; :meth:`job` expands run ``i``."""

    path: Path | None
    name: str
    seed: int
    samples: int
    model: str
    band: float
    batch: int
    nominal: dict[str, Any]
    params: tuple[Param, ...]
    scenarios: tuple[Scenario, ...]
    limits: tuple[dict[str, Any], ...]
    map: tuple[str, str] | None

    @property
    def n_grid(self) -> int:
        return int(np.prod([len(p.values) for p in self.params if p.is_grid], dtype=np.int64))

    @property
    def n_points(self) -> int:
        return self.n_grid * self.samples

    @property
    def n_runs(self) -> int:
        return self.n_points * len(self.scenarios)

    @property
    def swept(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.params)

    @property
    def digest(self) -> str:
        """sha256 of everything that decides the rows (not the file's text or ``batch``)."""
        doc = {
            "seed": self.seed, "samples": self.samples, "model": self.model,
            "band": self.band, "nominal": self.nominal,
            "params": [asdict(p) for p in self.params],
            "scenarios": [{**asdict(s), "limits": None} for s in self.scenarios],
            "limits": list(self.limits),
        }  # fmt: skip
        text = json.dumps(doc, sort_keys=True, default=repr)
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    def point_seed(self, point: int) -> int:
        """The seed of point ``point``'s random draws (uint32)."""
        ss = np.random.SeedSequence([self.seed, point])
        return int(ss.generate_state(1, dtype=np.uint32)[0])

    def job(self, run: int) -> RunJob:
        """Run ``run`` (0 <= run < n_runs): its inputs, scenario and limits."""
        if not 0 <= run < self.n_runs:
            raise SpecError(f"run {run} is not in this sweep (0..{self.n_runs - 1})")
        n_sc = len(self.scenarios)
        point, s = divmod(run, n_sc)
        seed = self.point_seed(point)
        return RunJob(
            run=run,
            point=point,
            seed=seed,
            inputs=self._inputs(point, seed),
            swept=self.swept,
            scenario=self.scenarios[s],
            limits=self.limits[s],
            model=self.model,
            band=self.band,
        )

    def _inputs(self, point: int, seed: int) -> dict[str, Any]:
        g = point // self.samples
        grid = [p for p in self.params if p.is_grid]
        idx: dict[str, int] = {}
        for p in reversed(grid):
            g, idx[p.name] = divmod(g, len(p.values))
        rng = np.random.default_rng(seed)
        nom = self.nominal
        out = dict(nom)
        ratios = {k: nom[est] / nom[mot] for k, (est, mot) in RATIOS.items()}
        for p in self.params:
            v = p.values[idx[p.name]] if p.is_grid else _draw(p, rng)
            if p.relative:
                base = ratios[p.name] if p.name in RATIOS else nom[p.name]
                v = base * (1.0 + v / 100.0)
            if p.name in RATIOS:
                ratios[p.name] = v
            else:
                out[p.name] = v
        if "k_e" in self.swept:
            out["K_rpm"] = k_rpm_of(out["k_e"])
        out["k_e"] = derived_k_e(out["K_rpm"])
        for k, (est, mot) in RATIOS.items():
            if k in self.swept:
                out[est] = ratios[k] * out[mot]
            out[k] = out[est] / out[mot]
        return out


def _draw(p: Param, rng: np.random.Generator) -> Any:
    a = p.args
    if p.dist == "uniform":
        return float(rng.uniform(a["low"], a["high"]))
    if p.dist == "loguniform":
        return float(math.exp(rng.uniform(math.log(a["low"]), math.log(a["high"]))))
    if p.dist == "normal":
        v = float(rng.normal(a["mean"], a["std"]))
        if "clip" in a:
            v = min(max(v, a["clip"][0]), a["clip"][1])
        return v
    return a["values"][int(rng.integers(len(a["values"])))]


def load_spec(path: str | Path) -> Spec:
    """Read and check the spec file at ``path`` (:class:`SpecError`: one line)."""
    p = Path(path)
    try:
        doc = tomllib.loads(p.read_text(encoding="utf-8"))
    except OSError as exc:
        raise SpecError(f"cannot read spec {str(p)!r}: {exc.strerror or exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise SpecError(f"{p.name}: not valid TOML: {exc}") from None
    return parse_spec(doc, base=p.parent, path=p)


def _table(doc: dict[str, Any], key: str) -> dict[str, Any]:
    t = doc.get(key, {})
    if not isinstance(t, dict):
        raise SpecError(f"[{key}] must be a table")
    return t


def _input_value(name: str, val: Any, where: str) -> Any:
    if name == "controller":
        if val not in _CONTROLLERS:
            raise SpecError(f"{where} must be one of {list(_CONTROLLERS)}, got {val!r}")
        return val
    return to_si(val, INPUTS[name][0], where)


def parse_spec(doc: dict[str, Any], base: Path | None = None, path: Path | None = None) -> Spec:
    """A :class:`Spec` from a parsed TOML document; DCF paths relative to ``base``."""
    extra = sorted(set(doc) - {"sweep", "gains", "motor", "protection", "parameters", "limits",
                               "scenarios", "scenario"})  # fmt: skip
    if extra:
        raise SpecError(f"unknown table(s) {extra}")
    sw = _table(doc, "sweep")
    known_sw = {"name", "seed", "samples", "model", "stability_band", "batch", "map"}
    if set(sw) - known_sw:
        raise SpecError(f"[sweep]: unknown key(s) {sorted(set(sw) - known_sw)}")
    nominal = nominal_inputs()
    gains = dict(_table(doc, "gains"))
    if "type" in gains:
        gains["controller"] = gains.pop("type")
    if "dcf" in gains:
        dcf = Path(str(gains.pop("dcf")))
        nominal.update(read_gain_set(dcf if dcf.is_absolute() or base is None else base / dcf))
    for table, keys, values in (("gains", _GAIN_KEYS, gains),
                                ("motor", _MOTOR_KEYS, _table(doc, "motor")),
                                ("protection", _PROT_KEYS, _table(doc, "protection"))):  # fmt: skip
        for k, v in values.items():
            if k not in keys:
                raise SpecError(f"[{table}].{k}: unknown (known: {list(keys)})")
            nominal[k] = _input_value(k, v, f"[{table}].{k}")
    if "k_e" in nominal:
        nominal["K_rpm"] = k_rpm_of(nominal.pop("k_e"))
    nominal["k_e"] = derived_k_e(nominal["K_rpm"])
    params = tuple(_param(k, v) for k, v in _table(doc, "parameters").items())
    names = [p.name for p in params]
    for ratio, (est, _mot) in RATIOS.items():
        if ratio in names and est in names:
            raise SpecError(f"[parameters]: give {ratio!r} or {est!r}, not both")
    if "k_e" in names and "K_rpm" in names:
        raise SpecError("[parameters]: give 'k_e' or 'K_rpm', not both")
    sc_docs = doc.get("scenarios", [])
    if "scenario" in doc:
        sc_docs = [doc["scenario"], *sc_docs]
    if not isinstance(sc_docs, list) or not sc_docs:
        raise SpecError("no scenario: add a [[scenarios]] table")
    scenarios = tuple(parse_scenario(d, i) for i, d in enumerate(sc_docs))
    glob = _table(doc, "limits")
    limits = tuple(
        resolve_limits(glob, s.limits, s.unit, f"scenarios[{i}]") for i, s in enumerate(scenarios)
    )
    seed = sw.get("seed", 0)
    samples = sw.get("samples", 1)
    batch = sw.get("batch", 0)
    for k, v in (("seed", seed), ("samples", samples), ("batch", batch)):
        if isinstance(v, bool) or not isinstance(v, int) or v < 0 or (k == "samples" and v < 1):
            raise SpecError(f"[sweep].{k} must be an integer >= {1 if k == 'samples' else 0}")
    model = sw.get("model", "pwm")
    if model not in ("pwm", "averaged"):
        raise SpecError(f"[sweep].model must be 'pwm' or 'averaged', got {model!r}")
    band = float(sw.get("stability_band", 0.25))
    if not 0.0 < band <= 10.0:
        raise SpecError("[sweep].stability_band must be in (0, 10]")
    mp = sw.get("map")
    if mp is not None:
        if not (isinstance(mp, list) and len(mp) == 2 and all(isinstance(x, str) for x in mp)):
            raise SpecError("[sweep].map must be two parameter names")
        bad = [m for m in mp if m not in INPUTS and m not in RATIOS]
        if bad:
            known = [*INPUTS, *RATIOS]
            raise SpecError(f"[sweep].map: {bad[0]!r} is not an input (known: {known})")
        mp = (mp[0], mp[1])
    spec = Spec(
        path=path, name=str(sw.get("name", path.stem if path else "sweep")), seed=seed,
        samples=samples, model=model, band=band, batch=batch, nominal=nominal, params=params,
        scenarios=scenarios, limits=limits, map=mp,
    )  # fmt: skip
    if spec.n_runs > 10_000_000:
        raise SpecError(f"{spec.n_runs} runs: more than 10,000,000")
    return spec


def _param(name: str, v: Any) -> Param:
    where = f"[parameters].{name}"
    if name not in INPUTS and name not in RATIOS:
        raise SpecError(f"{where}: unknown input (known: {[*INPUTS, *RATIOS]})")
    if not isinstance(v, dict):
        v = {"values": v if isinstance(v, list) else [v]}
    keys = set(v)
    unit = v.get("unit", "")
    if name == "controller" and unit:
        raise SpecError(f"{where}: the controller type takes no unit")
    relative = unit in ("%", "percent")
    si = "dimensionless" if name in RATIOS else INPUTS[name][0]
    factor = 1.0 if relative or not unit or name == "controller" else scale_to(unit, si, where)

    def num(x: Any, what: str) -> float:
        if isinstance(x, str):
            return to_si(x, si, f"{where}.{what}")
        if isinstance(x, bool) or not isinstance(x, int | float) or not math.isfinite(x):
            raise SpecError(f"{where}.{what}: expected a number, got {x!r}")
        return clean(float(x) * factor)

    if "dist" in v:
        dist = v["dist"]
        if dist not in _DISTS:
            raise SpecError(f"{where}.dist must be one of {list(_DISTS)}, got {dist!r}")
        need = {"uniform": ("low", "high"), "loguniform": ("low", "high"),
                "normal": ("mean", "std"), "choice": ("values",)}[dist]  # fmt: skip
        allowed = {"dist", "unit", "clip", *need}
        if set(need) - keys or keys - allowed:
            raise SpecError(f"{where}: dist {dist!r} takes {list(need)} (+ unit, clip)")
        if dist == "choice":
            vals = v["values"]
            if not isinstance(vals, list) or not vals:
                raise SpecError(f"{where}.values must be a non-empty list")
            args: dict[str, Any] = {"values": tuple(_grid_value(name, x, num, where) for x in vals)}
        else:
            args = {k: num(v[k], k) for k in need}
            if "clip" in v:
                c = v["clip"]
                if not (isinstance(c, list) and len(c) == 2):
                    raise SpecError(f"{where}.clip must be [low, high]")
                args["clip"] = (num(c[0], "clip"), num(c[1], "clip"))
            if dist in ("uniform", "loguniform") and not args["low"] < args["high"]:
                raise SpecError(f"{where}: low must be < high")
            if dist == "loguniform" and args["low"] <= 0:
                raise SpecError(f"{where}: loguniform needs low > 0")
            if dist == "normal" and args["std"] < 0:
                raise SpecError(f"{where}: std must be >= 0")
        return Param(name=name, dist=dist, args=args, relative=relative)
    grid_keys = [k for k in ("values", "linspace", "geomspace") if k in keys]
    if len(grid_keys) != 1 or keys - {"values", "linspace", "geomspace", "unit"}:
        raise SpecError(f"{where}: give one of values / linspace / geomspace / dist (+ unit)")
    gk = grid_keys[0]
    if gk == "values":
        vals = v["values"]
        if not isinstance(vals, list) or not vals:
            raise SpecError(f"{where}.values must be a non-empty list")
        values = tuple(_grid_value(name, x, num, where) for x in vals)
    else:
        a = v[gk]
        if not (isinstance(a, list) and len(a) == 3 and isinstance(a[2], int) and a[2] >= 1):
            raise SpecError(f"{where}.{gk} must be [start, stop, num] with num >= 1")
        lo, hi = num(a[0], gk), num(a[1], gk)
        if gk == "geomspace" and (lo <= 0 or hi <= 0):
            raise SpecError(f"{where}.geomspace needs start, stop > 0")
        fn = np.linspace if gk == "linspace" else np.geomspace
        values = tuple(float(x) for x in fn(lo, hi, a[2]))
    return Param(name=name, values=values, relative=relative)


def _grid_value(name: str, x: Any, num: Any, where: str) -> Any:
    if name == "controller":
        if x not in _CONTROLLERS:
            raise SpecError(f"{where}: controller must be one of {list(_CONTROLLERS)}, got {x!r}")
        return x
    return num(x, "values")
