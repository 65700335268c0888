"""The uncertainty study file (``studies/uncertainty/*.toml``) and its validation.

::

    name = "deorbit-small"
    description = "..."
    scene = "../scenes/deorbit-ed.toml"                 # relative to the study file
    summary = "tetherlab.uncertainty.summaries:deorbit_days"   # module:function, scene -> dict
    quantities = ["deorbit_days"]                       # the summary keys the statistics are about

    [set]                                               # fixed changes to the base scene
    "output.step" = "1 d"

    [sampling]
    method = "sobol"                                    # mc, lhs or sobol
    samples = 256
    seed = 20261202
    block = 64                                          # lhs only: rows per Latin hypercube

    [deadlines]                                         # P(quantity <= deadline), per quantity
    deorbit_days = [40.0, 45.0]

    [[dispersion]]
    key = "effects.electrodynamic.current"
    dist = "normal"
    mean = "2 A"
    sd = "0.1 A"

    [[correlation]]                                     # normal-score correlation (Gaussian copula)
    keys = ["bodies.satellite.mass", "bodies.end_mass.mass"]
    rho = 0.3

    [sensitivity]                                       # optional: python -m tetherlab.uncertainty --sensitivity
    method = "sobol"                                    # or "morris"
    samples = 64                                        # Saltelli base N (N (d + 2) runs) / Morris trajectories
    levels = 4                                          # morris only

Everything is checked by :func:`load_uncertainty_study` before any sample runs: the scene loads,
[set] applies, every dispersion names a key of the scene with the right dimension and valid
parameters, the correlation matrix is valid, the sample count is positive; each error names its key.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .dispersions import Correlation, Dispersion, DispersionError, parse_correlations, parse_dispersion
from .samplers import METHODS, Sampler, make_sampler

_TOP = {"name", "description", "scene", "summary", "quantities", "set", "sampling", "deadlines",
        "dispersion", "correlation", "sensitivity"}


@dataclass
class UncertaintyStudy:
    name: str
    path: Path
    scene_path: Path
    summary: str
    quantities: list[str]
    set: dict[str, Any]
    method: str
    samples: int
    seed: int
    block: int
    dispersions: list[Dispersion]
    correlation: Correlation | None
    deadlines: dict[str, list[float]] = field(default_factory=dict)
    sensitivity: dict[str, Any] = field(default_factory=dict)
    description: str = ""

    def base_scene(self):
        from ..scene import load_scene

        base = load_scene(self.scene_path)
        return base.replace(**self.set) if self.set else base

    def sampler(self) -> Sampler:
        return make_sampler(self.method, len(self.dispersions), self.seed, self.block)

    @property
    def keys(self) -> list[str]:
        return [d.key for d in self.dispersions]


def _err(path, key, expected, got) -> ValueError:
    return ValueError(f"{path}: {key!r}: expected {expected}, got {got}")


def _positive_int(value, path, key) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise _err(path, key, "a positive integer", repr(value))
    return value


def parse_study(data: dict, path: Path, *, samples: int | None = None) -> UncertaintyStudy:
    unknown = sorted(set(data) - _TOP)
    if unknown:
        raise _err(path, ", ".join(unknown), f"only the keys {sorted(_TOP)}", "unknown keys")
    for key in ("scene", "summary"):
        if not isinstance(data.get(key), str):
            raise _err(path, key, "a string", repr(data.get(key)))
    scene_path = Path(data["scene"])
    if not scene_path.is_absolute():
        scene_path = path.parent / scene_path
    quantities = data.get("quantities")
    if not isinstance(quantities, list) or not quantities or not all(isinstance(q, str) for q in quantities):
        raise _err(path, "quantities", "a non-empty list of summary keys", repr(quantities))
    sampling = data.get("sampling", {})
    if not isinstance(sampling, dict) or set(sampling) - {"method", "samples", "seed", "block"}:
        raise _err(path, "sampling", "a table of method, samples, seed, block", repr(sampling))
    method = sampling.get("method", "sobol")
    if method not in METHODS:
        raise _err(path, "sampling.method", f"one of {', '.join(METHODS)}", repr(method))
    n = _positive_int(sampling.get("samples") if samples is None else samples, path, "sampling.samples")
    seed = sampling.get("seed")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise _err(path, "sampling.seed", "a non-negative integer (a study is reproducible from it)", repr(seed))
    block = sampling.get("block", 64)
    if isinstance(block, bool) or not isinstance(block, int) or block < 2:
        raise _err(path, "sampling.block", "an integer >= 2", repr(block))
    set_ = data.get("set", {})
    if not isinstance(set_, dict):
        raise _err(path, "set", "a table of dotted scene keys", repr(set_))

    from ..scene import load_scene

    base = load_scene(scene_path)
    if set_:
        base = base.replace(**set_)
    scene_dict = base.to_dict()
    raw = data.get("dispersion")
    if not isinstance(raw, list) or not raw:
        raise _err(path, "dispersion", "at least one [[dispersion]] table", repr(raw))
    try:
        dispersions = [parse_dispersion(r, scene_dict) for r in raw]
        keys = [d.key for d in dispersions]
        dup = sorted({k for k in keys if keys.count(k) > 1})
        if dup:
            raise DispersionError(dup[0], "one dispersion per key", f"{keys.count(dup[0])}")
        corr = parse_correlations(data.get("correlation"), dispersions)
    except DispersionError as exc:
        raise ValueError(f"{path}: {exc}") from None
    deadlines = data.get("deadlines", {})
    if not isinstance(deadlines, dict):
        raise _err(path, "deadlines", "a table: quantity = [deadlines]", repr(deadlines))
    dl: dict[str, list[float]] = {}
    for q, v in deadlines.items():
        if q not in quantities:
            raise _err(path, f"deadlines.{q}", f"one of the quantities {quantities}", "not a quantity")
        v = v if isinstance(v, list) else [v]
        if not all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x) for x in v):
            raise _err(path, f"deadlines.{q}", "finite numbers in the quantity's unit", repr(v))
        dl[q] = [float(x) for x in v]
    sens = data.get("sensitivity", {})
    if not isinstance(sens, dict) or set(sens) - {"method", "samples", "levels", "seed"}:
        raise _err(path, "sensitivity", "a table of method, samples, levels, seed", repr(sens))
    if sens:
        if sens.get("method", "sobol") not in ("sobol", "morris"):
            raise _err(path, "sensitivity.method", "'sobol' or 'morris'", repr(sens.get("method")))
        _positive_int(sens.get("samples", 64), path, "sensitivity.samples")
    return UncertaintyStudy(
        name=str(data.get("name", path.stem)), path=path, scene_path=scene_path, summary=data["summary"],
        quantities=list(quantities), set=dict(set_), method=method, samples=n, seed=seed, block=block,
        dispersions=dispersions, correlation=corr, deadlines=dl, sensitivity=dict(sens),
        description=str(data.get("description", "")),
    )


def load_uncertainty_study(path: str | Path, *, samples: int | None = None) -> UncertaintyStudy:
    """Read and check a study file; ``samples`` overrides ``sampling.samples`` (an extension)."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise FileNotFoundError(f"study file {str(path)!r} does not exist") from None
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{path}: not valid TOML: {exc}") from None
    return parse_study(data, path, samples=samples)
