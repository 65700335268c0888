"""Richardson extrapolation and the observed order of convergence.

For a quantity computed with a discretisation parameter n (here the rod count) that behaves as

    a_n = a + c n^(-p) + o(n^(-p)),

three values on a geometric sequence n, r n, r^2 n give (Roache 1998, "Verification and
Validation in Computational Science and Engineering", section 5.4; Richardson 1911):

    p   = ln((a_n - a_rn) / (a_rn - a_r2n)) / ln r                  (observed order)
    a  ~= a_r2n + (a_r2n - a_rn) / (r^p - 1)                          (extrapolated value)

Derivation: a_n - a_rn = c n^-p (1 - r^-p) and a_rn - a_r2n = c n^-p r^-p (1 - r^-p); their
ratio is r^p.  Then a_r2n - a = c (r^2 n)^-p = (a_rn - a_r2n) / (r^p - 1).

The formulas need the two differences to be non-zero and of the same sign (monotone
convergence); otherwise the sequence is not in its asymptotic range (or is at round-off) and
:func:`observed_order` returns NaN rather than a meaningless number.
"""

from __future__ import annotations

import math
from collections.abc import Sequence


def observed_order(a_n: float, a_rn: float, a_r2n: float, ratio: float = 2.0) -> float:
    """Observed order p from three values at n, r n, r^2 n (NaN when not monotone)."""
    if not ratio > 1.0:
        raise ValueError(f"ratio: expected a refinement ratio > 1, got {ratio!r}")
    d1 = a_n - a_rn
    d2 = a_rn - a_r2n
    if d1 == 0.0 or d2 == 0.0 or (d1 > 0) != (d2 > 0) or not (math.isfinite(d1) and math.isfinite(d2)):
        return math.nan
    return math.log(d1 / d2) / math.log(ratio)


def extrapolate(a_rn: float, a_r2n: float, order: float, ratio: float = 2.0) -> float:
    """Richardson estimate of the limit from the two finest values and the order (NaN if p is)."""
    if not ratio > 1.0:
        raise ValueError(f"ratio: expected a refinement ratio > 1, got {ratio!r}")
    if not (math.isfinite(order) and order > 0):
        return math.nan
    return a_r2n + (a_r2n - a_rn) / (ratio**order - 1.0)


def richardson(ns: Sequence[float], values: Sequence[float]) -> dict[str, float]:
    """Observed order and extrapolated limit from the three finest points of a geometric sequence.

    ``ns`` must be increasing with a constant ratio over its last three entries (e.g. 1, 2, 4, 8).
    Returns ``{"order", "limit", "ratio", "error_estimate"}``; ``error_estimate`` is
    |limit - finest value| (Roache's error estimate of the finest point).
    """
    if len(ns) != len(values):
        raise ValueError(f"ns and values: expected equal lengths, got {len(ns)} and {len(values)}")
    if len(ns) < 3:
        raise ValueError(f"ns: expected at least three points, got {len(ns)}")
    n1, n2, n3 = (float(x) for x in ns[-3:])
    if not (0 < n1 < n2 < n3):
        raise ValueError(f"ns: expected increasing positive counts, got {list(ns)[-3:]}")
    r = n2 / n1
    if not math.isclose(n3 / n2, r, rel_tol=1e-12):
        raise ValueError(f"ns: expected a constant refinement ratio over the last three, got {n1}, {n2}, {n3}")
    a1, a2, a3 = (float(v) for v in values[-3:])
    p = observed_order(a1, a2, a3, r)
    limit = extrapolate(a2, a3, p, r)
    return {"order": p, "limit": limit, "ratio": r, "error_estimate": abs(limit - a3) if math.isfinite(limit) else math.nan}
