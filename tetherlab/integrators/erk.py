"""The step loop shared by the explicit Runge-Kutta methods DOP853 and Vern9, compiled.

One function, :func:`erk_core`, runs the whole integration (steps, rhs calls, outputs, events)
for either method; ``kind`` (:data:`DOP853` or :data:`VERN9`) selects the method's own pieces
(stages, solution and error norm, dense output) from :mod:`.dop853` and :mod:`.vern9`.  The
branch on ``kind`` is taken a few times per step and is perfectly predictable; one compiled loop
serves both methods, so their outputs, events, failure handling and continuation behave the same.

Controller (Hairer's, "Solving ODEs I", II.4 and the code DOP853): h_new = h / fac with
fac = clip(err^(1/q) / safety, 1/6, 1/0.333), q the order used for the step size (8 for DOP853,
whose error norm mixes its 5th- and 3rd-order estimates as Hairer's code does; 9 for Vern9), and
no increase right after a rejection.  Safety 0.9 for DOP853, 0.8 for Vern9 (:mod:`.vern9`).
"""

from __future__ import annotations

import numpy as np

from tetherlab._jit import njit, ptr, row_ptr

from . import vern9 as _v9
from .common import (
    EVENT,
    H_FLOOR,
    MAX_BAD_TRIALS,
    MAX_CONSECUTIVE_REJECTS,
    MAX_STEPS,
    NON_FINITE,
    OK,
    RHS_FAILED,
    ST_ACCEPTED,
    ST_NRHS,
    ST_REJECTED,
    ST_RHS_STATUS,
    STEP_UNDERFLOW,
    UNDERFLOW_FACTOR,
    all_finite,
    event_time_tolerance,
    fill_start_outputs,
    first_crossing,
    hinit,
    start_events,
)
from .dop853 import (
    _dop_combine,
    _dop_dense_coeffs,
    _dop_dense_eval,
    _dop_dense_stages,
    _dop_error,
    _dop_stages,
    dop853_step,
)

DOP853 = 0
VERN9 = 1
#: method name -> kind, for the callers that choose by name (the driver, DROMO's output clock)
KINDS = {"dop853": DOP853, "vern9": VERN9}
#: rows of a stage workspace K that serves either kind (erk_step callers)
K_ROWS = max(16, _v9.NK)


@njit(cache=True)
def _stages(kind, rhs, t, y, h, p, K, ys, stats):
    if kind == VERN9:
        return _v9.v9_stages(rhs, t, y, h, p, K, ys, 1, _v9.NS, stats)
    return _dop_stages(rhs, t, y, h, p, K, ys, stats)


@njit(cache=True)
def _solution(kind, y, K, h, y_new, rtol, atol, with_error):
    """y_new from the stages; returns the error norm (0.0 without error control)."""
    if kind == VERN9:
        return _v9.v9_solution(y, K, h, y_new, rtol, atol, with_error)
    _dop_combine(y, K, h, y_new)
    return _dop_error(y, y_new, K, h, rtol, atol) if with_error else 0.0


@njit(cache=True)
def _dense_stages(kind, rhs, t, y, h, p, K, ys, stats):
    if kind == VERN9:
        return _v9.v9_stages(rhs, t, y, h, p, K, ys, _v9.FSAL + 1, _v9.NK, stats)
    return _dop_dense_stages(rhs, t, y, h, p, K, ys, stats)


@njit(cache=True)
def _dense_prepare(kind, y, y_new, K, h, F):
    if kind == DOP853:
        _dop_dense_coeffs(y, y_new, K, h, F)


@njit(cache=True)
def _dense_eval(kind, y, K, F, h, x, out):
    if kind == VERN9:
        _v9.v9_dense_eval(y, K, h, x, out)
    else:
        _dop_dense_eval(y, F, x, out)


@njit(cache=True)
def erk_step(kind, rhs, t, y, h, p, K, ys, y_new, stats):
    """One step of the method without error control (K: (K_ROWS, n) workspace); see
    :func:`tetherlab.integrators.dop853.dop853_step`."""
    if kind == VERN9:
        return _v9.vern9_step(rhs, t, y, h, p, K, ys, y_new, stats)
    return dop853_step(rhs, t, y, h, p, K, ys, y_new, stats)


