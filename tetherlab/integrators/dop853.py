"""DOP853: explicit Runge-Kutta of order 8(5,3) with 7th-order dense output, compiled.

Reference: E. Hairer, S.P. Norsett, G. Wanner, "Solving Ordinary Differential Equations I",
2nd ed., Springer 1993, section II.10, and Hairer's Fortran code DOP853 (step-size controller,
error norm, HINIT, dense output CONTD8).  The coefficients come from :mod:`.tableau` (checked at
import).

The whole step loop, the calls of the right-hand side (a cfunc with :data:`tetherlab._jit.RHS_SIG`)
and the dense output are one compiled function: no Python runs between steps.

This module also holds the small helpers shared with :mod:`.radau5` (status codes, HINIT, output
at the start time), so both kernels behave the same at their boundaries.
"""

from __future__ import annotations

import numpy as np

from tetherlab._jit import njit, ptr, row_ptr

from .tableau import DOP_A, DOP_B, DOP_C, DOP_D, DOP_E3, DOP_E5

# Return codes of every kernel (see tetherlab.integrators.driver for their messages).
OK = 0
MAX_STEPS = 1
STEP_UNDERFLOW = 2
RHS_FAILED = 3
NON_FINITE = 4
EVENT = 5  # an event function changed sign in the step; see dop853_core / radau5_core

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

# Module-level copies as plain float64 arrays: numba freezes global arrays into the compiled code.
_A = DOP_A
_B = DOP_B
_C = DOP_C
_D = DOP_D
_E3 = DOP_E3
_E5 = DOP_E5


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
def _dop_stages(rhs, t, y, h, p, K, ys, stats):
    """Stages 1..11 into K[1..11] (K[0] = f(t, y) on entry).  Returns the first nonzero rhs
    status, or 0."""
    n = y.shape[0]
    for s in range(1, 12):
        for i in range(n):
            ys[i] = y[i]
        # j-outer loop: skips the many zero entries of A and runs contiguously over K[j].
        for j in range(s):
            a = _A[s, j] * h
            if a != 0.0:
                for i in range(n):
                    ys[i] += a * K[j, i]
        st = rhs(t + _C[s] * h, ptr(ys), row_ptr(K, s), ptr(p))
        stats[ST_NRHS] += 1
        if st != 0:
            return st
    return 0


@njit(cache=True)
def _dop_combine(y, K, h, y_new):
    """The 8th-order solution y + h sum_j b_j K[j] (b_12.. are zero)."""
    for i in range(y.shape[0]):
        acc = 0.0
        for j in range(12):
            acc += _B[j] * K[j, i]
        y_new[i] = y[i] + h * acc


@njit(cache=True)
def dop853_step(rhs, t, y, h, p, K, ys, y_new, stats):
    """One DOP853 step of size h from (t, y) into y_new, without error control: for a caller
    that lands exactly on a point inside a step the error control already accepted (so its error
    is within tolerance).  K (16, n) and ys (n,) are workspaces.  Returns the first nonzero rhs
    status, -1 for non-finite values, or 0."""
    st = rhs(t, ptr(y), row_ptr(K, 0), ptr(p))
    stats[ST_NRHS] += 1
    if st != 0:
        return st
    st = _dop_stages(rhs, t, y, h, p, K, ys, stats)
    if st != 0:
        return st
    _dop_combine(y, K, h, y_new)
    return 0 if all_finite(y_new) else -1


@njit(cache=True)
def _dop_error(y, y_new, K, h, rtol, atol):
    """Hairer's DOP853 error norm: the 5th-order estimate damped by the 3rd-order one,
    err = |h| * E5n^2 / sqrt(n (E5n^2 + 0.01 E3n^2)), with weights atol + rtol*max(|y|,|y_new|)."""
    n = y.shape[0]
    err5 = 0.0
    err3 = 0.0
    for i in range(n):
        sk = atol[i] + rtol * max(abs(y[i]), abs(y_new[i]))
        e5 = 0.0
        e3 = 0.0
        for j in range(12):
            e5 += _E5[j] * K[j, i]
            e3 += _E3[j] * K[j, i]
        err5 += scaled_sq(e5, sk)
        err3 += scaled_sq(e3, sk)
    if err5 == 0.0 and err3 == 0.0:
        return 0.0
    deno = err5 + 0.01 * err3
    return abs(h) * err5 / np.sqrt(n * deno)


