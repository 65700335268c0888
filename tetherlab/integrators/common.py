"""Pieces shared by every integrator kernel and the Python layer over them.

Status codes, the statistics slots, the step-size floors, the error-norm helpers, Hairer's initial
step (HINIT), output at the start time, the event bookkeeping, and the result type of a run
(:class:`IntegrationResult`, :func:`status_message`).  Kernels (DOP853/Vern9 in ``erk.py``,
RADAU5), the driver, the scipy backend and DROMO import them from here, so they behave the same at
their boundaries and no module imports another kernel's module for them (the driver <->
scipy_backend import cycle is gone: both import the result type from here).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from tetherlab._jit import njit, ptr

# Return codes of every kernel (see tetherlab.integrators.driver for their messages).
OK = 0
MAX_STEPS = 1
STEP_UNDERFLOW = 2
RHS_FAILED = 3
NON_FINITE = 4
EVENT = 5  # an event function changed sign in the step; see erk_core / radau5_core

# stats[] slots (int64[8], accumulated across calls).
ST_ACCEPTED = 0
ST_REJECTED = 1
ST_NRHS = 2
ST_NJAC = 3
ST_NLU = 4
ST_RHS_STATUS = 5
ST_NEWTON_FAIL = 6

EPS = float(np.finfo(np.float64).eps)
#: Consecutive failed trials caused by the rhs (nonzero status or non-finite values) after which
#: a kernel gives up.  Each failure divides h by 4, so 20 of them shrink it by 4**20 ~ 1e12: if
#: that has not moved the trial stages off the bad region, the step is not the problem.
MAX_BAD_TRIALS = 20
#: Consecutive rejections of any kind after which a kernel reports STEP_UNDERFLOW.  Rejections
#: for error or Newton convergence normally come in ones and twos; a hundred in a row means the
#: controller is not converging (and guards the case t = 0, where 16*eps*|t| never triggers).
MAX_CONSECUTIVE_REJECTS = 100
#: Step-size floor relative to |t|, below which t + h == t is near and the step is meaningless.
UNDERFLOW_FACTOR = 16.0 * EPS
#: Absolute floor (for t = 0): smaller steps are denormal-range nonsense for any model.
H_FLOOR = 1e-300


@njit(cache=True)
def fill_start_outputs(t, y, t_out, y_out):
    """Rows for output times <= t (i.e. == t, after validation) get y; returns how many."""
    k = 0
    m = t_out.shape[0]
    while k < m and t_out[k] <= t:
        y_out[k, :] = y
        k += 1
    return k

@njit(cache=True)
def all_finite(v):
    for i in range(v.shape[0]):
        if not np.isfinite(v[i]):
            return False
    return True

@njit(cache=True)
def scaled_sq(v, sk):
    """(v/sk)^2 with the convention 0/0 -> 0: atol_i = 0 is allowed, and a component that is
    exactly zero (a planar problem's z) must not poison the norm with NaN."""
    if sk > 0.0:
        r = v / sk
        return r * r
    if v == 0.0:
        return 0.0
    return np.inf

@njit(cache=True)
def hinit(rhs, t, y, f0, p, rtol, atol, iord, h_cap, y1, f1, stats):
    """Initial step, Hairer's HINIT (DOP853 source; also "Solving ODEs I", II.4).

    Uses one extra rhs evaluation (an explicit Euler step) to estimate the second derivative.
    Norms are Hairer's: unnormalised sums with sk = atol + rtol*|y|.  If the probing evaluation
    fails, the first estimate is returned and the step loop's failure handling shrinks it.
    """
    n = y.shape[0]
    dnf = 0.0
    dny = 0.0
    for i in range(n):
        sk = atol[i] + rtol * abs(y[i])
        dnf += scaled_sq(f0[i], sk)
        dny += scaled_sq(y[i], sk)
    if dnf <= 1e-10 or dny <= 1e-10 or not np.isfinite(dnf) or not np.isfinite(dny):
        h = 1e-6
    else:
        h = np.sqrt(dny / dnf) * 0.01
    h = min(h, h_cap)
    for i in range(n):
        y1[i] = y[i] + h * f0[i]
    st = rhs(t + h, ptr(y1), ptr(f1), ptr(p))
    stats[ST_NRHS] += 1
    if st != 0:
        stats[ST_RHS_STATUS] = st
        return h
    der2 = 0.0
    for i in range(n):
        sk = atol[i] + rtol * abs(y[i])
        der2 += scaled_sq(f1[i] - f0[i], sk)
    if not np.isfinite(der2):
        return h
    der2 = np.sqrt(der2) / h
    der12 = max(abs(der2), np.sqrt(dnf))
    if der12 <= 1e-15:
        h1 = max(1e-6, h * 1e-3)
    else:
        h1 = (0.01 / der12) ** (1.0 / iord)
    return min(100.0 * h, h1, h_cap)

@njit(cache=True)
def first_crossing(gold, gnew, ne):
    """True if any event component changed side: "side" is g < 0 versus g >= 0, so a restart
    exactly at a root (g = 0) counts as already on the non-negative side."""
    for i in range(ne):
        if (gold[i] < 0.0) != (gnew[i] < 0.0):
            return True
    return False

@njit(cache=True)
def start_events(event, t, y, p, ne, ev, stats):
    """Event buffers (g at the start, at the step end, scratch) and g(t, y) with the forced
    side of a just-located event applied; returns (status, gold, gnew, gtmp), status 0 or the
    event function's nonzero status (also stored in stats)."""
    gold = np.zeros(max(ne, 1))
    gnew = np.zeros(max(ne, 1))
    gtmp = np.zeros(max(ne, 1))
    st = 0
    if ne > 0:
        st = event(t, ptr(y), ptr(gold), ptr(p))
        if st != 0:
            stats[ST_RHS_STATUS] = st
        else:
            apply_forced_side(gold, ne, ev)
    return st, gold, gnew, gtmp

@njit(cache=True)
def apply_forced_side(gold, ne, ev):
    """Right after a located event the state sits within the bracket width of the root and may
    still evaluate on the old side; ev[2] >= 0 names that component and ev[3] its new-side value,
    used once for the start of the restarted integration (then cleared), so the same crossing is
    not found twice."""
    fc = int(ev[2])
    if fc >= 0 and fc < ne:
        gold[fc] = ev[3]
    ev[2] = -1.0


def event_time_tolerance(t, h):
    """Width of the bracket to which an event time is located (s): a few ulps of t, or of h."""
    return 64.0 * EPS * max(abs(t), abs(h))


event_time_tolerance = njit(cache=True)(event_time_tolerance)


# ----------------------------------------------------------------------------------------------
# the outcome of a run (driver, scipy backend, DROMO)
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class IntegrationResult:
    """Outcome of :func:`integrate`.

    ``t`` are the output times actually reached and ``y[k]`` the state at ``t[k]``; on failure
    they hold every output computed before it.  ``status`` is 0 on success, else the kernel code
    (1 max_steps, 2 step underflow / no convergence, 3 rhs failure, 4 non-finite values) and
    ``message`` says what happened and when.  ``t_end``/``y_end`` is the last accepted state.
    """

    t: np.ndarray
    y: np.ndarray
    status: int
    message: str
    t_end: float
    y_end: np.ndarray
    stats: dict = field(default_factory=dict)
    #: Located events, in time order: (t, component index, new side +1 (g >= 0) or -1 (g < 0)).
    events: tuple = ()
    #: Component of the terminal event that stopped the run (None if it ran to the end).
    stopped_by: int | None = None

    @property
    def success(self) -> bool:
        return self.status == OK


def status_message(status, t_end, h, rhs_status, n_newton_fail, max_steps):
    """Human-readable outcome of a run (shared with the scipy backend)."""
    if status == OK:
        return f"reached t={t_end!r}"
    if status == MAX_STEPS:
        return f"stopped after max_steps={max_steps} steps at t={t_end!r} (h={h:.3e})"
    if status == RHS_FAILED:
        return (f"the right-hand side returned status {rhs_status} at a trial state just after "
                f"t={t_end!r}, and reducing the step size did not help")  # fmt: skip
    if status == NON_FINITE:
        return (f"non-finite values (NaN or Inf) in the solution just after t={t_end!r} that "
                f"reducing the step size did not remove")  # fmt: skip
    if status == STEP_UNDERFLOW:
        extra = f" ({n_newton_fail} Newton failures)" if n_newton_fail else ""
        return (f"step size underflow or no convergence at t={t_end!r} (h={h:.3e}){extra}: "
                f"the problem may be singular there or too stiff for the method")  # fmt: skip
    return f"unknown status {status} at t={t_end!r}"