@njit(cache=True)
def dop853_run(rhs, t, y, t_out, p, rtol, atol, h, h_max, max_steps, y_out, stats, fixed_step):
    """The kernel ABI without events, DOP853: :func:`erk_core` with no event function."""
    ev = np.array([0.0, -1.0, -1.0, 0.0])
    return erk_core(DOP853, rhs, t, y, t_out, p, rtol, atol, h, h_max, max_steps, y_out, stats,
                    fixed_step, rhs, 0, ev)  # fmt: skip


@njit(cache=True)
def vern9_run(rhs, t, y, t_out, p, rtol, atol, h, h_max, max_steps, y_out, stats, fixed_step):
    """The kernel ABI without events, Vern9: :func:`erk_core` with no event function."""
    ev = np.array([0.0, -1.0, -1.0, 0.0])
    return erk_core(VERN9, rhs, t, y, t_out, p, rtol, atol, h, h_max, max_steps, y_out, stats,
                    fixed_step, rhs, 0, ev)  # fmt: skip


@njit(cache=True)
def erk_core(kind, rhs, t, y, t_out, p, rtol, atol, h, h_max, max_steps, y_out, stats, fixed_step,
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
    carried between steps is h and f(t, y), which is recomputed identically).
    """
    n = y.shape[0]
    m = t_out.shape[0]
    n_done = fill_start_outputs(t, y, t_out, y_out)
    if n_done == m:
        return OK, t, h, n_done
    t_end = t_out[m - 1]
    if kind == VERN9:
        fsal = _v9.FSAL
        expo = 1.0 / _v9.ORDER
        safe = _v9.SAFETY
        iord = _v9.ORDER
        nk = _v9.NK
    else:
        fsal = 12
        expo = 0.125
        safe = 0.9
        iord = 8
        nk = 16

    K = np.empty((nk, n))
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
        h = hinit(rhs, t, y, K[0], p, rtol, atol, iord, min(hmax, t_end - t), ys, y_new, stats)
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
        err = 0.0
        st = _stages(kind, rhs, t, y, h, p, K, ys, stats)
        if st != 0:
            stats[ST_RHS_STATUS] = st
            fail = RHS_FAILED
        else:
            err = _solution(kind, y, K, h, y_new, rtol, atol, not fixed_step)
            if fixed_step:
                if not all_finite(y_new):
                    fail = NON_FINITE
            elif not np.isfinite(err):
                fail = NON_FINITE
        if fail == 0 and err <= 1.0:
            # Every evaluation the step needs happens before it is committed, so a failure in
            # f(t+h, y_new) or in a dense-output stage rejects the step instead of leaving an
            # accepted state that cannot be continued.
            st = rhs(t + h, ptr(y_new), row_ptr(K, fsal), ptr(p))
            stats[ST_NRHS] += 1
            if st != 0:
                stats[ST_RHS_STATUS] = st
                fail = RHS_FAILED
            elif not all_finite(K[fsal]):
                fail = NON_FINITE
            else:
                # Dense stages only on steps with an output time strictly inside (t, t_new).
                if n_done < m and t_out[n_done] < t_new:
                    have_dense = True
                    st = _dense_stages(kind, rhs, t, y, h, p, K, ys, stats)
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
            # Hairer's controller with beta = 0: fac limits 0.333 <= hnew/h <= 6.
            fac11 = err**expo
            fac = max(1.0 / 6.0, min(1.0 / 0.333, fac11 / safe))
            hnew = h / fac
            if err > 1.0:
                hnew = h / min(1.0 / 0.333, fac11 / safe)
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
                    st = _dense_stages(kind, rhs, t, y, h, p, K, ys, stats)
                    if st != 0:
                        if st > 0:
                            stats[ST_RHS_STATUS] = st
                        return (RHS_FAILED if st > 0 else NON_FINITE), t, h, n_done
                _dense_prepare(kind, y, y_new, K, h, F)
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
                        _dense_eval(kind, y, K, F, h, mid, ys)
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
            _dense_prepare(kind, y, y_new, K, h, F)
            while n_done < m and t_out[n_done] < t_new:
                _dense_eval(kind, y, K, F, h, (t_out[n_done] - t) / h, y_out[n_done])
                n_done += 1
        # Output times equal to t_new get the step's own end value, not the interpolant.
        while n_done < m and t_out[n_done] <= t_new:
            y_out[n_done, :] = y_new
            n_done += 1
        t = t_new
        for i in range(n):
            y[i] = y_new[i]
            K[0, i] = K[fsal, i]
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
