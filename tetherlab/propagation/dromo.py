"""Integration drivers of the DROMO formulation (:mod:`tetherlab.formulations.dromo`).

The formulation module holds the equations and conversions; this module runs them:

* :func:`integrate_time` -- the time form (any scene, events included: the scene's event
  components are evaluated on the rebuilt Cowell state, :func:`formulations.dromo.dromo_time_events`)
  through the generic driver :func:`tetherlab.integrators.driver.integrate`;
* :func:`integrate_sigma` -- the sigma form for a point mass, reported at physical times.

Output at physical times with the sigma form: with DOP853 or Vern9, inside the compiled loop
(:func:`_clock_run`): an event tau = t_k/T located on the dense output, then one step of the same
method from the crossing step's start to the located sigma; with the Adams-Bashforth-Moulton
method ("abm", :mod:`tetherlab.integrators.abm`) the constant-step loop stops before the step in
which tau passes t_k/T and a Vern9 step, its length found by Newton on tau, lands on it
(:func:`_abm_clock_run`; an output passed inside a restart's Vern9 starting steps is landed
from the starting state before it); with the other methods (RADAU5, scipy), sigma is integrated on a coarse
grid (8 points a revolution) and t(sigma) = t_k is solved by a safeguarded Newton iteration whose
evaluations are short integrations from the bracketing grid state (dt/dsigma = T/(q3^3 s^2) is
the Newton derivative).  docs/dromo.md section 5 says why.
"""

from __future__ import annotations

import math

import numpy as np
from numba import carray

from .._jit import njit, rhs_cfunc
from ..formulations.dromo import (
    FP_CLOCK,
    FP_TIME,
    TIME_LINEAR,
    TWO_PI,
    cowell_state,
    dromo_sigma_rhs,
    dromo_time_events,
    dromo_time_rhs,
    dromo_to_cartesian,
    dt_dsigma,
    physical_tau,
    predicted_sigma,
    sigma_state,
    time_state,
    units,
)
from ..integrators import abm as _abm
from ..integrators.common import EVENT as EVENT_STATUS
from ..integrators.common import MAX_STEPS as MAX_STEPS_STATUS
from ..integrators.common import NON_FINITE as NON_FINITE_STATUS
from ..integrators.common import OK as OK_STATUS
from ..integrators.common import RHS_FAILED as RHS_FAILED_STATUS
from ..integrators.common import ST_ACCEPTED, ST_RHS_STATUS
from ..integrators.erk import K_ROWS as ERK_K_ROWS
from ..integrators.erk import KINDS as ERK_KINDS
from ..integrators.erk import VERN9, erk_core, erk_step
from ..kernel.layout import H_LEN, H_OFF_FORM

#: Sigma-form methods whose output times are found in a compiled loop.
ABM_METHOD = "abm"
#: The ABM order used by the sigma form (k of the AB predictor; docs/integrators.md, ABM).
ABM_ORDER = _abm.DEFAULT_ORDER
#: ABM's first step: 64 a revolution of sigma (the restarts then size it from the tolerance).
ABM_FIRST_STEPS_PER_REV = 64

#: Grid points per revolution of sigma in the sigma form's first pass.  Each grid point inside a
#: step costs DOP853 three extra stages (dense output), so few points keep the overhead small
#: (8 a revolution: ~4 % at 50 steps a revolution); the bracket width does not limit accuracy.
GRID_PER_REV = 8

