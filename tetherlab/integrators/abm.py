"""Adams-Bashforth-Moulton PECE with a (rarely changed) constant step, compiled.

For a problem whose solution is smooth on the scale of the step and whose best step hardly
changes -- the DROMO elements in the ideal anomaly sigma -- a k-step multistep method needs two
right-hand-side calls a step whatever its order, against 12 (DOP853) or 16 (Vern9) for a
Runge-Kutta step.  Derivation and choices: docs/integrators.md section "ABM".

One step from (t_n, y_n) with the history f_n, f_{n-1}, ..., f_{n-k+1} (f_j = f(t_j, y_j)):

    P:  y^P     = y_n + h sum_{j=0}^{k-1} AB_j f_{n-j}          Adams-Bashforth, k steps, order k
    E:  f^P     = f(t_n + h, y^P)
    C:  y_{n+1} = y_n + h (AM_0 f^P + sum_{j=1}^{k} AM_j f_{n+1-j})  Adams-Moulton, order k + 1
    E:  f_{n+1} = f(t_n + h, y_{n+1})

(Hairer, Norsett & Wanner, "Solving ODEs I", 2nd ed., section III.1, eqs. 1.5 and 1.8 in
ordinate form; PECE as in III.1 "Predictor-corrector methods".)  The corrector uses the same k
back values as the predictor plus f^P, so the step is of order k + 1 ("local extrapolation").
Local error estimate: the weighted RMS norm of y_{n+1} - y^P, which estimates the predictor's
error (order k): a conservative estimate of the step's error; the tolerance-to-error map is
measured on the work-precision axes, never assumed.

Step size: constant between restarts.  A step whose estimate exceeds 1 (tolerance units) is
rejected; the method restarts from y_n with h * (RESTART_TARGET / err)^(1/(k+1)).  Over each
window of ``window`` units of the independent variable (one revolution of sigma for DROMO) the
largest estimate is kept; if it leaves room for a step GROWTH_MIN times longer, the method
restarts with the longer step at the end of the window.  A restart costs k - 1 starting steps.

Starting procedure (:func:`abm_start`): k - 1 steps of length h with Vern9 (order 9), each split
into ``nsub`` substeps, give y_1 .. y_{k-1} and the history.  tests/test_abm.py checks that the
starting values are accurate to well below the step's own error.

Coefficients: computed at import in rational arithmetic (:func:`adams_coefficients`) from the
backward-difference recurrences (HNW III.1, eqs. 1.6 and 1.9), converted to ordinate form, and
checked exactly against the order conditions sum_j beta_j x_j^m = 1/(m+1) on the nodes
x_j = -j (AB) and 1 - j (AM): a TableauError at import if any fails.
"""

from __future__ import annotations

from fractions import Fraction
from math import comb

import numpy as np

from tetherlab._jit import njit, ptr, row_ptr

from .common import (
    NON_FINITE,
    OK,
    RHS_FAILED,
    MAX_BAD_TRIALS,
    STEP_UNDERFLOW,
    ST_ACCEPTED,
    ST_NRHS,
    ST_REJECTED,
    ST_RHS_STATUS,
    all_finite,
)
from .erk import K_ROWS, VERN9, erk_step
from .tableau import TableauError

#: Orders k of the Adams-Bashforth predictor available (the corrector is one order higher).
ORDERS = tuple(range(4, 17))
#: Default k for DROMO (docs/integrators.md, the ABM order study).
DEFAULT_ORDER = 12
#: Restart target, in units of the tolerance, for the largest step error after a change of step.
RESTART_TARGET = 0.5
#: A window whose largest error allows a step this much longer triggers a restart with it
#: (a restart costs k - 1 Vern9 starting steps: small gains are not worth it).
GROWTH_MIN = 1.15
#: Largest change of the step at one restart.
GROW_MAX = 3.0
SHRINK_MIN = 0.2
#: Stop status when the stop level (a component reaching a value) is crossed in a step.
LEVEL = 6
#: Stop status when the level was passed inside the last starting procedure (bracket in S).
LEVEL_START = 7
#: Vern9 substeps per starting interval.
START_SUBSTEPS = 2


