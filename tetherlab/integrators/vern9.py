"""Vern9: Verner's "most efficient" explicit Runge-Kutta pair of order 9(8), compiled.

Reference: J.H. Verner, "Numerically optimal Runge-Kutta pairs with interpolants", Numer.
Algorithms 53 (2010) 383-396.  Coefficients in :mod:`.vern9_coefficients` (exact decimals),
rounded and checked at import by :mod:`.tableau`; tests/test_vern9.py verifies every order
condition.

Why a second explicit method: at tight tolerances a higher order takes fewer steps.  On the
Stiefel-Scheifele problem (DROMO) Vern9 reaches 1 m with about 25 % fewer rhs calls than DOP853
(20.8k against 27.7k) and 1 mm with 18-30 % fewer (``make bench``, docs/integrators.md).  It
pays 16 rhs calls per step against DOP853's 12, and its stability region does not grow with
that, so where an explicit step is bounded by stability (a tether's axial mode) DOP853 is the
cheaper one.

The pieces here are the method's own: its stages, the order-9 solution with the order-8 error
estimate, and the interpolant.  The step loop (controller, outputs, events) is shared with
DOP853 in :mod:`.erk`.

* Error estimate: err = RMS of h sum_j E_j K_j / (atol + rtol max(|y|, |y_new|)), E = b8 - b9:
  the order-8 solution's deviation, i.e. error per step of the *embedded* method (the solution
  kept is the order-9 one: local extrapolation, as DOP853 does).
* Controller: Hairer's, h_new = h / (err^(1/9) / SAFETY) with 0.333 <= h_new/h <= 6, and
  SAFETY = 0.8, below Hairer's 0.9:
  with 0.9 a quarter of Vern9's steps were rejected on eccentric orbits (the error per step
  changes fast along the orbit); 0.8 rejects 1-2 % and reaches the same final error with fewer
  rhs calls (measured on Stiefel-Scheifele, DROMO and Cowell: see docs/integrators.md).
* Dense output: order 8, from the 16 stages, f(t + h, y_new) (computed for the next step anyway)
  and 4 extra stages, made only on steps with an output time or an event inside.  Its
  coefficients reach 1.3e4: summed over the stages themselves, the interpolated value carried a
  rounding of about 1e-12 of the step's increment h f (2e-11 rad/s on a wheel's speed at 5 s
  steps); summed over the stages' differences from the first it carries 1e-12 of h times the
  change of f across the step (docs/integrators.md section 5).  The step ends use the order-9
  solution itself.
"""

from __future__ import annotations

from tetherlab._jit import njit, ptr, row_ptr

from .common import ST_NRHS, all_finite, scaled_sq
from .dop853 import rk_stages
from .tableau import V9_A, V9_B, V9_C, V9_E, V9_N_ALL, V9_N_DENSE, V9_N_STAGES, V9_P

_A = V9_A
_B = V9_B
_C = V9_C
_E = V9_E
_P = V9_P
NS = V9_N_STAGES  # 16
FSAL = 16  # row of K holding f(t + h, y_new)
NK = V9_N_ALL  # 21 rows of K
ORDER = 9
SAFETY = 0.8


@njit(cache=True)
def v9_stages(rhs, t, y, h, p, K, ys, lo, hi, stats):
    """Stages lo..hi-1 into K[lo..hi-1] (K[0..lo-1] known); the interpolant's stages (lo > NS)
    are checked for non-finite values (-1).  See :func:`.dop853.rk_stages`."""
    return rk_stages(_A, _C, lo, hi, rhs, t, y, h, p, K, ys, lo > NS, stats)


@njit(cache=True)
def v9_solution(y, K, h, y_new, rtol, atol, with_error):
    """y_new = y + h sum_j b_j K_j (order 9); returns the error norm (0.0 if not with_error)."""
    n = y.shape[0]
    err = 0.0
    for i in range(n):
        acc = 0.0
        e = 0.0
        for j in range(NS):
            acc += _B[j] * K[j, i]
            e += _E[j] * K[j, i]
        y_new[i] = y[i] + h * acc
        if with_error:
            sk = atol[i] + rtol * max(abs(y[i]), abs(y_new[i]))
            err += scaled_sq(h * e, sk)
    if not with_error or err == 0.0:
        return 0.0
    return (err / n) ** 0.5


@njit(cache=True)
def v9_dense_eval(y, K, h, x, out):
    """y(t + x h) = y + h sum_s b_s(x) K_s with b_s(x) = x (P_s0 + x (P_s1 + ... x P_s7)), summed
    as y + h (x K_0 + sum_{s >= 1} b_s(x) (K_s - K_0)): the same value in exact arithmetic, since
    sum_s b_s(x) = x, but the weights (up to 1.3e4) multiply the stages' differences instead of the
    stages, so their rounding scales with how much f changes across the step, not with f."""
    n = y.shape[0]
    for i in range(n):
        out[i] = 0.0
    for s in range(1, NK):
        w = 0.0
        for k in range(V9_N_DENSE - 1, -1, -1):
            w = w * x + _P[s, k]
        w *= x
        if w != 0.0:
            for i in range(n):
                out[i] += w * (K[s, i] - K[0, i])
    for i in range(n):
        out[i] = y[i] + h * (x * K[0, i] + out[i])


@njit(cache=True)
def vern9_step(rhs, t, y, h, p, K, ys, y_new, stats):
    """One Vern9 step of size h from (t, y) into y_new, without error control (the DROMO output
    clock lands on a point inside a step the controller already accepted).  K (NK, n) and ys (n,)
    are workspaces.  Returns the first nonzero rhs status, -1 for non-finite values, or 0."""
    st = rhs(t, ptr(y), row_ptr(K, 0), ptr(p))
    stats[ST_NRHS] += 1
    if st != 0:
        return st
    st = v9_stages(rhs, t, y, h, p, K, ys, 1, NS, stats)
    if st != 0:
        return st
    v9_solution(y, K, h, y_new, 0.0, y, False)
    return 0 if all_finite(y_new) else -1