@rhs_cfunc
def dromo_clock_event(sigma, y_ptr, g_ptr, p_ptr):
    """Event g = tau - tau_k (tau_k at p[off + FP_CLOCK]): the sigma at which the physical time
    reaches an output time (the sigma form's outputs, :func:`integrate_sigma`); tau from the
    state's component 0, itself or through the linear time element (p[off + FP_TIME])."""
    p = carray(p_ptr, (int(p_ptr[H_LEN]),))
    g = carray(g_ptr, (1,))
    y = carray(y_ptr, (8,))
    off = int(p[H_OFF_FORM])
    tk = p[off + FP_CLOCK]
    if p[off + FP_TIME] == TIME_LINEAR:
        # tau = tau_l - Phi/n with |Phi| < pi + 1 (|2 atan2(kappa, s + w)| < pi as s + w > 0, and
        # |w kappa/s| = |e sin E| <= 1): while tau_l + (pi + 1)/n < tau_k the time is surely
        # short of the output, and that bound (negative) is returned without the trigonometry
        # and the atan2 of the exact value.  It is exact wherever |g| < (pi + 1 - |Phi|)/n, so
        # near every root; the ABM loop tests the event after every step (docs/dromo.md 11).
        q1 = y[1]
        q2 = y[2]
        q3 = y[3]
        w = math.sqrt(1.0 - q1 * q1 - q2 * q2)
        n = q3 * q3 * q3 * w * w * w
        lead = (tk - y[0]) * n - (math.pi + 1.0)  # > 0: tau_l + (pi + 1)/n < tau_k
        if lead > 0.0:
            g[0] = -lead / n
            return 0
    g[0] = physical_tau(sigma, y, int(p[off + FP_TIME])) - tk
    return 0


@njit(cache=True)
def _clock_run(kind, rhs, event, sig, z, h, targets, k, p, rtol, atol, sig_max, max_steps, out_sig,
               out_z, stats):  # fmt: skip
    """Sigma-form outputs k, k+1, ... at the non-dimensional times ``targets`` (compiled loop).

    The explicit method ``kind`` (DOP853 or Vern9, :mod:`tetherlab.integrators.erk`) runs with
    the event g = tau - targets[k]; at a crossing it returns with (sig, z) at the start of the
    crossing step and the located sigma in ev[0].  One step of the same method from there to
    ev[0] gives output k; the target moves on and the integration restarts from the same step
    start (redoing that step), so outputs do not move the path (a restart only forgets the
    controller's last rejection, which caps the next step).  Returns (status, sig, h, k,
    sig_max); status MAX_STEPS after ``max_steps`` accepted steps (the caller continues).
    """
    n = z.shape[0]
    off = int(p[H_OFF_FORM])
    mode = int(p[off + FP_TIME])
    m = targets.shape[0]
    ev = np.zeros(4)
    tout = np.empty(1)
    yout = np.empty((1, n))
    K = np.empty((ERK_K_ROWS, n))
    ys = np.empty(n)
    znew = np.empty(n)
    acc0 = stats[ST_ACCEPTED]
    while k < m:
        if targets[k] <= physical_tau(sig, z, mode):  # an output at the start time
            out_sig[k] = sig
            out_z[k, :] = z
            k += 1
            continue
        p[off + FP_CLOCK] = targets[k]
        left = max_steps - (stats[ST_ACCEPTED] - acc0)
        if left <= 0:
            return MAX_STEPS_STATUS, sig, h, k, sig_max
        tout[0] = sig_max
        # no forced side on (re)start: the target is new, so g < 0 there is a fresh fact
        ev[0] = 0.0
        ev[1] = -1.0
        ev[2] = -1.0
        ev[3] = 0.0
        st, sig, h, nd = erk_core(kind, rhs, sig, z, tout, p, rtol, atol, h, 0.0, left, yout, stats,
                                  False, event, 1, ev)  # fmt: skip
        if st == EVENT_STATUS:
            st2 = erk_step(kind, rhs, sig, z, ev[0] - sig, p, K, ys, znew, stats)
            if st2 != 0:
                if st2 > 0:
                    stats[ST_RHS_STATUS] = st2
                    return RHS_FAILED_STATUS, sig, h, k, sig_max
                return NON_FINITE_STATUS, sig, h, k, sig_max
            out_sig[k] = ev[0]
            out_z[k, :] = znew
            k += 1
        elif st == OK_STATUS:
            sig_max += TWO_PI  # the Kepler prediction of the output sigma was short
        else:
            return st, sig, h, k, sig_max
    return OK_STATUS, sig, h, k, sig_max


