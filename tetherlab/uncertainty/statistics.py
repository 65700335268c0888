"""Statistics of a sampled quantity, each with a bootstrap confidence interval.

:func:`describe` gives the mean, the standard deviation and variance, the 5 / 50 / 95 % quantiles
and the probability of meeting each deadline (quantity <= deadline), each with a percentile
bootstrap interval (Efron & Tibshirani 1993, ch. 13: ``n_boot`` resamples with replacement, the
interval between the (1 - level)/2 and (1 + level)/2 quantiles of the resampled statistic; the
resampling generator is seeded, so the interval is reproducible).  The bootstrap treats the sample
as independent draws: right for plain Monte Carlo; for a Latin hypercube or Sobol' design it is
conservative (their error is smaller than an independent sample's), which is what the convergence
study measures by independent replications (:func:`replicated_width`).

Failed samples are not in the statistics (they have no value) but are counted: ``n_failed`` and,
for each deadline, ``p_meet_failed_as_miss`` (a failed sample counted as missing the deadline: the
conservative bound a mission analyst quotes when failures are not understood).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

QUANTILES = (0.05, 0.50, 0.95)


def bootstrap_ci(x: np.ndarray, stat: Callable[[np.ndarray], np.ndarray], *, n_boot: int = 2000,
                 level: float = 0.95, seed: int = 0) -> tuple[float, float, float]:
    """(estimate, low, high): ``stat`` on ``x`` and its percentile bootstrap interval.

    ``stat(a)`` must reduce along the last axis (it is called once on an n_boot x n array).
    """
    x = np.asarray(x, dtype=float)
    if x.size == 0:
        return math.nan, math.nan, math.nan
    est = float(stat(x[None, :])[0])
    idx = np.random.default_rng(seed).integers(0, x.size, size=(n_boot, x.size))
    boot = stat(x[idx])
    lo, hi = np.quantile(boot, [(1.0 - level) / 2.0, (1.0 + level) / 2.0])
    return est, float(lo), float(hi)


def _mean(a):
    return a.mean(axis=-1)


def _var(a):
    return a.var(axis=-1, ddof=1) if a.shape[-1] > 1 else np.full(a.shape[:-1], math.nan)


def _sd(a):
    return np.sqrt(_var(a))


def _quantile(q):
    def f(a):
        return np.quantile(a, q, axis=-1)

    return f


def _below(d):
    def f(a):
        return (a <= d).mean(axis=-1)

    return f


def describe(values: Sequence[float], *, deadlines: Sequence[float] = (), n_failed: int = 0,
             n_boot: int = 2000, level: float = 0.95, seed: int = 0) -> dict[str, dict[str, float]]:
    """``{statistic: {"value", "low", "high"}}`` for the successful samples ``values``."""
    x = np.asarray(values, dtype=float)
    out: dict[str, dict[str, float]] = {}
    stats: list[tuple[str, Callable]] = [("mean", _mean), ("sd", _sd), ("var", _var)]
    stats += [(f"q{round(q * 100):02d}", _quantile(q)) for q in QUANTILES]
    stats += [(f"p_meet_{d!r}", _below(d)) for d in deadlines]
    for k, (name, f) in enumerate(stats):
        if x.size < 2:
            est = float(f(x[None, :])[0]) if x.size else math.nan
            out[name] = {"value": est, "low": math.nan, "high": math.nan}
            continue
        # one seed per statistic: adding a deadline does not move the other intervals
        v, lo, hi = bootstrap_ci(x, f, n_boot=n_boot, level=level, seed=seed + 7919 * k)
        out[name] = {"value": v, "low": lo, "high": hi}
    n_all = x.size + n_failed
    for d in deadlines:
        met = float((x <= d).sum())
        out[f"p_meet_failed_as_miss_{d!r}"] = {"value": met / n_all if n_all else math.nan,
                                               "low": math.nan, "high": math.nan}
    out["n_ok"] = {"value": float(x.size), "low": math.nan, "high": math.nan}
    out["n_failed"] = {"value": float(n_failed), "low": math.nan, "high": math.nan}
    return out


def ci_width_curve(values: Sequence[float], ns: Sequence[int], *, n_boot: int = 1000,
                   level: float = 0.95, seed: int = 0) -> list[tuple[int, float]]:
    """Bootstrap width of the mean's interval on the first n samples, for each n in ``ns``
    (the samples are in draw order, so a prefix is the study at that size)."""
    x = np.asarray(values, dtype=float)
    rows = []
    for n in ns:
        if 2 <= n <= x.size:
            _, lo, hi = bootstrap_ci(x[:n], _mean, n_boot=n_boot, level=level, seed=seed)
            rows.append((int(n), hi - lo))
    return rows


def replicated_width(draw: Callable[[int, int], np.ndarray], f: Callable[[np.ndarray], np.ndarray],
                     ns: Sequence[int], replications: int = 30, level: float = 0.95) -> list[tuple[int, float]]:
    """Width of a ``level`` interval of the mean estimated from ``replications`` independent
    studies (``draw(n, r)``: the points of replication r; ``f``: the quantity, vectorised):
    2 z sd(estimates).  Valid for any design, Sobol' included (randomised QMC: each scrambling is
    an independent replication; Owen 1997)."""
    from scipy.special import ndtri

    z = float(ndtri(0.5 + level / 2.0))
    rows = []
    for n in ns:
        est = np.array([f(draw(n, r)).mean() for r in range(replications)])
        rows.append((int(n), 2.0 * z * float(est.std(ddof=1))))
    return rows


def fit_slope(rows: Sequence[tuple[int, float]]) -> tuple[float, float]:
    """Least-squares slope of log(width) against log(n), and its standard error."""
    n = np.log([r[0] for r in rows])
    w = np.log([r[1] for r in rows])
    if len(rows) < 3:
        return math.nan, math.nan
    A = np.vstack([n, np.ones_like(n)]).T
    coef, res, *_ = np.linalg.lstsq(A, w, rcond=None)
    resid = w - A @ coef
    s2 = float(resid @ resid) / (len(rows) - 2)
    se = math.sqrt(s2 / float(((n - n.mean()) ** 2).sum()))
    return float(coef[0]), se
