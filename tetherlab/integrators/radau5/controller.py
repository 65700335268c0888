"""RADAU5's step-size controller: the step ratio from the error estimate, Gustafsson's predictive
correction (RADAU5 with PRED = true), the Newton-rate cap (THETA_STEP, docs/integrators.md
section 7) and the step factor after a Newton iteration predicted to miss its iteration limit.
Each returns what the step loop (:mod:`.core`) assigns; the loop decides when each applies."""

from __future__ import annotations

import numpy as np

from tetherlab._jit import njit

from .constants import FACL, FACR, SAFE


@njit(cache=True)
def error_quotient(err, newt, nit, cfac):
    """h / h_new from the error estimate err (Hairer's FAC and QUOT: the safety factor falls with
    the Newton iterations spent; the ratio is bounded by FACR ... FACL)."""
    fac = min(SAFE, cfac / (newt + 2 * nit))
    return max(FACR, min(FACL, err**0.25 / fac))


@njit(cache=True)
def gustafsson_quotient(quot, h, hacc, err, erracc):
    """The larger of ``quot`` and Gustafsson's predictive ratio from the last accepted step
    (hacc, erracc) and this one (h, err)."""
    facgus = (hacc / h) * (err * err / erracc) ** 0.25 / SAFE
    facgus = max(FACR, min(FACL, facgus))
    return max(quot, facgus)


@njit(cache=True)
def newton_rate_cap(hnew, h, thstep, theta):
    """h_new capped so the next fresh Jacobian's Newton rate, growing like h^2, stays near thstep."""
    return min(hnew, h * np.sqrt(thstep / theta))


@njit(cache=True)
def newton_slow_factor(dyth, nit, newt):
    """The step factor after iteration ``newt`` predicted a miss of the limit nit by dyth
    (Hairer's QNEWT and HHFAC)."""
    qnewt = max(1e-4, min(20.0, dyth))
    return 0.8 * qnewt ** (-1.0 / (4.0 + nit - 1 - newt))