#: Newton iterations of the ABM landing step (each one Vern9 step); converges in 2-3.
ABM_LANDING_ITERS = 8


@njit(cache=True)
def _abm_clock_run(rhs, event, order, sig, z, h, F, S, head, targets, k, p, rtol, atol, max_steps,
                   out_sig, out_z, stats, K, w, fix):  # fmt: skip
    """Sigma-form outputs k, k+1, ... with the constant-step ABM method (compiled loop).

    :func:`tetherlab.integrators.abm.abm_core` runs until the step in which the clock ``event``
    g = tau - targets[k] (:func:`dromo_clock_event`, passed as an argument so that this loop is
    cached; tau from the state, itself or through the linear time element) would become >= 0
    (status LEVEL: land from the step's start (sig, z)), or
    reports that it was passed inside its last starting procedure (LEVEL_START: land from the
    starting state before it, kept in S).  A Vern9 step of length d lands on it, d by Newton on
    tau(sig + d) = targets[k] with dtau/dsigma = 1/(q3^3 s^2) (sheet s5).  The ABM run then
    resumes with its history: outputs do not move the path.  The time residual left after the
    last Newton step is the caller's (Kepler drift, as with :func:`_clock_run`).  Returns
    (status, sig, h, head, k)."""
    n = z.shape[0]
    m = targets.shape[0]
    off = int(p[H_OFF_FORM])
    mode = int(p[off + FP_TIME])
    ys = np.empty(n)
    zn = np.empty(n)
    z0 = np.empty(n)
    acc0 = stats[ST_ACCEPTED]
    while k < m:
        tk = targets[k]
        p[off + FP_CLOCK] = tk
        if head < 0 and tk <= physical_tau(sig, z, mode):  # an output at the start state
            out_sig[k] = sig
            out_z[k, :] = z
            k += 1
            continue
        left = max_steps - (stats[ST_ACCEPTED] - acc0)
        if left <= 0:
            return MAX_STEPS_STATUS, sig, h, head, k
        st, sig, h, head = _abm.abm_core(rhs, sig, z, h, order, F, S, head, p, rtol, atol, 1e300,
                                         0, 0.0, TWO_PI, left, True, stats, K, w, fix,
                                         event, True)  # fmt: skip
        if st == _abm.LEVEL:
            s0 = sig
            for i in range(n):
                z0[i] = z[i]
        elif st == _abm.LEVEL_START:
            j = int(fix[5])
            s0 = fix[4] + (j - 1) * h
            for i in range(n):
                z0[i] = S[j - 1, i]
        else:
            return st, sig, h, head, k
        # fix[0]: g after the bracket; g0 before it (< 0): the secant guess of the landing step
        g0 = physical_tau(s0, z0, mode) - tk
        d = h * (-g0) / (fix[0] - g0)
        d_used = d
        for _ in range(ABM_LANDING_ITERS):
            d_used = d
            st2 = erk_step(VERN9, rhs, s0, z0, d, p, K, ys, zn, stats)
            if st2 != 0:
                if st2 > 0:
                    stats[ST_RHS_STATUS] = st2
                    return RHS_FAILED_STATUS, sig, h, head, k
                return NON_FINITE_STATUS, sig, h, head, k
            g = physical_tau(s0 + d, zn, mode) - tk
            c = math.cos(s0 + d)
            sn = math.sin(s0 + d)
            s = 1.0 + zn[1] * c + zn[2] * sn
            dd = g * zn[3] * zn[3] * zn[3] * s * s
            if abs(dd) <= 4e-16 * max(1.0, abs(s0)):
                break
            d -= dd
        out_sig[k] = s0 + d_used
        out_z[k, :] = zn
        k += 1
    return OK_STATUS, sig, h, head, k


# ------------------------------------------------------------------------------------------------
# integration
# ------------------------------------------------------------------------------------------------
def _time_mode(p_ext) -> int:
    """The sigma form's time variable set by :func:`formulations.dromo.attach` (FP_TIME)."""
    return int(p_ext[int(p_ext[H_OFF_FORM]) + FP_TIME])