@njit(cache=True)
def _dop_dense_stages(rhs, t, y, h, p, K, ys, stats):
    """The three extra stages K[13..15] of the 7th-order interpolant (K[12] = f(t+h, y_new))."""
    n = y.shape[0]
    for s in range(13, 16):
        for i in range(n):
            ys[i] = y[i]
        for j in range(s):
            a = _A[s, j] * h
            if a != 0.0:
                for i in range(n):
                    ys[i] += a * K[j, i]
        st = rhs(t + _C[s] * h, ptr(ys), row_ptr(K, s), ptr(p))
        stats[ST_NRHS] += 1
        if st != 0:
            return st
        if not all_finite(K[s]):
            return -1  # caller maps -1 to "non-finite"
    return 0


@njit(cache=True)
def _dop_dense_coeffs(y, y_new, K, h, F):
    """F[0..6] of Hairer's CONTD8 (scipy's Dop853DenseOutput uses the same layout)."""
    n = y.shape[0]
    for i in range(n):
        dy = y_new[i] - y[i]
        F[0, i] = dy
        F[1, i] = h * K[0, i] - dy
        F[2, i] = 2.0 * dy - h * (K[12, i] + K[0, i])
    for r in range(4):
        for i in range(n):
            acc = 0.0
            for j in range(16):
                acc += _D[r, j] * K[j, i]
            F[3 + r, i] = h * acc


@njit(cache=True)
def _dop_dense_eval(y, F, x, out):
    """y(t_old + x h) = y + x(F0 + (1-x)(F1 + x(F2 + (1-x)(F3 + x(F4 + (1-x)(F5 + x F6))))))."""
    x1 = 1.0 - x
    for i in range(y.shape[0]):
        v = F[6, i] * x
        v = (v + F[5, i]) * x1
        v = (v + F[4, i]) * x
        v = (v + F[3, i]) * x1
        v = (v + F[2, i]) * x
        v = (v + F[1, i]) * x1
        v = (v + F[0, i]) * x
        out[i] = y[i] + v


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


@njit(cache=True)
def dop853_run(rhs, t, y, t_out, p, rtol, atol, h, h_max, max_steps, y_out, stats, fixed_step):
    """The kernel ABI without events: :func:`dop853_core` with no event function."""
    ev = np.array([0.0, -1.0, -1.0, 0.0])
    return dop853_core(rhs, t, y, t_out, p, rtol, atol, h, h_max, max_steps, y_out, stats,
                       fixed_step, rhs, 0, ev)  # fmt: skip


