"""RADAU5's step loop (Hairer's RADCOR): step size, Jacobian and factorisation, the simplified
Newton iteration, the error estimate (ESTRAD), events, acceptance with Gustafsson's predictive
controller, and the dense output (CONTR5)."""

from __future__ import annotations

import numpy as np

from tetherlab._jit import njit, ptr

from ..common import (
    EPS,
    EVENT,
    H_FLOOR,
    MAX_BAD_TRIALS,
    MAX_CONSECUTIVE_REJECTS,
    MAX_STEPS,
    NON_FINITE,
    OK,
    RHS_FAILED,
    ST_ACCEPTED,
    ST_NEWTON_FAIL,
    ST_NJAC,
    ST_NLU,
    ST_NRHS,
    ST_REJECTED,
    ST_RHS_STATUS,
    STEP_UNDERFLOW,
    UNDERFLOW_FACTOR,
    all_finite,
    event_time_tolerance,
    fill_start_outputs,
    first_crossing,
    start_events,
    hinit,
    scaled_sq,
)
from ..linear_solver import data_ptr
from .border import _border_factor, _border_jacobian
from .constants import (
    ALPH,
    BETA,
    C1,
    C1M1,
    C1MC2,
    C2,
    C2M1,
    DD1,
    DD2,
    DD3,
    MAX_SINGULAR,
    NIT,
    QUOT1,
    QUOT2,
    SAFE,
    T11,
    T12,
    T13,
    T21,
    T22,
    T23,
    T31,
    THET,
    TI11,
    TI12,
    TI13,
    TI21,
    TI22,
    TI23,
    TI31,
    TI32,
    TI33,
    U1,
    _F_ERRACC,
    _F_FACCON,
    _F_FLOOR,
    _F_HACC,
    _F_HLU,
    _F_HOLD,
    _F_JACEVERY,
    _F_NIT,
    _F_TBASE,
    _F_THETA,
    _F_THSTEP,
    _I_FIRST,
    _I_LU_VALID,
    _I_M1,
    _I_NACCPT,
    _I_NBORDER,
    _I_NEED_JAC,
    _I_NSING,
    _I_STARTED,
    _I_STRUCT,
)
from .controller import error_quotient, gustafsson_quotient, newton_rate_cap, newton_slow_factor
from .dense import _decompose, _jacobian
from .newton import _increment_noise, _lin
from .workspace import radau5_workspace


@njit(cache=True)
def _collocation(y_new, z1, z2, z3, cont):
    """The step's collocation polynomial in Hairer's CONTR5 form: y(t_new + s h) =
    cont0 + s (cont1 + (s - C2M1)(cont2 + (s - C1M1) cont3)), s in [-1, 0]."""
    for i in range(y_new.shape[0]):
        z1i = z1[i]
        z2i = z2[i]
        c1 = (z2i - z3[i]) / C2M1
        ak = (z1i - z2i) / C1MC2
        acont3 = (ak - z1i / C1) / C2
        c2 = (ak - c1) / C1M1
        cont[0, i] = y_new[i]
        cont[1, i] = c1
        cont[2, i] = c2
        cont[3, i] = c2 - acont3