def _taus(sigmas, Z, mode) -> np.ndarray:
    """Physical times tau of the sigma-form states Z (rows) at ``sigmas``: column 0 itself with
    tau, one compiled :func:`physical_tau` call per row with the time element (a call from Python
    costs ~5 us, so tau's rows, the default, make none)."""
    if mode == TIME_LINEAR:
        return np.array([physical_tau(float(a), b, mode) for a, b in zip(sigmas, Z)])
    return np.array(Z[:, 0], dtype=float)


_STAT_KEYS = ("n_accepted", "n_rejected", "n_rhs", "n_jac", "n_lu")


def _add_stats(total: dict, part: dict) -> None:
    for k in _STAT_KEYS:
        total[k] = total.get(k, 0) + int(part.get(k, 0))


def integrate_time(method, p_ext, layout, y0_cowell, t_out, rtol, atol_cowell, mu, length_m, h_max=0.0,
                   max_steps=10**7, progress=None, n_events=0, terminal=(), t0=0.0):  # fmt: skip
    """Time form: integrate and return an IntegrationResult whose ``y`` rows are Cowell states.

    ``n_events`` > 0: the scene's event components (kernel/events.py, as many as the Cowell run
    would locate; ``terminal`` their flags) are located on the same physical state through
    :func:`formulations.dromo.dromo_time_events`; the result's ``events`` and ``stopped_by``
    are the driver's.  ``layout``: the Cowell state's StateLayout (model/state.py): only its
    root-orbit block is mapped to DROMO, every other block passes through."""
    from ..integrators.driver import IntegrationResult, integrate

    z0 = time_state(np.asarray(y0_cowell, float), layout, mu, length_m)
    # elements and sigma are O(1) non-dimensional: atol in their own units = the scene's atol,
    # which is atol_cowell[0]/L (the root position scale is the reference radius)
    a = np.asarray(atol_cowell, float)
    atol = np.concatenate([np.full(8, a[0] / length_m), layout.passthrough_atol(a)])
    ev = {"event": dromo_time_events, "n_events": n_events, "terminal": terminal} if n_events else {}
    res = integrate(method, dromo_time_rhs, t0, z0, t_out, p_ext, rtol, atol, h_max=h_max,
                    max_steps=max_steps, progress=progress, **ev)  # fmt: skip
    Y = np.array([cowell_state(z, layout, mu, length_m) for z in res.y]).reshape(len(res.t), layout.size)
    return IntegrationResult(t=res.t, y=Y, status=res.status, message=res.message, t_end=res.t_end,
                             y_end=cowell_state(res.y_end, layout, mu, length_m), stats=dict(res.stats),
                             events=res.events, stopped_by=res.stopped_by)  # fmt: skip


#: Sigma-form methods whose run can be written as it goes and continued (the clock loop's).
CLOCK_METHODS = (*ERK_KINDS, ABM_METHOD)


