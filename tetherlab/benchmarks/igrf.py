"""Cost of one IGRF evaluation against the truncation degree (target: degree 13 in a few us).

The compiled kernel environment/igrf.py::field_ecef called from a compiled loop (points moving so
nothing is constant-folded), degrees 1 to 13; the cost should grow as the number of coefficients,
N (N + 3)/2 ~ N^2: the exponent is the log-log slope between degrees 4 and 13.
"""

from __future__ import annotations

import datetime as dt
import math
import time

import numpy as np

from .._jit import njit
from ..environment import igrf

DEGREES = (1, 2, 4, 8, 13)


@njit(cache=True)
def _loop(p, n):
    s = 0.0
    for k in range(n):
        a = 0.001 * k
        bx, by, bz = igrf.field_ecef(p, 0, 1.0 * k, 7.0e6 * math.cos(a), 7.0e6 * math.sin(a), 1.0e6 + 10.0 * k)
        s += bx + by + bz
    return s


def bench_rows(repeats: int = 5) -> list[dict]:
    rows = []
    for nmax in DEGREES:
        p = np.array(igrf.pack(dt.datetime(2026, 3, 1), nmax=nmax))
        _loop(p, 10)
        n = 200000
        best = math.inf
        for _ in range(repeats):
            t0 = time.perf_counter()
            _loop(p, n)
            best = min(best, (time.perf_counter() - t0) / n)
        rows.append({"degree": nmax, "coefficients": nmax * (nmax + 3), "us_per_eval": best * 1e6})
    c4 = next(r for r in rows if r["degree"] == 4)["us_per_eval"]
    c13 = rows[-1]["us_per_eval"]
    for r in rows:
        r["exponent (deg 4-13)"] = math.log(c13 / c4) / math.log(13 / 4)
    return rows


if __name__ == "__main__":
    from ..bench import _print_table

    _print_table("IGRF-14 evaluation cost against the degree", bench_rows())