@njit(cache=True)
def radau5_core(
    rhs,
    t,
    y,
    t_out,
    p,
    rtol,
    atol,
    h,
    h_max,
    max_steps,
    y_out,
    stats,
    fixed_step,
    dense,
    cont,
    f0,
    fs,
    is_,
    solver,
    border,
    form,
    factor_real,
    factor_complex,
    solve_real,
    solve_complex,
    resume,
    event,
    ne,
    ev,
):
    """RADAU5 with an explicit workspace (:func:`.workspace.radau5_workspace`: the arrays, then
    the Newton solver's five cfuncs of tetherlab/integrators/linear_solver.py); ``resume``
    continues from the state it holds.

    Events (``event``, ``ne``, ``ev``) as in :func:`tetherlab.integrators.erk.erk_core`,
    located on the step's collocation polynomial; an EVENT return leaves the workspace of the
    uncommitted step, so the caller restarts fresh (``resume=False``) after it.

    Same contract as :func:`radau5_run` otherwise.  ``max_steps`` counts accepted steps and the
    call returns right after an accepted step, with everything the next step needs in the
    workspace, so resumed calls reproduce one long call exactly.
    """
    n = y.shape[0]
    m = t_out.shape[0]
    n_done = fill_start_outputs(t, y, t_out, y_out)
    if n_done == m:
        return OK, t, h, n_done
    t_end = t_out[m - 1]
    m1 = is_[_I_M1]
    struct = is_[_I_STRUCT] != 0
    nb = is_[_I_NBORDER] if struct else 0
    fjac, e1, e2, ip1, ip2 = dense
    blk, sfac1, sfac2 = solver
    bcol, bz1, bz2, bs1, bs2, bp1, bp2, bw = border
    thstep = fs[_F_THSTEP]
    nit = int(fs[_F_NIT]) if fs[_F_NIT] > 0.0 else NIT
    jac_every = fs[_F_JACEVERY] > 0.0
    jac_mid = fs[_F_JACEVERY] > 1.0
    floor_gain = fs[_F_FLOOR]

    # Hairer's tolerance map (RADAU5 driver, EXPM = 2/3), and Newton's stopping tolerance FNEWT.
    rtol_i = 0.1 * rtol ** (2.0 / 3.0)
    atol_i = atol * (rtol_i / rtol)
    fnewt = max(10.0 * EPS / rtol_i, min(0.03, np.sqrt(rtol_i)))
    cfac = SAFE * (1 + 2 * nit)
    hmax = h_max if h_max > 0.0 else np.inf

    z1 = np.empty(n)
    z2 = np.empty(n)
    z3 = np.empty(n)
    f1 = np.empty(n)
    f2 = np.empty(n)
    f3 = np.empty(n)
    tmp = np.empty(n)
    scal = np.empty(n)
    wnoise = np.empty(n)
    w = np.empty(n, dtype=np.complex128)
    evc = np.zeros((4, n))
    st, gold, gnew, gtmp = start_events(event, t, y, p, ne, ev, stats)
    if st != 0:
        return RHS_FAILED, t, h, n_done

    if not (resume and is_[_I_STARTED] != 0):
        st = rhs(t, ptr(y), ptr(f0), ptr(p))
        stats[ST_NRHS] += 1
        if st != 0:
            stats[ST_RHS_STATUS] = st
            return RHS_FAILED, t, h, n_done
        if not all_finite(f0):
            return NON_FINITE, t, h, n_done
        if h <= 0.0:
            if fixed_step:
                return STEP_UNDERFLOW, t, h, n_done  # the driver rejects this before calling
            # HINIT with IORD = 4: the local error estimate of RADAU5 behaves like h^4.
            h = hinit(rhs, t, y, f0, p, rtol_i, atol_i, 4, min(hmax, t_end - t), z1, z2, stats)
        h = min(h, hmax)
        fs[_F_HOLD] = h
        fs[_F_THETA] = THET
        fs[_F_FACCON] = 1.0
        fs[_F_HACC] = h
        fs[_F_ERRACC] = 1e-2
        fs[_F_HLU] = 0.0
        is_[_I_FIRST] = 1
        is_[_I_NEED_JAC] = 1
        is_[_I_LU_VALID] = 0
        is_[_I_NACCPT] = 0
        is_[_I_NSING] = 0
        is_[_I_STARTED] = 1

    hold = fs[_F_HOLD]
    theta = fs[_F_THETA]
    faccon = fs[_F_FACCON]
    hacc = fs[_F_HACC]
    erracc = fs[_F_ERRACC]
    h_lu = fs[_F_HLU]
    first = is_[_I_FIRST] != 0
    need_jac = is_[_I_NEED_JAC] != 0
    lu_valid = is_[_I_LU_VALID] != 0
    naccpt = is_[_I_NACCPT]
    nsing = is_[_I_NSING]
    tb = fs[_F_TBASE]

    caljac = False  # the Jacobian in fjac was evaluated at the current (t, y)
    reject = False
    n_acc = 0
    n_rej = 0
    n_bad = 0
    bad_kind = 0
    land = 1.0 + 1e-9 if fixed_step else 1.01
    status = OK

    while True:
        # ------------------------------------------------ step size for this trial
        if h < UNDERFLOW_FACTOR * abs(t) or h < H_FLOOR or n_rej >= MAX_CONSECUTIVE_REJECTS:
            status = bad_kind if (n_rej > 0 and bad_kind != 0) else STEP_UNDERFLOW
            break
        h_unclipped = h
        last = False
        if t + land * h >= t_end:
            h = t_end - t
            last = True
        xph = t_end if last else t + h

        # ------------------------------------------------ Jacobian and LU (Hairer's 10 / 20)
        if need_jac:
            if struct:
                if jac_mid and not first:
                    # at the middle of the coming step, on the extrapolated collocation polynomial
                    cq = 0.5 * h / hold
                    for i in range(n):
                        tmp[i] = y[i] + cq * (cont[1, i] + (cq - C2M1) * (
                            cont[2, i] + (cq - C1M1) * cont[3, i]))  # fmt: skip
                    tb = t + 0.5 * h
                    st = form(tb, ptr(tmp), ptr(p), m1, data_ptr(blk))
                else:
                    tb = t
                    st = form(tb, ptr(y), ptr(p), m1, data_ptr(blk))
                    if nb > 0:
                        for i in range(n):
                            tmp[i] = y[i]
                stats[ST_NJAC] += 1
                if st != 0:
                    st = -1
                elif nb > 0:
                    # the border: f at the same base state and its nb columns (section 13)
                    st = _border_jacobian(rhs, tb, tmp, p, m1, nb, bcol, bw, stats)
                    if st != 0 and tb != t:
                        # the model failed at the extrapolated mid-step state: the border at
                        # (t, y) instead (an approximate matrix changes the rate, not the result)
                        tb = t
                        st = _border_jacobian(rhs, tb, y, p, m1, nb, bcol, bw, stats)
                    fs[_F_TBASE] = tb
            else:
                st = _jacobian(rhs, t, y, f0, p, fjac, tmp, stats)
            if st != 0:
                if st == -1:
                    status = NON_FINITE
                else:
                    stats[ST_RHS_STATUS] = st
                    status = RHS_FAILED
                break
            need_jac = False
            caljac = True
            lu_valid = False
        if not lu_valid or h != h_lu:
            if struct:
                stats[ST_NLU] += 1
                ier = factor_real(U1 / h, 0.0, ptr(p), data_ptr(blk), data_ptr(sfac1))
                if ier == 0:
                    ier = factor_complex(ALPH / h, BETA / h, ptr(p), data_ptr(blk), data_ptr(sfac2))
                if ier == 0 and nb > 0:
                    ier = _border_factor(rhs, tb, p, blk, m1, nb, U1 / h, sfac1, solve_real, bcol, bz1, bs1,
                                         bp1, bw, 0.0, stats)  # fmt: skip
                    if ier == 0:
                        ier = _border_factor(rhs, tb, p, blk, m1, nb, complex(ALPH / h, BETA / h), sfac2,
                                             solve_complex, bcol, bz2, bs2, bp2, bw, 1j, stats)  # fmt: skip
            else:
                ier = _decompose(fjac, h, e1, e2, ip1, ip2, stats, m1)
            if ier != 0:
                lu_valid = False
                nsing += 1
                if nsing >= MAX_SINGULAR or fixed_step:
                    status = STEP_UNDERFLOW
                    break
                # Hairer's label 78: halve h; the Jacobian is refreshed unless it is current.
                h = 0.5 * h
                reject = True
                stats[ST_REJECTED] += 1
                n_rej += 1
                bad_kind = 0
                need_jac = not caljac
                continue
            lu_valid = True
            h_lu = h
        fac1 = U1 / h
        alphn = ALPH / h
        betan = BETA / h
        fac2 = complex(alphn, betan)

        for i in range(n):
            scal[i] = atol_i[i] + rtol_i * abs(y[i])

        # ------------------------------------------------ starting values for Newton
        if first:
            for i in range(n):
                z1[i] = 0.0
                z2[i] = 0.0
                z3[i] = 0.0
                f1[i] = 0.0
                f2[i] = 0.0
                f3[i] = 0.0
        else:
            # Extrapolate the previous step's collocation polynomial (CONTR5 form).
            c3q = h / hold
            c1q = C1 * c3q
            c2q = C2 * c3q
            for i in range(n):
                ak1 = cont[1, i]
                ak2 = cont[2, i]
                ak3 = cont[3, i]
                z1i = c1q * (ak1 + (c1q - C2M1) * (ak2 + (c1q - C1M1) * ak3))
                z2i = c2q * (ak1 + (c2q - C2M1) * (ak2 + (c2q - C1M1) * ak3))
                z3i = c3q * (ak1 + (c3q - C2M1) * (ak2 + (c3q - C1M1) * ak3))
                z1[i] = z1i
                z2[i] = z2i
                z3[i] = z3i
                f1[i] = TI11 * z1i + TI12 * z2i + TI13 * z3i
                f2[i] = TI21 * z1i + TI22 * z2i + TI23 * z3i
                f3[i] = TI31 * z1i + TI32 * z2i + TI33 * z3i

        # ------------------------------------------------ simplified Newton iteration
        newt = 0
        faccon = max(faccon, EPS) ** 0.8
        theta = THET
        dynold = 0.0
        thqold = 0.0
        fail = 0  # 0 ok, RHS_FAILED / NON_FINITE, 10 = Newton failure, 11 = Newton too slow
        hhfac = 1.0
        noise = -1.0  # the Newton increments' round-off floor at this step (computed on demand)
        at_floor = False
        while True:
            if newt >= nit:
                fail = 10
                break
            # Stage values y + z_k -> f, written back into z_k.
            for i in range(n):
                tmp[i] = y[i] + z1[i]
            st = rhs(t + C1 * h, ptr(tmp), ptr(z1), ptr(p))
            if st == 0:
                for i in range(n):
                    tmp[i] = y[i] + z2[i]
                st = rhs(t + C2 * h, ptr(tmp), ptr(z2), ptr(p))
                if st == 0:
                    for i in range(n):
                        tmp[i] = y[i] + z3[i]
                    st = rhs(xph, ptr(tmp), ptr(z3), ptr(p))
                    stats[ST_NRHS] += 3
                else:
                    stats[ST_NRHS] += 2
            else:
                stats[ST_NRHS] += 1
            if st != 0:
                stats[ST_RHS_STATUS] = st
                fail = RHS_FAILED
                break
            # Right-hand sides of the transformed systems, then the two solves (SLVRAD).
            for i in range(n):
                a1 = z1[i]
                a2 = z2[i]
                a3 = z3[i]
                s2 = -f2[i]
                s3 = -f3[i]
                z1[i] = -f1[i] * fac1 + TI11 * a1 + TI12 * a2 + TI13 * a3
                z2[i] = s2 * alphn - s3 * betan + TI21 * a1 + TI22 * a2 + TI23 * a3
                z3[i] = s3 * alphn + s2 * betan + TI31 * a1 + TI32 * a2 + TI33 * a3
            _lin(struct, e1, ip1, fjac, fac1, m1, z1, p, blk, sfac1, solve_real, rhs, nb, bz1, bs1, bp1, bw, tb, 0.0, stats)
            for i in range(n):
                w[i] = complex(z2[i], z3[i])
            _lin(struct, e2, ip2, fjac, fac2, m1, w, p, blk, sfac2, solve_complex, rhs, nb, bz2, bs2, bp2, bw, tb, 1j, stats)
            for i in range(n):
                z2[i] = w[i].real
                z3[i] = w[i].imag
            newt += 1
            dyno = 0.0
            for i in range(n):
                dyno += scaled_sq(z1[i], scal[i]) + scaled_sq(z2[i], scal[i])
                dyno += scaled_sq(z3[i], scal[i])
            dyno = np.sqrt(dyno / (3 * n))
            if not np.isfinite(dyno):
                fail = NON_FINITE
                break
            # Convergence rate; bad convergence or a predicted miss of nit.
            if newt > 1 and newt < nit:
                thq = dyno / dynold
                if newt == 2:
                    theta = thq
                else:
                    theta = np.sqrt(thq * thqold)
                thqold = thq
                stalled = False
                if theta < 0.99:
                    faccon = theta / (1.0 - theta)
                    dyth = faccon * dyno * theta ** (nit - 1 - newt) / fnewt
                    if dyth >= 1.0 and not fixed_step:
                        hhfac = newton_slow_factor(dyth, nit, newt)
                        stalled = True
                        fail = 11
                else:
                    stalled = True
                    fail = 10
                if stalled:
                    # Increments that stopped shrinking may have reached the round-off of the
                    # stage values themselves, which no smaller step lowers (docs/integrators.md
                    # section 12): then the iterate is as converged as double precision allows.
                    if floor_gain > 0.0:
                        if noise < 0.0:
                            noise = _increment_noise(rhs, t, y, f0, p, scal, tmp, wnoise, struct, e1,
                                                     ip1, fjac, fac1, m1, blk, sfac1, solve_real, nb, bz1,
                                                     bs1, bp1,
                                                     bw, tb, stats)  # fmt: skip
                        if dyno <= floor_gain * noise:
                            fail = 0
                            at_floor = True
                    if not at_floor:
                        break
            dynold = max(dyno, EPS)
            for i in range(n):
                f1i = f1[i] + z1[i]
                f2i = f2[i] + z2[i]
                f3i = f3[i] + z3[i]
                f1[i] = f1i
                f2[i] = f2i
                f3[i] = f3i
                z1[i] = T11 * f1i + T12 * f2i + T13 * f3i
                z2[i] = T21 * f1i + T22 * f2i + T23 * f3i
                z3[i] = T31 * f1i + f2i
            if faccon * dyno <= fnewt or at_floor:
                break

        if fail != 0:
            if fixed_step:
                status = STEP_UNDERFLOW if fail >= 10 else fail
                if fail >= 10:
                    stats[ST_NEWTON_FAIL] += 1
                break
            stats[ST_REJECTED] += 1
            n_rej += 1
            reject = True
            if fail >= 10:
                stats[ST_NEWTON_FAIL] += 1
                bad_kind = 0
                h = h * (hhfac if fail == 11 else 0.5)
            else:
                n_bad += 1
                bad_kind = fail
                if n_bad >= MAX_BAD_TRIALS:
                    status = fail
                    break
                h = 0.25 * h
            need_jac = not caljac
            continue

        # ------------------------------------------------ error estimate (ESTRAD)
        err = 0.0
        quot = 1.0
        if not fixed_step:
            hee1 = DD1 / h
            hee2 = DD2 / h
            hee3 = DD3 / h
            for i in range(n):
                f2[i] = hee1 * z1[i] + hee2 * z2[i] + hee3 * z3[i]
                tmp[i] = f2[i] + f0[i]
                # Weights for the error test use max(|y|, |y_new|), as the DOP853 kernel and
                # scipy do; f3 is free here and holds them.
                f3[i] = atol_i[i] + rtol_i * max(abs(y[i]), abs(y[i] + z3[i]))
            _lin(struct, e1, ip1, fjac, fac1, m1, tmp, p, blk, sfac1, solve_real, rhs, nb, bz1, bs1, bp1, bw, tb, 0.0, stats)
            for i in range(n):
                err += scaled_sq(tmp[i], f3[i])
            err = max(np.sqrt(err / n), 1e-10)
            if err >= 1.0 and (first or reject):
                # Filter the estimate once more with the real system: without this, the
                # estimate is unbounded for very stiff components (Hairer & Wanner IV.8).
                for i in range(n):
                    tmp[i] = y[i] + tmp[i]
                st = rhs(t, ptr(tmp), ptr(f1), ptr(p))
                stats[ST_NRHS] += 1
                if st == 0 and all_finite(f1):
                    for i in range(n):
                        tmp[i] = f1[i] + f2[i]
                    _lin(struct, e1, ip1, fjac, fac1, m1, tmp, p, blk, sfac1, solve_real, rhs, nb, bz1, bs1, bp1, bw, tb, 0.0, stats)
                    err = 0.0
                    for i in range(n):
                        err += scaled_sq(tmp[i], f3[i])
                    err = max(np.sqrt(err / n), 1e-10)
                # (If that probe fails, the unfiltered estimate stands: it is >= 1, so the
                # step is rejected either way.)
            if not np.isfinite(err):
                stats[ST_REJECTED] += 1
                n_rej += 1
                n_bad += 1
                bad_kind = NON_FINITE
                reject = True
                if n_bad >= MAX_BAD_TRIALS:
                    status = NON_FINITE
                    break
                h = 0.25 * h
                need_jac = not caljac
                continue
            quot = error_quotient(err, newt, nit, cfac)
        hnew = h / quot

        if err < 1.0:
            # f at the new point before committing (it is the next step's f0 and Jacobian base):
            # if the model fails there the step is rejected, not half-accepted.
            for i in range(n):
                tmp[i] = y[i] + z3[i]
            st = rhs(xph, ptr(tmp), ptr(f1), ptr(p))
            stats[ST_NRHS] += 1
            fail = 0
            if st != 0:
                stats[ST_RHS_STATUS] = st
                fail = RHS_FAILED
            elif not (all_finite(f1) and all_finite(tmp)):
                fail = NON_FINITE
            if fail != 0:
                if fixed_step:
                    status = fail
                    break
                stats[ST_REJECTED] += 1
                n_rej += 1
                n_bad += 1
                bad_kind = fail
                reject = True
                if n_bad >= MAX_BAD_TRIALS:
                    status = fail
                    break
                h = 0.25 * h
                need_jac = not caljac
                continue

            # ---------------------------------------------- events (nothing committed yet)
            if ne > 0:
                st = event(xph, ptr(tmp), ptr(gnew), ptr(p))
                if st != 0:
                    stats[ST_RHS_STATUS] = st
                    status = RHS_FAILED
                    break
                if first_crossing(gold, gnew, ne):
                    _collocation(tmp, z1, z2, z3, evc)  # this step's polynomial, s in [-1, 0]
                    tol = event_time_tolerance(xph, h)
                    best = 0.0
                    comp = -1
                    for k in range(ne):
                        if (gold[k] < 0.0) == (gnew[k] < 0.0):
                            continue
                        a = -1.0
                        b = 0.0
                        for _ in range(200):
                            if (b - a) * h <= tol:
                                break
                            sm = 0.5 * (a + b)
                            for i in range(n):
                                f2[i] = evc[0, i] + sm * (
                                    evc[1, i] + (sm - C2M1) * (evc[2, i] + (sm - C1M1) * evc[3, i])
                                )
                            st = event(xph + sm * h, ptr(f2), ptr(gtmp), ptr(p))
                            if st != 0:
                                break
                            if (gtmp[k] < 0.0) == (gold[k] < 0.0):
                                a = sm
                            else:
                                b = sm
                        if st != 0:
                            break
                        if comp < 0 or b < best:
                            best = b
                            comp = k
                    if st != 0:
                        stats[ST_RHS_STATUS] = st
                        status = RHS_FAILED
                        break
                    ev[0] = xph if best >= 0.0 else xph + best * h
                    ev[1] = comp
                    ev[2] = comp
                    ev[3] = 0.0 if gold[comp] < 0.0 else -1.0
                    h = h_unclipped
                    status = EVENT
                    break
                for k in range(ne):
                    gold[k] = gnew[k]

            # ---------------------------------------------- accept
            fresh_jac = caljac
            first = False
            naccpt += 1
            if not fixed_step:
                # Predictive controller of Gustafsson (RADAU5, PRED = true).
                if naccpt > 1:
                    quot = gustafsson_quotient(quot, h, hacc, err, erracc)
                    hnew = h / quot
                hacc = h
                erracc = max(1e-2, err)
                if newt >= 2 and fresh_jac and thstep > 0.0 and not at_floor:
                    # Newton-rate cap (THETA_STEP): a fresh Jacobian's rate grows like h^2 here
                    # (not after an iteration stopped at its round-off floor: its rate is noise)
                    hnew = newton_rate_cap(hnew, h, thstep, theta)
            hold = h
            t = xph
            for i in range(n):
                y[i] = tmp[i]
                f0[i] = f1[i]
            _collocation(y, z1, z2, z3, cont)
            # Outputs inside the step from the collocation polynomial, s = (t_o - t)/h in [-1, 0).
            while n_done < m and t_out[n_done] < t:
                s = (t_out[n_done] - t) / hold
                row = y_out[n_done]
                for i in range(n):
                    row[i] = cont[0, i] + s * (
                        cont[1, i] + (s - C2M1) * (cont[2, i] + (s - C1M1) * cont[3, i])
                    )
                n_done += 1
            while n_done < m and t_out[n_done] <= t:
                y_out[n_done, :] = y
                n_done += 1
            stats[ST_ACCEPTED] += 1
            n_acc += 1
            n_rej = 0
            n_bad = 0
            bad_kind = 0
            nsing = 0
            caljac = False

            hnew = min(hnew, hmax)
            if fixed_step:
                hnew = h_unclipped
            hopt = hnew
            if reject:
                hnew = min(hnew, h)
            reject = False
            need_jac = theta > THET or jac_every
            if last:
                h = min(max(hopt, h_unclipped), hmax)
                status = OK
                break
            qt = hnew / h
            if not (theta <= THET and qt >= QUOT1 and qt <= QUOT2):
                h = hnew  # else keep h: the LU factors stay valid (Hairer's label 30)
            if n_acc >= max_steps:
                status = MAX_STEPS
                break
        else:
            # ---------------------------------------------- reject (error test)
            reject = True
            if first:
                h = 0.1 * h
            else:
                h = hnew
            stats[ST_REJECTED] += 1
            n_rej += 1
            bad_kind = 0
            # Hairer refreshes the Jacobian here (need_jac = not caljac).  An error-test rejection
            # says the step was too long, not that J is stale: the Newton iteration converged with
            # it.  Keeping J (the LU is redone for the new h) saves n rhs calls per rejection (14 %
            # of all calls on bench-libration); a stale J still shows as a slow Newton rate
            # (theta > THET), which refreshes it after the next step, or as a Newton failure.
            need_jac = False

    fs[_F_HOLD] = hold
    fs[_F_THETA] = theta
    fs[_F_FACCON] = faccon
    fs[_F_HACC] = hacc
    fs[_F_ERRACC] = erracc
    fs[_F_HLU] = h_lu
    is_[_I_FIRST] = 1 if first else 0
    is_[_I_NEED_JAC] = 1 if need_jac else 0
    is_[_I_LU_VALID] = 1 if lu_valid else 0
    is_[_I_NACCPT] = naccpt
    is_[_I_NSING] = nsing
    return status, t, h, n_done


def radau5_run(rhs, t, y, t_out, p, rtol, atol, h, h_max, max_steps, y_out, stats, fixed_step):
    """Kernel ABI entry: RADAU5 from a fresh start (new Jacobian, zero Newton predictor), with the
    dense Newton matrix and no second-order structure.

    A caller continuing from (t_end, y, h_next) gets a valid but not bit-identical continuation,
    because the Jacobian, LU factors and Newton predictor are rebuilt; use :func:`radau5_core`
    with a workspace (as the driver does) for exact continuation.  (A Python function: compiled
    code cannot build the workspace, whose Newton cfuncs are Python objects; the step loop it
    calls is compiled.)
    """
    return radau5_core(rhs, t, y, t_out, p, rtol, atol, h, h_max, max_steps, y_out, stats, fixed_step,
                       *radau5_workspace(y.shape[0]), False, rhs, 0, np.array([0.0, -1.0, -1.0, 0.0]))  # fmt: skip