def integrate_sigma(method, p_ext, r0_m, v0_m_s, t_out, rtol, atol, mu, length_m, sigma0=0.0,
                    max_steps=10**7, progress=None, grid_per_rev=GRID_PER_REV, store=None):  # fmt: skip
    """Sigma form for a point mass, with the state reported at the physical times ``t_out`` (s).

    Returns an IntegrationResult with Cartesian rows [r, v] (m, m/s) at ``t_out``.  ``atol`` is in
    the units of the non-dimensional state (a scalar).  DOP853, Vern9 and "abm" find the output
    sigmas in their compiled loop (:func:`_integrate_sigma_clock`); the other methods use the sigma
    grid and a Newton search (:func:`_integrate_sigma_grid`).  See the module docstring.

    ``store`` (clock methods only; tetherlab/runstore.py): a run written as it goes.  After every
    call of the compiled loop, ``store.rows(j0, t, Y)`` receives the output rows j0.. it completed
    and ``store.chunk(state)`` the loop's state (CLOCK_STATE_ARRAYS and CLOCK_STATE_SCALARS, plus
    ``t`` and ``ended``), which it may checkpoint; a
    store whose ``resume`` is such a state continues from it, bit for bit the run that was never
    stopped (the loop restarts from the same numbers at the same step counts); the result's rows
    are then ``store.table(k)``, the k rows it holds.
    """
    tt = np.asarray(t_out, float)
    if tt.ndim != 1 or tt.size == 0 or np.any(np.diff(tt) < 0) or tt[0] < 0:
        raise ValueError(f"t_out: expected non-decreasing times >= 0 s; got {tt!r}")
    if method in CLOCK_METHODS:
        return _integrate_sigma_clock(method, p_ext, r0_m, v0_m_s, tt, rtol, atol, mu, length_m,
                                      sigma0, max_steps, progress, store)  # fmt: skip
    if store is not None:
        raise ValueError(f"method: expected one of {CLOCK_METHODS} for a sigma-form run written as it goes, "
                         f"got {method!r}")  # fmt: skip
    return _integrate_sigma_grid(method, p_ext, r0_m, v0_m_s, tt, rtol, atol, mu, length_m, sigma0,
                                 max_steps, progress, grid_per_rev)  # fmt: skip


#: Accepted steps per call of the compiled clock loop: progress is reported, rows streamed and
#: checkpoints taken between calls.  The calls restart the method (forgetting the controller's
#: last rejection), so the chunk size is a constant, never tuned to the machine's speed: a run
#: continued from a checkpoint then meets the same restarts as one that never stopped.
CLOCK_CHUNK_STEPS = 200_000

#: What the clock loop carries from one call to the next (the ``state`` its store receives).
CLOCK_STATE_ARRAYS = ("z", "stats", "p", "abm_F", "abm_S", "abm_K", "abm_w", "abm_fix")
CLOCK_STATE_SCALARS = ("sig", "h", "k", "budget", "status", "sig_max", "head", "n_landings", "residual_max_s",
                       "wall_s")


def _cartesian_rows(out_sig, out_z, tt, j0, j1, mode, T, mu, length_m):
    """Cowell rows [r, v] of the outputs j0..j1-1, and the largest time residual |t_k - t(sigma_k)|
    among them: each output's residual g is stepped over with the Kepler acceleration,
    r + v g + a g^2/2, v + a g."""
    tau_out = _taus(out_sig[j0:j1], out_z[j0:j1], mode)
    rows = []
    for i, j in enumerate(range(j0, j1)):
        r, v = dromo_to_cartesian(float(out_sig[j]), out_z[j, 1:8], mu, length_m)
        g = float(tt[j] - tau_out[i] * T)
        a = -mu * r / float(r @ r) ** 1.5
        rows.append(np.concatenate([r + v * g + 0.5 * a * g * g, v + a * g]))
    residual = float(np.max(np.abs(tt[j0:j1] - tau_out * T))) if j1 > j0 else 0.0
    return np.array(rows).reshape(j1 - j0, 6), residual


