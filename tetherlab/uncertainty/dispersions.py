"""Dispersions: the distribution of one scene key, and the correlations between them.

A dispersion maps a uniform number u in (0, 1) to a value of its key through the inverse of its
cumulative distribution (so every sampler -- plain Monte Carlo, Latin hypercube, Sobol' -- only
draws points in the unit cube).  Correlations act on the normal scores z = Phi^-1(u) (a Gaussian
copula): z' = L z with L the Cholesky factor of the correlation matrix, u' = Phi(z').  The matrix
is that of the normal scores, not of the values (for normal marginals they coincide; for others
the value correlation is slightly smaller in magnitude).

Every parameter is a scene-file quantity with its unit ("2 A", "0.1 A", "35 deg"); a value is
written back into the scene as ``"<repr of the float> <unit of the dispersion>"``, so a sample
reproduces bit for bit.  Kinds (``dist``):

* ``normal``: ``mean``, ``sd``;
* ``truncnormal``: ``mean``, ``sd``, ``low``, ``high`` (the normal restricted to [low, high]);
* ``uniform``: ``low``, ``high``;
* ``lognormal``: ``median`` (a quantity) and ``sigma_log`` (the standard deviation of the
  natural log, a bare number): value = median exp(sigma_log z);
* ``choice``: ``values`` (a list of scene values, any type: strings, quantities, integers) and
  optional ``weights`` (positive, normalised here).

The ``epoch`` is dispersed as a date: ``normal`` (``mean`` an ISO date, ``sd`` a time such as
"30 d"), ``uniform`` (``low``, ``high`` ISO dates) or ``truncnormal`` (all four); internally in
days from J2000 (TDB), written back as an ISO date to the microsecond.  A tether's initial angles
(``tethers.<name>.initial.theta`` / ``phi``) are dispersable on a scene that leaves the default
straight shape implicit (its ``to_dict`` omits it): the default's values stand in for it.

Bad input is refused by :func:`validate` before any sample runs, each error naming the key.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import stats
from scipy.special import ndtri

KINDS = ("normal", "truncnormal", "uniform", "lognormal", "choice")
_PARAMS = {
    "normal": ("mean", "sd"),
    "truncnormal": ("mean", "sd", "low", "high"),
    "uniform": ("low", "high"),
    "lognormal": ("median", "sigma_log"),
    "choice": ("values",),
}
_OPTIONAL = {"choice": ("weights",)}
# A point of a scrambled Sobol' net or of SALib's designs can be 0 or 1 exactly, where the
# inverse normal is infinite; a uniform is clipped to [2^-53, 1 - 2^-53] (Phi^-1: -8.1 .. 8.1).
U_MIN = 2.0**-53
U_MAX = 1.0 - 2.0**-53


class DispersionError(ValueError):
    """A dispersion or correlation refused, naming the key, the expected value and what was got."""

    def __init__(self, key: str, expected: str, got: str):
        self.key, self.expected, self.got = key, expected, got
        super().__init__(f"dispersion of {key!r}: expected {expected}, got {got}")


@dataclass(frozen=True)
class Dispersion:
    """The distribution of one scene key; parameters as floats in ``unit`` (``""``: a bare number)."""

    key: str
    dist: str
    params: dict[str, float] = field(default_factory=dict)
    unit: str = ""
    values: tuple = ()  # choice only
    weights: tuple[float, ...] = ()  # choice only, summing to 1
    kind: str = "quantity"  # "epoch": values are days from J2000 (TDB), written as ISO dates


    def ppf(self, u: np.ndarray) -> np.ndarray:
        """The values (floats in ``unit``; for a choice, the indices into ``values``) at u."""
        u = np.clip(np.asarray(u, dtype=float), U_MIN, U_MAX)
        p = self.params
        if self.dist == "normal":
            return p["mean"] + p["sd"] * ndtri(u)
        if self.dist == "uniform":
            return p["low"] + (p["high"] - p["low"]) * u
        if self.dist == "lognormal":
            return p["median"] * np.exp(p["sigma_log"] * ndtri(u))
        if self.dist == "truncnormal":
            a = (p["low"] - p["mean"]) / p["sd"]
            b = (p["high"] - p["mean"]) / p["sd"]
            return np.clip(stats.truncnorm.ppf(u, a, b, loc=p["mean"], scale=p["sd"]), p["low"], p["high"])
        if self.dist == "choice":
            edges = np.cumsum(self.weights)
            edges[-1] = 1.0
            return np.searchsorted(edges, u, side="right").clip(0, len(self.values) - 1).astype(float)
        raise AssertionError(self.dist)  # validate() admits only KINDS

    def scene_value(self, x: float) -> Any:
        """The scene-file value for one sampled float (repr keeps every digit)."""
        if self.dist == "choice":
            return self.values[int(x)]
        if self.kind == "epoch":
            return iso_date(float(x))
        return f"{float(x)!r} {self.unit}" if self.unit else float(x)

    # analytic moments, for the report and the verification gate
    def mean(self) -> float:
        p = self.params
        if self.dist == "normal":
            return p["mean"]
        if self.dist == "uniform":
            return 0.5 * (p["low"] + p["high"])
        if self.dist == "lognormal":
            return p["median"] * math.exp(0.5 * p["sigma_log"] ** 2)
        if self.dist == "truncnormal":
            a, b = (p["low"] - p["mean"]) / p["sd"], (p["high"] - p["mean"]) / p["sd"]
            return float(stats.truncnorm.mean(a, b, loc=p["mean"], scale=p["sd"]))
        return math.nan


@dataclass(frozen=True)
class Correlation:
    """The normal-score correlation matrix over some dispersed keys (a Gaussian copula)."""

    keys: tuple[str, ...]
    matrix: np.ndarray
    cholesky: np.ndarray


def _quantity(value: Any, key: str, what: str):
    from ..units import parse_quantity

    try:
        return parse_quantity(value, key=f"{key}.{what}") if not isinstance(value, (int, float)) or isinstance(value, bool) else None
    except ValueError as exc:
        raise DispersionError(key, f"{what} as a quantity with a unit, e.g. '2 A'", f"{value!r} ({exc})") from None


J2000_JD = 2451545.0


def iso_date(days: float) -> str:
    """The ISO date (TDB, to the microsecond) ``days`` after J2000 (two-part Julian date: exact)."""
    from astropy.time import Time

    t = Time(J2000_JD, days, format="jd", scale="tdb")
    t.precision = 6
    return t.isot


def _days_of_date(value: Any, key: str, what: str) -> float:
    from astropy.time import Time

    if isinstance(value, str):
        for fmt in ("isot", "iso"):
            try:
                t = Time(value, format=fmt, scale="tdb")
                return float((t.jd1 - J2000_JD) + t.jd2)
            except ValueError:
                continue
    raise DispersionError(key, f"{what!r} as an ISO date such as '2026-01-01T00:00:00' (TDB)", repr(value))


def _default_initial() -> dict:
    """The default initial shape as ``Scene.to_dict`` would write it (it omits the default)."""
    from ..scene.data import InitialShape

    d = InitialShape()
    return {"shape": d.shape, "theta": f"{float(d.theta_rad)!r} rad", "phi": f"{float(d.phi_rad)!r} rad",
            "side": d.side, "strain": float(d.strain)}


def _lookup(scene_dict: dict, key: str) -> Any:
    node: Any = scene_dict
    parts = key.split(".")
    for k, part in enumerate(parts):
        if (k == 2 and parts[0] == "tethers" and part == "initial" and isinstance(node, dict)
                and part not in node and "from" in node):
            node = _default_initial()  # a tether on the default straight shape (omitted by to_dict)
            continue
        if not isinstance(node, dict) or part not in node:
            return KeyError
        node = node[part]
    return node


def _base_unit(base_value: Any):
    """The astropy unit of a scene value written by ``Scene.to_dict`` ("5000.0 m"), None for a
    bare number, False for something that is not a quantity (a string like "paper", a table)."""
    import astropy.units as u

    if isinstance(base_value, bool) or isinstance(base_value, (dict, list)):
        return False
    if isinstance(base_value, (int, float)):
        return None
    if isinstance(base_value, str):
        try:
            return u.Quantity(base_value).unit
        except (TypeError, ValueError):
            return False
    return False


def parse_dispersion(raw: Any, scene_dict: dict, where: str = "") -> Dispersion:
    """One ``[[dispersion]]`` table, checked against the base scene (its ``to_dict()``)."""
    if not isinstance(raw, dict):
        raise DispersionError("?", "a table with key, dist and parameters", repr(raw))
    key = raw.get("key")
    if not isinstance(key, str) or not key:
        raise DispersionError(str(key), "'key': a dotted scene key, e.g. 'effects.electrodynamic.current'", repr(key))
    dist = raw.get("dist")
    if dist not in KINDS:
        raise DispersionError(key, f"'dist' one of {', '.join(KINDS)}", repr(dist))
    allowed = {"key", "dist", *_PARAMS[dist], *_OPTIONAL.get(dist, ())}
    unknown = sorted(set(raw) - allowed)
    if unknown:
        raise DispersionError(key, f"only the parameters {sorted(allowed - {'key', 'dist'})} for dist = {dist!r}",
                              f"unknown {unknown}")
    missing = [k for k in _PARAMS[dist] if k not in raw]
    if missing:
        raise DispersionError(key, f"the parameters {list(_PARAMS[dist])} for dist = {dist!r}", f"{missing} missing")
    base = _lookup(scene_dict, key)
    if base is KeyError:
        raise DispersionError(key, "a key of the base scene (after [set]; a key the scene leaves at its "
                              "default must be given there first)", "no such key")
    if dist == "choice":
        return _parse_choice(raw, key)
    if key == "epoch":
        return _parse_epoch(raw, key, dist)
    base_unit = _base_unit(base)
    if base_unit is False:
        raise DispersionError(key, "a key holding a quantity or a number (other keys take dist = 'choice')",
                              f"{base!r}")
    if isinstance(base, int) and not isinstance(base, bool) and base_unit is None and not isinstance(base, float):
        raise DispersionError(key, "a continuous key (an integer key such as a rod count takes dist = 'choice')",
                              f"{base!r}")
    names = [k for k in _PARAMS[dist] if k != "sigma_log"]
    unit = None
    params: dict[str, float] = {}
    for name in names:
        value = raw[name]
        if isinstance(value, bool) or not isinstance(value, (int, float, str)):
            raise DispersionError(key, f"{name!r} as a quantity with a unit, e.g. '2 A'", repr(value))
        if base_unit is None:  # a bare-number key: bare parameters
            if not isinstance(value, (int, float)):
                raise DispersionError(key, f"{name!r} as a bare number (the key is dimensionless)", repr(value))
            params[name] = float(value)
            continue
        q = _quantity(value, key, name)
        if q is None or (q.unit.physical_type == "dimensionless" and not base_unit.physical_type == "dimensionless"):
            raise DispersionError(key, f"{name!r} with a unit of {base_unit.physical_type} (e.g. '{base}')",
                                  f"{value!r} (missing unit)")
        if not q.unit.is_equivalent(base_unit):
            raise DispersionError(key, f"{name!r} with the dimension of the key ({base_unit.physical_type}, "
                                  f"base value {base!r})", f"{value!r} (dimension {q.unit.physical_type})")
        if unit is None:
            unit = q.unit
        params[name] = float(q.to_value(unit))
    if dist == "lognormal":
        s = raw["sigma_log"]
        if isinstance(s, bool) or not isinstance(s, (int, float)):
            raise DispersionError(key, "'sigma_log' as a bare number (the sd of the natural log)", repr(s))
        params["sigma_log"] = float(s)
    for name, v in params.items():
        if not math.isfinite(v):
            raise DispersionError(key, f"a finite {name!r}", repr(raw[name]))
    if "sd" in params and not params["sd"] > 0.0:
        raise DispersionError(key, "'sd' > 0", repr(raw["sd"]))
    if "sigma_log" in params and not params["sigma_log"] > 0.0:
        raise DispersionError(key, "'sigma_log' > 0", repr(raw["sigma_log"]))
    if "median" in params and not params["median"] > 0.0:
        raise DispersionError(key, "'median' > 0 (a log-normal value is positive)", repr(raw["median"]))
    if "low" in params and not params["low"] < params["high"]:
        raise DispersionError(key, "low < high", f"low = {raw['low']!r}, high = {raw['high']!r}")
    if dist == "truncnormal":
        a = (params["low"] - params["mean"]) / params["sd"]
        b = (params["high"] - params["mean"]) / params["sd"]
        if stats.norm.cdf(b) - stats.norm.cdf(a) < 1e-12:
            raise DispersionError(key, "bounds holding some of the normal's mass", f"[{a:.3g}, {b:.3g}] sd from the mean")
    unit_text = "" if unit is None else unit.to_string()
    return Dispersion(key=key, dist=dist, params=params, unit=unit_text)


def _parse_epoch(raw: dict, key: str, dist: str) -> Dispersion:
    """A dispersed date: dates as ISO strings, the sd as a time; stored in days from J2000."""
    if dist not in ("normal", "uniform", "truncnormal"):
        raise DispersionError(key, "dist = 'normal', 'uniform' or 'truncnormal' for a date (or 'choice' of dates)",
                              repr(dist))
    params = {name: _days_of_date(raw[name], key, name) for name in ("mean", "low", "high") if name in raw}
    if "sd" in raw:
        q = _quantity(raw["sd"], key, "sd")
        if q is None or not q.unit.is_equivalent("d"):
            raise DispersionError(key, "'sd' as a time with its unit, e.g. '30 d'", repr(raw["sd"]))
        params["sd"] = float(q.to_value("d"))
        if not (math.isfinite(params["sd"]) and params["sd"] > 0.0):
            raise DispersionError(key, "'sd' > 0", repr(raw["sd"]))
    if "low" in params and not params["low"] < params["high"]:
        raise DispersionError(key, "low < high (dates)", f"low = {raw['low']!r}, high = {raw['high']!r}")
    if dist == "truncnormal":
        a = (params["low"] - params["mean"]) / params["sd"]
        b = (params["high"] - params["mean"]) / params["sd"]
        if stats.norm.cdf(b) - stats.norm.cdf(a) < 1e-12:
            raise DispersionError(key, "bounds holding some of the normal's mass", f"[{a:.3g}, {b:.3g}] sd from the mean")
    return Dispersion(key=key, dist=dist, params=params, unit="d", kind="epoch")


def _parse_choice(raw: dict, key: str) -> Dispersion:
    values = raw["values"]
    if not isinstance(values, list) or not values:
        raise DispersionError(key, "'values': a non-empty list of scene values", repr(values))
    weights = raw.get("weights")
    if weights is None:
        w = [1.0 / len(values)] * len(values)
    else:
        if (not isinstance(weights, list) or len(weights) != len(values)
                or not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in weights)):
            raise DispersionError(key, f"'weights': {len(values)} numbers, one per value", repr(weights))
        if not all(math.isfinite(x) and x > 0 for x in weights):
            raise DispersionError(key, "'weights' all finite and > 0", repr(weights))
        total = float(sum(weights))
        w = [float(x) / total for x in weights]
    return Dispersion(key=key, dist="choice", values=tuple(values), weights=tuple(w))


def parse_correlations(raw: Any, dispersions: list[Dispersion]) -> Correlation | None:
    """``[[correlation]]`` tables: ``keys = [a, b]`` with ``rho``, or ``keys = [...]`` with ``matrix``.

    All are assembled into one matrix over the dispersed keys they name (in dispersion order);
    it must be symmetric with a unit diagonal, entries in [-1, 1], and positive definite.
    """
    if raw is None:
        return None
    if not isinstance(raw, list):
        raise DispersionError("correlation", "[[correlation]] tables", repr(raw))
    known = [d.key for d in dispersions]
    pairs: dict[tuple[str, str], float] = {}
    for k, c in enumerate(raw, 1):
        if not isinstance(c, dict) or not isinstance(c.get("keys"), list):
            raise DispersionError(f"correlation {k}", "'keys': a list of dispersed keys", repr(c))
        keys = c["keys"]
        for key in keys:
            if key not in known:
                raise DispersionError(str(key), f"a dispersed key (one of {known}) in correlation {k}", "not dispersed")
        if len(set(keys)) != len(keys):
            raise DispersionError(", ".join(map(str, keys)), f"distinct keys in correlation {k}", "a key repeated")
        if "rho" in c:
            if len(keys) != 2 or "matrix" in c or set(c) - {"keys", "rho"}:
                raise DispersionError(", ".join(keys), "'rho' with exactly two keys", repr(c))
            entries = {(keys[0], keys[1]): c["rho"]}
        elif "matrix" in c:
            m = c["matrix"]
            if set(c) - {"keys", "matrix"}:
                raise DispersionError(", ".join(keys), "only 'keys' and 'matrix'", repr(sorted(c)))
            if (not isinstance(m, list) or len(m) != len(keys)
                    or not all(isinstance(r, list) and len(r) == len(keys) for r in m)):
                raise DispersionError(", ".join(keys), f"'matrix': {len(keys)} x {len(keys)}", repr(m))
            for i in range(len(keys)):
                if m[i][i] != 1:
                    raise DispersionError(keys[i], "a unit diagonal in the correlation matrix", repr(m[i][i]))
                for j in range(len(keys)):
                    if m[i][j] != m[j][i]:
                        raise DispersionError(f"{keys[i]}, {keys[j]}", "a symmetric correlation matrix",
                                              f"{m[i][j]!r} and {m[j][i]!r}")
            entries = {(keys[i], keys[j]): m[i][j] for i in range(len(keys)) for j in range(i + 1, len(keys))}
        else:
            raise DispersionError(", ".join(map(str, keys)), f"'rho' or 'matrix' in correlation {k}", "neither")
        for (a, b), rho in entries.items():
            if isinstance(rho, bool) or not isinstance(rho, (int, float)) or not math.isfinite(rho):
                raise DispersionError(f"{a}, {b}", "a correlation as a number", repr(rho))
            if not -1.0 <= rho <= 1.0:
                raise DispersionError(f"{a}, {b}", "a correlation in [-1, 1]", repr(rho))
            pair = tuple(sorted((a, b), key=known.index))
            if pair in pairs and pairs[pair] != rho:
                raise DispersionError(f"{a}, {b}", "one correlation per pair", f"{pairs[pair]!r} and {rho!r}")
            pairs[pair] = float(rho)
    names = sorted({k for p in pairs for k in p}, key=known.index)
    if not names:
        return None
    idx = {k: i for i, k in enumerate(names)}
    m = np.eye(len(names))
    for (a, b), rho in pairs.items():
        m[idx[a], idx[b]] = m[idx[b], idx[a]] = rho
    try:
        chol = np.linalg.cholesky(m)
    except np.linalg.LinAlgError:
        chol = None
    smallest = float(np.linalg.eigvalsh(m).min())
    if chol is None or smallest <= 1e-12:
        raise DispersionError(", ".join(names), "a positive-definite correlation matrix",
                              f"smallest eigenvalue {smallest:.3g}")
    return Correlation(keys=tuple(names), matrix=m, cholesky=chol)


def apply_copula(u: np.ndarray, dispersions: list[Dispersion], corr: Correlation | None) -> np.ndarray:
    """Correlate the columns of ``u`` (n x d, one column per dispersion) through the copula."""
    if corr is None:
        return u
    cols = [[d.key for d in dispersions].index(k) for k in corr.keys]
    out = np.array(u, dtype=float, copy=True)
    z = ndtri(np.clip(out[:, cols], U_MIN, U_MAX))
    out[:, cols] = stats.norm.cdf(z @ corr.cholesky.T)
    return out