def _gammas(k: int):
    """Backward-difference coefficients (HNW III.1): gamma*_m of Adams-Bashforth, from
    sum_{i=0}^{m} gamma*_i / (m + 1 - i) = 1, and gamma_m of Adams-Moulton, from
    sum_{i=0}^{m} gamma_i / (m + 1 - i) = 0 (m >= 1), gamma_0 = 1."""
    gs = [Fraction(1)]
    g = [Fraction(1)]
    for m in range(1, k + 1):
        gs.append(1 - sum(gs[i] / (m + 1 - i) for i in range(m)))
        g.append(-sum(g[i] / (m + 1 - i) for i in range(m)))
    return gs, g


def adams_coefficients(k: int):
    """(AB, AM) as Fractions: AB_j (j = 0..k-1) of the k-step Adams-Bashforth method and AM_j
    (j = 0..k) of the Adams-Moulton method of order k + 1, in ordinate form:
    AB_j = (-1)^j sum_{m=j}^{k-1} C(m, j) gamma*_m, AM_j = (-1)^j sum_{m=j}^{k} C(m, j) gamma_m
    (the backward differences nabla^m f_n = sum_j (-1)^j C(m, j) f_{n-j} expanded)."""
    gs, g = _gammas(k)
    ab = [(-1) ** j * sum(comb(m, j) * gs[m] for m in range(j, k)) for j in range(k)]
    am = [(-1) ** j * sum(comb(m, j) * g[m] for m in range(j, k + 1)) for j in range(k + 1)]
    return ab, am


def check_adams(k: int, ab, am) -> None:
    """Exact order conditions: the quadrature sum_j beta_j x_j^m over [0, 1] is exact for
    polynomials of degree m: = 1/(m + 1), m = 0..k-1 for AB (nodes x_j = -j), m = 0..k for AM
    (nodes 1 - j); and the next condition fails (the order is not higher)."""
    for name, beta, nodes, order in (("AB", ab, [-j for j in range(k)], k),
                                     ("AM", am, [1 - j for j in range(k + 1)], k + 1)):  # fmt: skip
        for m in range(order + 1):
            q = sum(b * Fraction(x) ** m for b, x in zip(beta, nodes))
            exact = q == Fraction(1, m + 1)
            if exact != (m < order):
                raise TableauError(f"Adams {name} k={k}: sum beta x^{m} = {q}, expected "
                                   f"{'' if m < order else 'not '}1/{m + 1} (order {order})")  # fmt: skip


def _build():
    kmax = max(ORDERS)
    AB = np.zeros((kmax + 1, kmax + 1))
    AM = np.zeros((kmax + 1, kmax + 1))
    for k in ORDERS:
        ab, am = adams_coefficients(k)
        check_adams(k, ab, am)
        AB[k, :k] = [float(x) for x in ab]
        AM[k, : k + 1] = [float(x) for x in am]
    return AB, AM


#: AB[k, :k], AM[k, :k+1]: the float64 coefficients of order k (rows of other k are zero).
AB_TABLE, AM_TABLE = _build()
KMAX = max(ORDERS)


def workspace(n: int) -> dict:
    """Arrays the kernels need for a state of length n (``fix``: the level-stop values and the
    step-size window, carried between calls)."""
    return {"F": np.zeros((KMAX, n)), "S": np.zeros((KMAX, n)), "K": np.empty((K_ROWS, n)),
            "w": np.empty((2, n)), "fix": np.zeros(6)}  # fmt: skip


@njit(cache=True)
def abm_start(rhs, t, y, h, k, F, S, p, K, w, nsub, stats):
    """Starting procedure: from (t, y), k - 1 Vern9 intervals of length h (``nsub`` substeps
    each) give y_1..y_{k-1}; F[j] = f(t + j h, y_j) and S[j] = y_j, j = 0..k-1 (the history slots
    in time order, so the ring head is k - 1; S keeps the starting states for a caller that must
    land on a point inside the starting span).  On return y holds y_{k-1}.  Returns a status."""
    n = y.shape[0]
    ys = w[0]
    ynew = w[1]
    for i in range(n):
        S[0, i] = y[i]
    st = rhs(t, ptr(y), row_ptr(F, 0), ptr(p))
    stats[ST_NRHS] += 1
    if st != 0:
        stats[ST_RHS_STATUS] = st
        return RHS_FAILED
    hs = h / nsub
    for j in range(1, k):
        t0 = t + (j - 1) * h
        for s in range(nsub):
            st = erk_step(VERN9, rhs, t0 + s * hs, y, hs, p, K, ys, ynew, stats)
            if st != 0:
                if st > 0:
                    stats[ST_RHS_STATUS] = st
                    return RHS_FAILED
                return NON_FINITE
            for i in range(n):
                y[i] = ynew[i]
        for i in range(n):
            S[j, i] = y[i]
        st = rhs(t + j * h, ptr(y), row_ptr(F, j), ptr(p))
        stats[ST_NRHS] += 1
        if st != 0:
            stats[ST_RHS_STATUS] = st
            return RHS_FAILED
    return OK