def _integrate_sigma_clock(method, p_ext, r0_m, v0_m_s, tt, rtol, atol, mu, length_m, sigma0,
                           max_steps, progress, store=None):  # fmt: skip
    """DOP853 or Vern9 in sigma with the output times found inside the compiled loop
    (:func:`_clock_run`).

    Each output row comes from one extra step of the method, from the start of the step in which tau
    crosses tau_k to the sigma located on that step's dense output; the main integration then
    goes on from that step's start, so the trajectory does not depend on the output times.  The
    small residual g = t_k - t(sigma_k) (the located sigma's bracket, and the interpolant's error
    in tau) is stepped over with the Kepler acceleration: r + v g + a g^2/2, v + a g.
    """
    import time

    from ..integrators.common import ST_ACCEPTED, ST_NJAC, ST_NLU, ST_NRHS, ST_REJECTED
    from ..integrators.common import IntegrationResult, status_message
    from ..integrators.driver import warm_up

    L, T = units(mu, length_m)
    mode = _time_mode(p_ext)
    z = sigma_state(r0_m, v0_m_s, mu, length_m, sigma0, 0.0, mode)
    el0 = z[1:]
    atol_v = np.full(8, float(atol))
    targets = tt / T
    # a sigma bound past the last output (extended by a revolution whenever it is reached first)
    sig_max = predicted_sigma(el0, sigma0, float(tt[-1]), T) + 0.25 * TWO_PI
    m = tt.size
    out_sig = np.empty(m)
    out_z = np.empty((m, 8))
    stats = np.zeros(8, dtype=np.int64)
    is_abm = method == ABM_METHOD
    compile_s = warm_up("vern9" if is_abm else method, dromo_sigma_rhs, 8, p_ext)
    kind = VERN9 if is_abm else ERK_KINDS[method]
    ws = _abm.workspace(8) if is_abm else None
    head = -1
    sig, h, k, budget, status = float(sigma0), 0.0, 0, int(max_steps), OK_STATUS
    if is_abm:
        h = TWO_PI / ABM_FIRST_STEPS_PER_REV
    n_landings, residual_max, wall_before = 0, 0.0, 0.0
    rows = []  # without a store: the Cowell rows, kept in memory
    back = store.resume if store is not None else None
    if back is not None:  # continue the loop where a checkpoint left it (CLOCK_STATE_*)
        if back["p"].shape != p_ext.shape:
            raise ValueError(f"resume: a parameter block of {back['p'].size} floats, this run's has {p_ext.size}")
        p_ext[:] = back["p"]
        z[:] = back["z"]
        stats[:] = back["stats"]
        sig, h, k, budget = float(back["sig"]), float(back["h"]), int(back["k"]), int(back["budget"])
        status, sig_max, head = int(back["status"]), float(back["sig_max"]), int(back["head"])
        n_landings, residual_max, wall_before = int(back["n_landings"]), float(back["residual_max_s"]), float(back["wall_s"])
        if is_abm:
            for key in ("F", "S", "K", "w", "fix"):
                ws[key][...] = back["abm_" + key]
    t0 = time.perf_counter()
    while k < m:
        acc = int(stats[ST_ACCEPTED])
        k_before = k
        if is_abm:
            status, sig, h, head, k = _abm_clock_run(dromo_sigma_rhs, dromo_clock_event, ABM_ORDER, sig, z, h,
                                                     ws["F"], ws["S"], head, targets, k, p_ext, float(rtol),
                                                     atol_v, min(CLOCK_CHUNK_STEPS, budget), out_sig, out_z,
                                                     stats, ws["K"], ws["w"], ws["fix"])  # fmt: skip
        else:
            status, sig, h, k, sig_max = _clock_run(kind, dromo_sigma_rhs, dromo_clock_event, sig, z,
                                                    h, targets, k, p_ext, float(rtol), atol_v,
                                                    sig_max, min(CLOCK_CHUNK_STEPS, budget), out_sig,
                                                    out_z, stats)  # fmt: skip
        budget -= int(stats[ST_ACCEPTED]) - acc
        # the outputs this call completed: their rows, the landing steps, the largest residual
        Yk, res_k = _cartesian_rows(out_sig, out_z, tt, k_before, k, mode, T, mu, length_m)
        n_landings += int(np.count_nonzero(out_sig[k_before:k] != sigma0))
        residual_max = max(residual_max, res_k)
        if store is None:
            rows.append(Yk)
        else:
            store.rows(k_before, tt[k_before:k], Yk)
        if progress is not None:
            progress(float(physical_tau(sig, z, mode) * T))
        ended = status != OK_STATUS and (status != MAX_STEPS_STATUS or budget <= 0)
        if store is not None:
            store.chunk(dict(
                t=float(physical_tau(sig, z, mode) * T), ended=ended, sig=sig, h=h, k=k, budget=budget, status=int(status),
                sig_max=sig_max, head=head, n_landings=n_landings, residual_max_s=residual_max,
                wall_s=wall_before + time.perf_counter() - t0, z=z, stats=stats, p=p_ext,
                **{"abm_" + key: (ws[key] if is_abm else np.zeros(0)) for key in ("F", "S", "K", "w", "fix")},
            ))  # fmt: skip
        if ended:
            break
    wall = wall_before + time.perf_counter() - t0
    Y = np.concatenate(rows) if rows else np.zeros((0, 6))
    if store is not None:
        Y = store.table(k)
    st = {"n_accepted": int(stats[ST_ACCEPTED]), "n_rejected": int(stats[ST_REJECTED]),
          "n_rhs": int(stats[ST_NRHS]), "n_jac": int(stats[ST_NJAC]), "n_lu": int(stats[ST_NLU]),
          "wall_s": wall, "compile_s": compile_s, "sigma_end": float(sig),
          # the landing steps, one per output after the start (their rhs calls are in n_rhs)
          "search_n_accepted": n_landings, "time_residual_max_s": residual_max}  # fmt: skip
    if k == m:
        status, message = 0, f"reached t={tt[-1]!r} (sigma form, sigma={out_sig[-1]:.6f})"
    else:
        t_now = float(physical_tau(sig, z, mode) * T)
        message = status_message(int(status), t_now, h, int(stats[5]), 0, int(max_steps))
        message += f" (sigma form: sigma={sig!r}, t={t_now!r} s)"
    r_end, v_end = dromo_to_cartesian(float(sig), z[1:8], mu, length_m)
    return IntegrationResult(t=tt[:k].copy(), y=Y, status=int(status), message=message,
                             t_end=float(tt[k - 1]) if k else 0.0,
                             y_end=np.concatenate([r_end, v_end]), stats=st)  # fmt: skip