@njit(cache=True)
def dop853_core(rhs, t, y, t_out, p, rtol, atol, h, h_max, max_steps, y_out, stats, fixed_step,
                event, ne, ev):  # fmt: skip
    """Integrate y' = rhs(t, y) from t to t_out[-1]; see the package docstring for the contract.

    Events: ``event(t, y_ptr, g_ptr, p_ptr)`` (the rhs ABI) writes ``ne`` values g; after each
    accepted step the kernel checks whether any changed side (g < 0 vs g >= 0).  If one did, the
    step is *not* committed: the earliest crossing is bracketed by bisection on the step's dense
    output to :func:`event_time_tolerance`, ``ev[0]`` gets the bracket's right end (where the
    component is already on its new side), ``ev[1]`` the component, ``ev[2:4]`` the component and
    its new-side value for the restart (:func:`apply_forced_side`), and the kernel returns EVENT
    with (t, y) still the state at the step's start.  The caller then integrates exactly to
    ev[0] (so a kink in the rhs at the event never lies inside a step) and restarts there.  Two
    crossings of one component inside a single step cancel and are not seen.

    Returns (status, t_end, h_next, n_done).  ``y`` is overwritten with the state at t_end; rows
    0..n_done-1 of ``y_out`` hold the solution at t_out[0..n_done-1].  ``max_steps`` counts
    accepted steps of this call; the call returns right after an accepted step, so a caller that
    continues from (t_end, y, h_next) reproduces a single long call bit for bit (the only state
    carried between DOP853 steps is h and f(t, y), which is recomputed identically).
    """
    n = y.shape[0]
    m = t_out.shape[0]
    n_done = fill_start_outputs(t, y, t_out, y_out)
    if n_done == m:
        return OK, t, h, n_done
    t_end = t_out[m - 1]

    K = np.empty((16, n))
    ys = np.empty(n)
    y_new = np.empty(n)
    F = np.empty((7, n))

    st = rhs(t, ptr(y), row_ptr(K, 0), ptr(p))
    stats[ST_NRHS] += 1
    if st != 0:
        stats[ST_RHS_STATUS] = st
        return RHS_FAILED, t, h, n_done
    if not all_finite(K[0]):
        return NON_FINITE, t, h, n_done
    st, gold, gnew, gtmp = start_events(event, t, y, p, ne, ev, stats)
    if st != 0:
        return RHS_FAILED, t, h, n_done

    hmax = h_max if h_max > 0.0 else np.inf
    if h <= 0.0:
        if fixed_step:
            return STEP_UNDERFLOW, t, h, n_done  # the driver rejects this before calling
        h = hinit(rhs, t, y, K[0], p, rtol, atol, 8, min(hmax, t_end - t), ys, y_new, stats)
    h = min(h, hmax)

    n_acc = 0
    n_rej = 0  # consecutive rejections of any kind
    n_bad = 0  # consecutive failures caused by the rhs (status or non-finite values)
    bad_kind = 0  # RHS_FAILED or NON_FINITE: cause of the most recent failed trial, 0 if none
    reject = False
    # Fixed steps: a relative slack so that N steps of T/N land on T without a sliver step.
    land = 1.0 + 1e-9 if fixed_step else 1.01

    while True:
        if h < UNDERFLOW_FACTOR * abs(t) or h < H_FLOOR or n_rej >= MAX_CONSECUTIVE_REJECTS:
            code = bad_kind if (n_rej > 0 and bad_kind != 0) else STEP_UNDERFLOW
            return code, t, h, n_done
        h_unclipped = h
        last = False
        if t + land * h >= t_end:
            h = t_end - t
            last = True

        fail = 0
        have_dense = False
        t_new = t_end if last else t + h
        st = _dop_stages(rhs, t, y, h, p, K, ys, stats)
        if st != 0:
            stats[ST_RHS_STATUS] = st
            fail = RHS_FAILED
        else:
            _dop_combine(y, K, h, y_new)
            if fixed_step:
                err = 0.0
                if not all_finite(y_new):
                    fail = NON_FINITE
            else:
                err = _dop_error(y, y_new, K, h, rtol, atol)
                if not np.isfinite(err):
                    fail = NON_FINITE
        if fail == 0 and err <= 1.0:
            # Every evaluation the step needs happens before it is committed, so a failure in
            # f(t+h, y_new) or in a dense-output stage rejects the step instead of leaving an
            # accepted state that cannot be continued.
            st = rhs(t + h, ptr(y_new), row_ptr(K, 12), ptr(p))
            stats[ST_NRHS] += 1
            if st != 0:
                stats[ST_RHS_STATUS] = st
                fail = RHS_FAILED
            elif not all_finite(K[12]):
                fail = NON_FINITE
            else:
                # Dense stages only on steps with an output time strictly inside (t, t_new).
                if n_done < m and t_out[n_done] < t_new:
                    have_dense = True
                    st = _dop_dense_stages(rhs, t, y, h, p, K, ys, stats)
                    if st == -1:
                        fail = NON_FINITE
                    elif st != 0:
                        stats[ST_RHS_STATUS] = st
                        fail = RHS_FAILED

        if fail != 0:
            if fixed_step:
                return fail, t, h, n_done
            stats[ST_REJECTED] += 1
            n_rej += 1
            n_bad += 1
            bad_kind = fail
            if n_bad >= MAX_BAD_TRIALS:
                return fail, t, h, n_done
            reject = True
            h = 0.25 * h
            continue

        if fixed_step:
            hnew = h_unclipped
        else:
            # Hairer's controller with beta = 0: fac limits 0.333 <= hnew/h <= 6, safety 0.9.
            fac11 = err**0.125
            fac = max(1.0 / 6.0, min(1.0 / 0.333, fac11 / 0.9))
            hnew = h / fac
            if err > 1.0:
                hnew = h / min(1.0 / 0.333, fac11 / 0.9)
                reject = True
                stats[ST_REJECTED] += 1
                n_rej += 1
                bad_kind = 0
                h = hnew
                continue

        # ---- events (before anything is committed) ----
        if ne > 0:
            st = event(t_new, ptr(y_new), ptr(gnew), ptr(p))
            if st != 0:
                stats[ST_RHS_STATUS] = st
                return RHS_FAILED, t, h, n_done
            if first_crossing(gold, gnew, ne):
                if not have_dense:
                    st = _dop_dense_stages(rhs, t, y, h, p, K, ys, stats)
                    if st != 0:
                        if st > 0:
                            stats[ST_RHS_STATUS] = st
                        return (RHS_FAILED if st > 0 else NON_FINITE), t, h, n_done
                _dop_dense_coeffs(y, y_new, K, h, F)
                tol = event_time_tolerance(t_new, h)
                best = 1.0
                comp = -1
                for i in range(ne):
                    if (gold[i] < 0.0) == (gnew[i] < 0.0):
                        continue
                    a = 0.0
                    b = 1.0
                    for _ in range(200):
                        if (b - a) * h <= tol:
                            break
                        mid = 0.5 * (a + b)
                        _dop_dense_eval(y, F, mid, ys)
                        st = event(t + mid * h, ptr(ys), ptr(gtmp), ptr(p))
                        if st != 0:
                            stats[ST_RHS_STATUS] = st
                            return RHS_FAILED, t, h, n_done
                        if (gtmp[i] < 0.0) == (gold[i] < 0.0):
                            a = mid
                        else:
                            b = mid
                    if comp < 0 or b < best:
                        best = b
                        comp = i
                ev[0] = t_new if best >= 1.0 else t + best * h
                ev[1] = comp
                ev[2] = comp
                ev[3] = 0.0 if gold[comp] < 0.0 else -1.0
                return EVENT, t, h_unclipped, n_done
            for i in range(ne):
                gold[i] = gnew[i]

        # ---- accept ----
        if n_done < m and t_out[n_done] < t_new:
            _dop_dense_coeffs(y, y_new, K, h, F)
            while n_done < m and t_out[n_done] < t_new:
                _dop_dense_eval(y, F, (t_out[n_done] - t) / h, y_out[n_done])
                n_done += 1
        # Output times equal to t_new get the step's own end value, not the interpolant.
        while n_done < m and t_out[n_done] <= t_new:
            y_out[n_done, :] = y_new
            n_done += 1
        t = t_new
        for i in range(n):
            y[i] = y_new[i]
            K[0, i] = K[12, i]
        stats[ST_ACCEPTED] += 1
        n_acc += 1
        n_rej = 0
        n_bad = 0
        bad_kind = 0

        hnew = min(hnew, hmax)
        if reject:
            hnew = min(hnew, h)
        reject = False
        if last:
            # The clipped last step says little about the natural step; hand back the larger.
            return OK, t, min(max(hnew, h_unclipped), hmax), n_done
        h = hnew
        if n_acc >= max_steps:
            return MAX_STEPS, t, h, n_done