@njit(cache=True)
def _stop_value(event, use_event, t, y, comp, level, p, g):
    """The stop function, >= 0 once the stop is reached: ``event``'s first component g(t, y)
    (``use_event``; a cfunc with the rhs signature writing into g), else y[comp] - level."""
    if use_event:
        event(t, ptr(y), ptr(g), ptr(p))
        return g[0]
    return y[comp] - level


@njit(cache=True)
def abm_core(rhs, t, y, h, k, F, S, head, p, rtol, atol, t_stop, comp, level, window, max_steps,
             adapt, stats, K, w, fix, event, use_event):  # fmt: skip
    """Constant-step ABM PECE of order k from (t, y) with history F (ring head ``head``).

    ``head < 0``: no history yet; the starting procedure runs first, always to its end (so
    outputs never change the path), keeping its states in S.  Stops (history kept, so a later
    call resumes bit-for-bit):
    The stop (comp >= 0) is y[comp] >= ``level``, or with ``use_event`` g(t, y) >= 0 for the
    cfunc ``event`` (rhs signature, first component; a stop that is not one state component, e.g.
    DROMO's physical time through a time element):
    * status LEVEL_START when the stop holds already (passed inside the last starting
      procedure): the bracket is S[j-1], S[j] with j = fix[5] (at t_s + (j-1) h, t_s = fix[4]),
      fix[0] = S[j, comp] (with ``use_event``: g at S[j]);
    * status LEVEL when a step would reach the stop: y, t are the step's start, ``fix[0]`` =
      y[comp] after the step (with ``use_event``: g after it), fix[1] = f[comp] there;
      ``fix`` (float64[6]) also carries the step-size window between calls (fix[2:4]);
    * status OK when the next step would pass t_stop (the caller lands on it);
    * status 1 (MAX_STEPS) after ``max_steps`` accepted steps.
    With ``adapt`` the step changes as in the module docstring (restarts; a non-finite step is a
    rejection with h/4, up to MAX_BAD_TRIALS in a row); without, h is fixed.
    Returns (status, t, h, head)."""
    n = y.shape[0]
    ab = AB_TABLE[k]
    am = AM_TABLE[k]
    # separate allocations, not rows of one workspace: the compiler may then assume they do not
    # overlap, keep the sums in registers and vectorise them (rows of w halved the step's speed)
    yp = np.empty(n)
    yc = np.empty(n)
    pa = np.empty(n)
    ca = np.empty(n)
    fnew = np.empty(n)
    gbuf = np.empty(1)
    gv = -1.0
    a0 = am[0]
    expo = 1.0 / (k + 1)
    n_acc = 0
    n_bad = 0
    # the window (start, largest error) lives in fix[2:4], so a run split into calls (outputs,
    # chunks) takes the same steps as one call
    win_start = fix[2]
    win_max = fix[3]
    while True:
        if head < 0:
            if t + (k - 1) * h > t_stop:
                return OK, t, h, head  # the starting procedure would pass t_stop: the caller lands
            st = abm_start(rhs, t, y, h, k, F, S, p, K, w, START_SUBSTEPS, stats)
            if st != OK:
                return st, t, h, head
            fix[4] = t
            t = t + (k - 1) * h
            head = k - 1
            win_start = t
            win_max = 0.0
        if comp >= 0 and _stop_value(event, use_event, t, y, comp, level, p, gbuf) >= 0.0:
            # the level was passed inside the last starting procedure: the bracket S[j-1], S[j]
            j = 1
            gj = _stop_value(event, use_event, fix[4] + j * h, S[j], comp, level, p, gbuf)
            while j < k - 1 and gj < 0.0:
                j += 1
                gj = _stop_value(event, use_event, fix[4] + j * h, S[j], comp, level, p, gbuf)
            fix[0] = gj if use_event else S[j, comp]
            fix[5] = j
            fix[2] = win_start
            fix[3] = win_max
            return LEVEL_START, t, h, head
        if n_acc >= max_steps or t + h > t_stop:
            fix[2] = win_start
            fix[3] = win_max
            return (1 if n_acc >= max_steps else OK), t, h, head
        # ---- one PECE step (module docstring) into yc, f_{n+1} into fnew.  Written out here: as
        # a function (even IR-inlined) it ran at half this speed (docs/integrators.md section 8).
        # Both history sums in one pass before the first evaluation, from the oldest value to the
        # newest, one history row at a time: the n components are independent accumulators (no
        # chain through the k terms; the row loop vectorises), and f_n, which the previous step's
        # last evaluation produced, enters last, so the predictor waits for it by one multiply-add.
        # The corrector's old part (all but AM_0 f^P) is ready while f(y^P) is evaluated.
        for i in range(n):
            pa[i] = 0.0
            ca[i] = 0.0
        for j in range(k - 1, -1, -1):  # age j: f_{n-j} in slot head - j (mod k), oldest first
            slot = head - j
            if slot < 0:
                slot += k
            b = ab[j]
            c = am[j + 1]
            for i in range(n):
                f = F[slot, i]
                pa[i] += b * f
                ca[i] += c * f
        for i in range(n):
            yp[i] = y[i] + h * pa[i]
        st = rhs(t + h, ptr(yp), ptr(fnew), ptr(p))
        stats[ST_NRHS] += 1
        err = 0.0
        if st == 0:
            for i in range(n):
                v = y[i] + h * (ca[i] + a0 * fnew[i])
                yc[i] = v
                d = (v - yp[i]) / (atol[i] + rtol * max(abs(y[i]), abs(v)))
                err += d * d
            err = np.sqrt(err / n)  # weighted RMS of y_{n+1} - y^P (the predictor's error)
            st = rhs(t + h, ptr(yc), ptr(fnew), ptr(p))
            stats[ST_NRHS] += 1
        if st != 0:
            stats[ST_RHS_STATUS] = st
            st = RHS_FAILED
        elif not (err == err and all_finite(yc)):
            st = NON_FINITE
        # ---- end of the step
        if st != OK:
            fix[2] = win_start
            fix[3] = win_max
        if st == NON_FINITE and adapt and n_bad < MAX_BAD_TRIALS:
            # a blow-up (the step outside the method's small stability region): as a rejection
            n_bad += 1
            stats[ST_REJECTED] += 1
            h *= 0.25
            head = -1
            continue
        if st != OK:
            return st, t, h, head
        n_bad = 0
        if adapt and err > 1.0:
            stats[ST_REJECTED] += 1
            h = h * max(SHRINK_MIN, (RESTART_TARGET / err) ** expo)
            if abs(h) <= 16.0 * 2.220446049250313e-16 * abs(t):
                return STEP_UNDERFLOW, t, h, head
            head = -1  # restart from (t, y): y is still y_n
            continue
        # the stop test, written out: through _stop_value the loop took 577 against 528 ns a step
        # (DROMO Example 1 with the time element's clock event, in-process alternating runs)
        if comp >= 0:
            if use_event:
                event(t + h, ptr(yc), ptr(gbuf), ptr(p))
                gv = gbuf[0]
            else:
                gv = yc[comp] - level
        if comp >= 0 and gv >= 0.0:
            fix[0] = gv if use_event else yc[comp]
            fix[1] = fnew[comp]
            fix[2] = win_start
            fix[3] = win_max
            return LEVEL, t, h, head
        head += 1
        if head == k:
            head = 0
        for i in range(n):
            y[i] = yc[i]
            F[head, i] = fnew[i]
        t = t + h
        n_acc += 1
        stats[ST_ACCEPTED] += 1
        if err > win_max:
            win_max = err
        if adapt and t - win_start >= window:
            grow = GROW_MAX if win_max <= 0.0 else (RESTART_TARGET / win_max) ** expo
            if grow >= GROWTH_MIN:
                h = h * min(GROW_MAX, grow)
                head = -1
            win_start = t
            win_max = 0.0