def _integrate_sigma_grid(method, p_ext, r0_m, v0_m_s, tt, rtol, atol, mu, length_m, sigma0,
                          max_steps, progress, grid_per_rev):  # fmt: skip
    """Sigma form by a sigma grid and a Newton search on t(sigma) for each output time (any
    method; the module docstring)."""
    from ..integrators.driver import IntegrationResult, integrate

    L, T = units(mu, length_m)
    mode = _time_mode(p_ext)
    z0 = sigma_state(r0_m, v0_m_s, mu, length_m, sigma0, 0.0, mode)
    el0 = z0[1:]
    atol_v = np.full(8, float(atol))
    t_last = float(tt[-1])
    dsig = TWO_PI / grid_per_rev
    sig_end = predicted_sigma(el0, sigma0, t_last, T) + 0.25 * TWO_PI
    stats: dict = {}
    wall = 0.0

    # pass 1: sigma grid until it passes t_last (extended one revolution at a time if the
    # perturbation made the prediction short)
    sig_grid = [np.array([sigma0])]
    z_grid = [z0[None, :]]
    start_sig, start_z = sigma0, z0
    status, message, budget = 0, "", max_steps
    while True:
        n = max(1, int(math.ceil((sig_end - start_sig) / dsig)))
        grid = start_sig + dsig * np.arange(1, n + 1)
        res = integrate(method, dromo_sigma_rhs, start_sig, start_z, grid, p_ext, rtol, atol_v,
                        max_steps=budget, progress=None)  # fmt: skip
        _add_stats(stats, res.stats)
        wall += res.stats.get("wall_s", 0.0)
        budget -= res.stats.get("n_accepted", 0)
        sig_grid.append(res.t)
        z_grid.append(res.y)
        if progress is not None and len(res.t):
            progress(float(physical_tau(float(res.t[-1]), res.y[-1], mode) * T))
        if res.status != 0:
            status, message = res.status, res.message
            break
        if physical_tau(float(res.t[-1]), res.y[-1], mode) * T >= t_last or budget <= 0:
            break
        start_sig, start_z = float(res.t[-1]), res.y[-1].copy()
        sig_end = start_sig + TWO_PI
    S = np.concatenate(sig_grid)
    Z = np.concatenate(z_grid)
    tg = _taus(S, Z, mode) * T
    if not np.all(np.diff(tg) > 0):
        status = status or 4
        message = message or "time did not increase along sigma (h -> 0 or s <= 0: DROMO singular)"

    # pass 2: each requested time by Newton on t(sigma) from its bracketing grid state
    rows = []
    n_newton = 0
    search: dict = {}  # cost of the time searches, reported apart from the sigma pass
    for tk in tt:
        j = int(np.searchsorted(tg, tk, side="right")) - 1
        if j < 0 or j >= len(S) - 1 and tk > tg[-1]:
            break
        if tk == tg[j] or j == len(S) - 1:
            sig_k, z_k, g = float(S[j]), Z[j], tk - tg[j]
        else:
            sig_k, z_k, g, nn, st = _solve_time(method, p_ext, float(S[j]), Z[j], float(S[j + 1] - S[j]),
                                                tk, T, rtol, atol_v, search, mode)  # fmt: skip
            n_newton += nn
            if st != 0:
                status, message = st, f"time search near t={tk!r} s failed (status {st})"
                break
        r, v = dromo_to_cartesian(sig_k, z_k[1:8], mu, length_m)
        rows.append(np.concatenate([r + v * g, v]))  # first-order step over the residual g (~ulp of t)
    Y = np.array(rows).reshape(len(rows), 6)
    t_done = tt[: len(rows)].copy()
    stats["wall_s"] = wall
    stats["newton_integrations"] = n_newton
    for k in _STAT_KEYS:
        stats["search_" + k] = search.get(k, 0)
    stats["sigma_end"] = float(S[-1])
    z_end = Z[-1]
    r_end, v_end = dromo_to_cartesian(float(S[-1]), z_end[1:8], mu, length_m)
    if status == 0:
        message = f"reached t={t_done[-1]!r} (sigma form, sigma_end={S[-1]:.6f})"
    return IntegrationResult(t=t_done, y=Y, status=int(status), message=message,
                             t_end=float(t_done[-1]) if len(t_done) else 0.0,
                             y_end=np.concatenate([r_end, v_end]), stats=stats)  # fmt: skip


