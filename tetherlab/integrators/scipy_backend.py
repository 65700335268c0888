"""Cross-check backend: scipy's ODE solvers on the same compiled right-hand side.

The cfunc is called from Python through ctypes (a few microseconds a call, fine for a reference
run).  The step loop is the one of ``scipy.integrate.solve_ivp`` (scipy/integrate/_ivp/ivp.py:
``solver.step()``, then the step's dense output evaluated at the output times it passed, found
with ``searchsorted(..., side='right')``), written out here because ``solve_ivp`` discards
everything when the right-hand side raises: this loop keeps the outputs of every completed step
and reports the failure in the result instead.  On success the numbers are those of
``solve_ivp(..., t_eval=t_out)`` (a test checks it).
"""

from __future__ import annotations

import ctypes
import time

import numpy as np
from scipy import integrate as _si

from .common import (
    MAX_STEPS,
    NON_FINITE,
    OK,
    RHS_FAILED,
    STEP_UNDERFLOW,
    IntegrationResult,
    status_message,
)

SOLVERS = {
    "DOP853": _si.DOP853,
    "Radau": _si.Radau,
    "LSODA": _si.LSODA,
    "BDF": _si.BDF,
    "RK45": _si.RK45,
}

# Our own prototype over the cfunc's address, taking raw addresses: cheaper than building
# POINTER(c_double) objects on every call through ``rhs.ctypes``.
_PROTO = ctypes.CFUNCTYPE(ctypes.c_int64, ctypes.c_double, ctypes.c_void_p, ctypes.c_void_p,
                          ctypes.c_void_p)  # fmt: skip


class _RhsFailure(Exception):
    """Raised inside ``fun`` to stop the solver; ``code`` is RHS_FAILED or NON_FINITE."""

    def __init__(self, code, t):
        super().__init__(f"rhs failure {code} at t={t!r}")
        self.code = code
        self.t = t


def integrate_scipy(solver, rhs, t0, y0, t_out, p, rtol, atol, h0, h_max, max_steps,
                    chunk_seconds, progress, breaks=(), at_interval=None):  # fmt: skip
    """Run scipy's ``solver`` (a key of :data:`SOLVERS`); arguments already validated by the
    driver (``atol`` is an array, ``t_out`` non-decreasing and >= t0).  ``breaks`` (sorted,
    inside (t0, t_out[-1])): a new solver object is started at each, as from a new initial value,
    its ``t_bound`` the next breakpoint (scipy's steps land on t_bound), with ``at_interval(t_b)``
    called first (driver.integrate)."""
    if solver not in SOLVERS:
        raise ValueError(f"solver: expected one of {', '.join(SOLVERS)}; got {solver!r}")
    cls = SOLVERS[solver]
    n = y0.size
    m = t_out.size
    cf = _PROTO(rhs.address)
    p_addr = p.ctypes.data
    counts = {"n_rhs": 0, "rhs_status": 0}

    def fun(t, y):
        y = np.ascontiguousarray(y, dtype=np.float64)
        dydt = np.empty(n)
        st = cf(t, y.ctypes.data, dydt.ctypes.data, p_addr)
        counts["n_rhs"] += 1
        if st != 0:
            counts["rhs_status"] = int(st)
            raise _RhsFailure(RHS_FAILED, float(t))
        # scipy cannot step around NaN: Radau and BDF raise from their LU on a NaN Jacobian.
        # Stop cleanly instead (the native kernels retry with smaller steps first).
        if not np.all(np.isfinite(dydt)):
            raise _RhsFailure(NON_FINITE, float(t))
        return dydt

    y_out = np.empty((m, n))
    done = int(np.searchsorted(t_out, t0, side="right"))  # output times equal to t0
    y_out[:done] = y0
    t_end = t0
    y_end = y0.copy()
    status = OK
    scipy_msg = ""
    n_steps = 0
    wall0 = time.perf_counter()
    next_report = wall0 + chunk_seconds
    solver_obj = None
    fail_t = None
    ends = [float(b) for b in breaks] + [float(t_out[-1])]
    piece = 0
    done_pieces = {"njev": 0, "nlu": 0}  # Jacobians and LU factorisations of the finished pieces

    def start(t_a, y_a, first):
        if at_interval is not None:
            at_interval(ends[piece])
        return cls(
            fun, t_a, y_a, ends[piece], rtol=rtol, atol=atol,
            first_step=first if first > 0 else None,
            max_step=h_max if h_max > 0 else np.inf,
        )  # fmt: skip

    try:
        if done < m:
            solver_obj = start(t0, y0, h0)
        while solver_obj is not None and solver_obj.status in ("running", "finished"):
            if solver_obj.status == "finished":
                if piece + 1 >= len(ends):
                    break
                piece += 1
                for k in done_pieces:
                    done_pieces[k] += int(getattr(solver_obj, k, 0) or 0)
                solver_obj = start(t_end, y_end, 0.0)
                continue
            if n_steps >= max_steps:
                status = MAX_STEPS
                break
            message = solver_obj.step()
            if solver_obj.status == "failed":
                status = STEP_UNDERFLOW
                scipy_msg = str(message)
                break
            n_steps += 1
            t_new = solver_obj.t
            if not np.all(np.isfinite(solver_obj.y)):
                status = NON_FINITE
                break
            j = int(np.searchsorted(t_out, t_new, side="right"))
            if j > done:
                # Dense output of the step (DOP853 evaluates its 3 extra stages here, which may
                # fail: then the step's outputs are not written and t_end stays at its start).
                vals = solver_obj.dense_output()(t_out[done:j])
                vals = np.asarray(vals).reshape(n, j - done)
                if not np.all(np.isfinite(vals)):
                    status = NON_FINITE
                    break
                y_out[done:j] = vals.T
                done = j
            t_end = float(t_new)
            y_end = np.array(solver_obj.y, dtype=np.float64)
            if progress is not None and time.perf_counter() >= next_report:
                progress(t_end)
                next_report = time.perf_counter() + chunk_seconds
    except _RhsFailure as exc:
        status = exc.code
        fail_t = exc.t
    wall_s = time.perf_counter() - wall0
    if progress is not None:
        progress(t_end)

    stats = {
        "n_accepted": n_steps,
        "n_rejected": None,  # scipy's solvers do not report rejected steps
        "n_rhs": counts["n_rhs"],
        "n_jac": done_pieces["njev"] + int(getattr(solver_obj, "njev", 0) or 0),
        "n_lu": done_pieces["nlu"] + int(getattr(solver_obj, "nlu", 0) or 0),
        "rhs_status": counts["rhs_status"],
        "n_newton_fail": None,
        "n_chunks": 1,
        "wall_s": wall_s,
        "compile_s": 0.0,
    }
    h = float(getattr(solver_obj, "step_size", None) or 0.0) if solver_obj is not None else 0.0
    if fail_t is not None:
        # scipy has no retry with a smaller step: the first failing evaluation ends the run.
        what = (f"the right-hand side returned status {counts['rhs_status']}"
                if status == RHS_FAILED else "the right-hand side returned non-finite values")
        msg = f"{what} at t={fail_t!r} (in the step from t={t_end!r})"
    else:
        msg = status_message(status, t_end, h, counts["rhs_status"], 0, max_steps)
    if scipy_msg:
        msg = f"{msg}; scipy: {scipy_msg}"
    msg = f"scipy {solver}: {msg}"
    return IntegrationResult(
        t=t_out[:done].copy(), y=y_out[:done].copy(), status=status, message=msg, t_end=t_end,
        y_end=y_end, stats=stats,
    )  # fmt: skip