def _solve_time(method, p_ext, sig_a, z_a, width, tk, T, rtol, atol_v, stats, mode):
    """sigma in (sig_a, sig_a + width] with t(sigma) = tk: safeguarded Newton whose evaluations
    integrate from the grid state (sig_a, z_a).  Returns (sigma, z, tk - t(sigma), evals, status).
    ``mode``: the state's time variable (:func:`physical_tau`)."""
    from ..integrators.driver import integrate

    lo, hi = 0.0, width
    d = (tk - physical_tau(sig_a, z_a, mode) * T) / dt_dsigma(sig_a, z_a, T)
    if not lo < d < hi:
        d = 0.5 * (lo + hi)
    tol = 4.0 * np.finfo(float).eps * max(abs(tk), T)
    for it in range(1, 60):
        res = integrate(method, dromo_sigma_rhs, sig_a, z_a, np.array([sig_a + d]), p_ext, rtol,
                        atol_v)  # fmt: skip
        _add_stats(stats, res.stats)
        if res.status != 0:
            return sig_a + d, z_a, 0.0, it, res.status
        z = res.y[-1]
        sig = sig_a + d
        g = physical_tau(sig, z, mode) * T - tk
        if abs(g) <= tol:
            return sig, z, -g, it, 0
        if g < 0:
            lo = d
        else:
            hi = d
        dn = d - g / dt_dsigma(sig, z, T)
        if not lo < dn < hi:
            dn = 0.5 * (lo + hi)
        if hi - lo <= 4.0 * np.finfo(float).eps * max(abs(sig), 1.0):
            return sig, z, -g, it, 0
        d = dn
    return sig, z, -g, it, 0
