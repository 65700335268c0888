"""Python layer over the compiled kernels: validation, chunked calls, progress, results.

Inputs are validated once here, so the kernels can trust them.  The kernel is then called in
chunks so a progress callback (and Ctrl-C) can run between them.  A chunk is a budget of
*accepted steps*, sized from the measured step rate so one call lasts about ``chunk_seconds``; each
call gets all remaining output times and stops right after an accepted step.  Chunking by steps
rather than by slices of output times is deliberate: a chunk that ended at an output time would
clip the step there, so the trajectory would depend on the chunk sizes, i.e. on the speed of the
machine.  With step budgets and exact resumption (DOP853 carries only h and f(t, y); RADAU5 gets
its workspace back) the result is bit-for-bit the same however the run is split.
"""

from __future__ import annotations

import math
import numbers
import time
import numpy as np
from numba.core.ccallback import CFunc

from tetherlab._jit import RHS_SIG

from .common import (
    IntegrationResult,
    EVENT,
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
    status_message,
)
from .erk import KINDS, erk_core
from .linear_solver import NewtonSolver, dense
from .radau5 import radau5_core, radau5_workspace

NATIVE_METHODS = ("dop853", "vern9", "radau5")
SCIPY_METHODS = ("scipy:DOP853", "scipy:Radau", "scipy:LSODA", "scipy:BDF", "scipy:RK45")
METHODS = NATIVE_METHODS + SCIPY_METHODS

#: Accepted steps of the first chunk: small, so the step rate is measured (and the first progress
#: report arrives) quickly; later chunks are sized from that rate.
_FIRST_CHUNK_STEPS = 64
#: A chunk grows by at most this factor per call, so one unrepresentative fast chunk (e.g. a
#: quiet stretch of the trajectory) cannot schedule a chunk of many minutes.
_MAX_CHUNK_GROWTH = 8


# ----------------------------------------------------------------------------------------------
# validation
# ----------------------------------------------------------------------------------------------
def _check_method(method):
    if not isinstance(method, str) or method not in METHODS:
        raise ValueError(f"method: expected one of {', '.join(METHODS)}; got {method!r}")


def _finite_float(name, value, *, min_value=None, open_min=False):
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(f"{name}: expected a real number; got {type(value).__name__} {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise ValueError(f"{name}: expected a finite number; got {v!r}")
    if min_value is not None and (v <= min_value if open_min else v < min_value):
        rel = ">" if open_min else ">="
        raise ValueError(f"{name}: expected a value {rel} {min_value}; got {v!r}")
    return v


def _check_rhs(rhs):
    if not isinstance(rhs, CFunc) or rhs._sig != RHS_SIG:
        got = getattr(rhs, "_sig", None) or type(rhs).__name__
        raise ValueError(
            "rhs: expected a numba cfunc with signature "
            f"{RHS_SIG} (use tetherlab._jit.rhs_cfunc); got {got}"
        )


def _check_p(p):
    # No silent copy: the model may write diagnostics into p, and the caller reads them there.
    if not (
        isinstance(p, np.ndarray)
        and p.dtype == np.float64
        and p.ndim == 1
        and p.flags.c_contiguous
    ):
        desc = (
            f"{p.dtype} array of shape {p.shape}, contiguous={p.flags.c_contiguous}"
            if isinstance(p, np.ndarray)
            else type(p).__name__
        )
        raise ValueError(f"p: expected a 1-D C-contiguous float64 numpy array; got {desc}")


def _as_vector(name, value):
    try:
        arr = np.array(value, dtype=np.float64)  # a copy: the caller's array is never modified
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name}: expected an array of real numbers; got {value!r}") from exc
    return arr


def _validate(method, rhs, t0, y0, t_out, p, rtol, atol, h0, h_max, max_steps, chunk_seconds,
              progress, fixed_step):  # fmt: skip
    _check_method(method)
    _check_rhs(rhs)
    t0 = _finite_float("t0", t0)
    y = _as_vector("y0", y0)
    if y.ndim != 1 or y.size == 0:
        raise ValueError(f"y0: expected a non-empty 1-D array; got shape {y.shape}")
    if not np.all(np.isfinite(y)):
        raise ValueError(f"y0: expected finite values; got non-finite at indices "
                         f"{np.flatnonzero(~np.isfinite(y)).tolist()[:10]}")  # fmt: skip
    n = y.size
    tt = np.ascontiguousarray(_as_vector("t_out", t_out))
    if tt.ndim != 1 or tt.size == 0:
        raise ValueError(f"t_out: expected a non-empty 1-D array; got shape {tt.shape}")
    if not np.all(np.isfinite(tt)):
        raise ValueError("t_out: expected finite times; got NaN or Inf")
    if np.any(np.diff(tt) < 0):
        k = int(np.flatnonzero(np.diff(tt) < 0)[0])
        raise ValueError(f"t_out: expected non-decreasing times; got t_out[{k}]={tt[k]!r} > "
                         f"t_out[{k + 1}]={tt[k + 1]!r}")  # fmt: skip
    if tt[0] < t0:
        raise ValueError(f"t_out: expected times >= t0={t0!r} (forward integration only); "
                         f"got t_out[0]={tt[0]!r}")  # fmt: skip
    _check_p(p)
    rtol = _finite_float("rtol", rtol)
    if not 0.0 < rtol < 1.0:
        raise ValueError(f"rtol: expected a value in (0, 1); got {rtol!r}")
    a = _as_vector("atol", atol)
    if a.ndim == 0:
        a = np.full(n, float(a))
    if a.ndim != 1 or a.size != n:
        raise ValueError(f"atol: expected a scalar or an array of length {n} (len(y0)); "
                         f"got shape {a.shape}")  # fmt: skip
    if not np.all(np.isfinite(a)) or np.any(a < 0):
        raise ValueError(f"atol: expected finite values >= 0; got min {a.min()!r}")
    a = np.ascontiguousarray(a)
    h0 = _finite_float("h0", h0, min_value=0.0)
    h_max = _finite_float("h_max", h_max, min_value=0.0)
    if isinstance(max_steps, bool) or not isinstance(max_steps, numbers.Integral) or max_steps < 1:
        raise ValueError(f"max_steps: expected an integer >= 1; got {max_steps!r}")
    chunk_seconds = _finite_float("chunk_seconds", chunk_seconds, min_value=0.0, open_min=True)
    if progress is not None and not callable(progress):
        raise ValueError(f"progress: expected a callable or None; got {type(progress).__name__}")
    if not isinstance(fixed_step, (bool, np.bool_)):
        raise ValueError(f"fixed_step: expected a bool; got {fixed_step!r}")
    fixed_step = bool(fixed_step)
    if fixed_step:
        if method not in NATIVE_METHODS:
            raise ValueError(f"fixed_step: expected False with a scipy method (fixed steps are "
                             f"supported by {NATIVE_METHODS} only); got True with "
                             f"{method!r}")  # fmt: skip
        if h0 <= 0.0:
            raise ValueError(f"h0: expected the fixed step size > 0 (fixed_step=True); got {h0!r}")
    return t0, y, tt, rtol, a, h0, h_max, int(max_steps), chunk_seconds, fixed_step


# ----------------------------------------------------------------------------------------------
# compilation
# ----------------------------------------------------------------------------------------------
def _call_kernel(method, rhs, t, y, t_out, p, rtol, atol, h, h_max, max_steps, y_out, stats,
                 fixed_step, ws, resume, event=None, ne=0, ev=None):  # fmt: skip
    if event is None:
        event, ne, ev = rhs, 0, _NO_EV  # same ABI; never called with ne = 0
    if method in KINDS:
        return erk_core(KINDS[method], rhs, t, y, t_out, p, rtol, atol, h, h_max, max_steps, y_out,
                        stats, fixed_step, event, ne, ev)  # fmt: skip
    return radau5_core(rhs, t, y, t_out, p, rtol, atol, h, h_max, max_steps, y_out, stats,
                       fixed_step, *ws, resume, event, ne, ev)  # fmt: skip


_NO_EV = np.array([0.0, -1.0, -1.0, 0.0])  # t, component, forced component, its side

#: Native methods whose kernel this process has already compiled or loaded.  Every rhs cfunc has
#: the same first-class function type (RHS_SIG), so one warm-up per method covers every model;
#: skipping the repeat saves ~0.1 ms of numba argument typing per call (measurable on a 3 ms
#: Stiefel run).
_WARM: set[str] = set()


def warm_up(method, rhs, n, p):
    """Make sure the kernel of ``method`` is compiled (or loaded from the disk cache); return the
    seconds that took.

    The kernel is called with an output time equal to the start time, which returns before any
    rhs evaluation (so the model is never called at a made-up state), but numba compiles the
    whole function for these argument types on that first call.  Once warm (in this process),
    it only validates its arguments and returns 0.0.  scipy methods need no compilation (the cfunc
    is compiled when defined): 0.0.
    """
    _check_method(method)
    if method not in NATIVE_METHODS:
        return 0.0
    _check_rhs(rhs)
    _check_p(p)
    n = int(n)
    if n < 1:
        raise ValueError(f"n: expected an integer >= 1; got {n}")
    if method in _WARM:
        return 0.0
    y = np.zeros(n)
    t_out = np.zeros(1)
    y_out = np.zeros((1, n))
    stats = np.zeros(8, dtype=np.int64)
    ws = radau5_workspace(n) if method == "radau5" else ()
    t0 = time.perf_counter()
    _call_kernel(method, rhs, 0.0, y, t_out, p, 1e-6, np.ones(n), 0.0, 0.0, 1, y_out, stats,
                 False, ws, False)  # fmt: skip
    _WARM.add(method)
    return time.perf_counter() - t0


# ----------------------------------------------------------------------------------------------
# integrate
# ----------------------------------------------------------------------------------------------


def integrate(method, rhs, t0, y0, t_out, p, rtol, atol, h0=0.0, h_max=0.0, max_steps=10**7,
              chunk_seconds=0.5, progress=None, fixed_step=False, second_order=False,
              event=None, n_events=0, terminal=(), newton="auto", y_out=None, checkpoint=None,
              restart=None, breaks=(), at_interval=None, at_sides=None):  # fmt: skip
    """Integrate y' = rhs(t, y; p) from t0 and return the solution at the times ``t_out``.

    ``method``: one of :data:`METHODS`.  ``rhs``: a cfunc with :data:`tetherlab._jit.RHS_SIG`.
    ``p``: the model's float64 parameter array, passed by reference (the model may write into
    it).  ``rtol`` in (0, 1); ``atol`` scalar or per component (>= 0).  ``h0``: first step (0:
    automatic); ``h_max``: largest step (0: unlimited); ``max_steps``: accepted-step budget of
    the whole run.  ``progress(t)`` is called after each chunk of about ``chunk_seconds``.
    ``fixed_step``: constant steps of ``h0`` without error control (native methods only; for
    convergence studies).  ``second_order``: the state is y = [q, v] with q' = v exactly (Cowell);
    an integer M1 instead: y = [q, v, w] with q' = v for the first M1 components and a first-order
    rest w (Hairer's M1 = M2; the attitude and wheel blocks of rigid bodies);
    RADAU5 then solves reduced Newton systems of half the size (same steps, less linear
    algebra); other methods ignore it.  ``event``: a cfunc with the rhs ABI writing ``n_events``
    values g(t, y) (native methods only); every change of side of a component (g < 0 vs g >= 0)
    is located on the dense output, the integration is taken exactly to it (no step straddles
    it: the place for kinks such as a tether going slack) and restarted there; components whose
    ``terminal[k]`` is true stop the run there, with the stop state as the last output row.
    ``newton`` (RADAU5): the Newton matrix, as scipy's ``jac``: a
    :class:`tetherlab.integrators.linear_solver.NewtonSolver` handed in by the model (a tether
    model's: ``tetherlab.tether.newton_solver.choose(p, n, second_order, "auto")``, the O(n)
    structured matrix where it applies, which pipeline.py passes for every scene run), or "dense"
    / "auto" (no solver handed in): the finite-difference Jacobian and dense LU.
    ``stats["newton_matrix"]`` says which was used and, for a dense one, why.
    Never raises for a failure of the integration itself: that is
    reported in the result's ``status``/``message``, with every output computed before it.

    Runs that write as they go (tetherlab/runstore.py; native methods only): ``y_out`` is the
    caller's (len(t_out), n) output buffer (e.g. a memory-mapped file), returned as a view, never
    copied; ``checkpoint(state)`` is called after each chunk that continues, with every value the
    loop carries from one kernel call to the next (:func:`_loop_state`; ``p`` is the caller's);
    ``restart=state`` continues from such a state.  Since a chunk ends right after an accepted
    step and the kernels continue from (t, y, h, p, event state, RADAU5 workspace) exactly, a
    continued run computes the same outputs bit for bit.

    Breakpoints (docs/integrators.md section 14): ``breaks``, times where the right-hand side has
    a kink or a jump in t (the corners and jumps of time tables).  The integration is split into
    smooth intervals between them: a step lands exactly on each breakpoint and the method restarts
    there as from a new initial value (fresh initial step, RADAU5's workspace rebuilt, the event
    state cleared), so no step straddles a breakpoint and nothing estimated before it is used after
    it.  ``at_interval(t_b)`` is called before each interval is integrated with its end t_b (a
    breakpoint or the last output time): the model uses it to evaluate its tables from the left at
    t_b (the driver knows no layout).  An event component whose side changes at a breakpoint (a
    jump in the table it depends on) is reported as an event at the breakpoint's time.

    ``at_sides(sides)`` (with events): called with the side of every event component (+1: g >= 0,
    -1: g < 0) at the start, after each located event and at each breakpoint, and only then: a
    model may lock the branch of each switch to it, so that the right-hand side is smooth between
    located events (discontinuity locking; bodies/wheels.py).  The sides travel in checkpoints.
    """
    t0, y, tt, rtol, atol_v, h0, h_max, max_steps, chunk_seconds, fixed_step = _validate(
        method, rhs, t0, y0, t_out, p, rtol, atol, h0, h_max, max_steps, chunk_seconds,
        progress, fixed_step,
    )  # fmt: skip
    ne, terminal = _check_events(method, event, n_events, terminal)
    bks = _check_breaks(breaks, t0, tt, at_interval, at_sides)
    if method in SCIPY_METHODS:
        from .scipy_backend import integrate_scipy

        return integrate_scipy(method.split(":", 1)[1], rhs, t0, y, tt, p, rtol, atol_v, h0,
                               h_max, max_steps, chunk_seconds, progress, bks, at_interval)  # fmt: skip

    n = y.size
    m = tt.size
    compile_s = warm_up(method, rhs, n, p)
    external = y_out is not None
    if external:
        if not (isinstance(y_out, np.ndarray) and y_out.dtype == np.float64 and y_out.shape == (m, n)
                and y_out.flags.c_contiguous):  # fmt: skip
            raise ValueError(f"y_out: expected a C-contiguous float64 array of shape {(m, n)}; got "
                             f"{getattr(y_out, 'shape', type(y_out).__name__)}")  # fmt: skip
    else:
        y_out = np.empty((m, n))
    stats = np.zeros(8, dtype=np.int64)
    if isinstance(second_order, (bool, np.bool_)):
        if second_order and n % 2:
            raise ValueError(f"second_order: expected an even state length (y = [q, v]); got {n}")
        m1 = n // 2 if second_order else 0
    elif isinstance(second_order, (int, np.integer)) and 0 <= second_order and 2 * second_order <= n:
        m1 = int(second_order)  # y = [q (m1), v (m1), first-order rest]: the state-layout descriptor's NQT
    else:
        raise ValueError(f"second_order: expected a bool or an integer M1 with 0 <= 2 M1 <= n = {n}; got {second_order!r}")
    # the structured Newton matrix: y = [q, q'], or y = [q, q', w] with rigid bodies' attitude and
    # wheels as the border (docs/integrators.md section 13)
    solver = _newton_choice(method, newton)

    def new_ws():
        return radau5_workspace(n, m1, solver) if method == "radau5" else ()

    ws = new_ws()
    ev = _NO_EV.copy()
    events = []
    sides = np.ones(ne)
    stopped_by = None
    t_stop_row = None

    t = t0
    h = h0
    done = 0
    budget = max_steps
    chunk = _FIRST_CHUNK_STEPS
    n_chunks = 0
    resume = False
    if restart is not None:
        t, h, done, budget = float(restart["t"]), float(restart["h"]), int(restart["done"]), int(restart["budget"])
        y[:] = restart["y"]
        stats[:] = restart["stats"]
        ev[:] = restart["ev"]
        resume = bool(restart["resume"])
        for a, b in zip(_ws_arrays(ws), restart["ws"]):
            a[...] = b
        events = [tuple(e) for e in restart["events"]]
        events = [(float(a), int(b), int(c)) for a, b, c in events]
        sides = np.array(restart["sides"], dtype=float) if ne > 0 else sides
    elif ne > 0 and at_sides is not None:
        if at_interval is not None:
            ib0 = int(np.searchsorted(bks, t, side="right"))
            at_interval(float(bks[ib0]) if ib0 < bks.size else float(tt[-1]))
        sides = np.where(event_values_at(event, t, y, p, ne) < 0.0, -1.0, 1.0)
        at_sides(sides.copy())
    wall0 = time.perf_counter()
    while True:
        steps_before = int(stats[ST_ACCEPTED])
        c0 = time.perf_counter()
        # the smooth interval: up to the next breakpoint after t, else to the last output
        ib = int(np.searchsorted(bks, t, side="right"))
        t_b = float(bks[ib]) if ib < bks.size else float(tt[-1])
        if at_interval is not None:
            at_interval(t_b)
        if ib < bks.size:
            k_in = int(np.searchsorted(tt, t_b, side="right"))  # outputs <= t_b (k_in < m: t_b < tt[-1])
            if k_in > done and tt[k_in - 1] == t_b:
                sub_t, n_real = tt[done:k_in], k_in - done
            else:
                # t_b is not an output time: it is handed to the kernel as the last one, its row
                # the next output's (written again when that output is reached)
                sub_t, n_real = np.concatenate([tt[done:k_in], [t_b]]), k_in - done
            sub_y = y_out[done : done + sub_t.size]
        else:
            sub_t, sub_y, n_real = tt[done:], y_out[done:], m - done
        status, t, h, nd = _call_kernel(method, rhs, t, y, sub_t, p, rtol, atol_v, h, h_max,
                                        min(chunk, budget), sub_y, stats, fixed_step, ws,
                                        resume, event, ne, ev)  # fmt: skip
        n_chunks += 1
        resume = True
        done += min(int(nd), n_real)
        if status == OK and ib < bks.size:
            # at the breakpoint: restart afresh on the next interval (events whose side the jump
            # changed are reported at its time)
            nxt = float(bks[ib + 1]) if ib + 1 < bks.size else float(tt[-1])
            if ne > 0:
                before = event_values_at(event, t, y, p, ne)
                if at_interval is not None:
                    at_interval(nxt)
                after = event_values_at(event, t, y, p, ne)
                for comp in range(ne):
                    if (before[comp] < 0.0) != (after[comp] < 0.0):
                        events.append((float(t), comp, 1 if after[comp] >= 0.0 else -1))
                sides = np.where(after < 0.0, -1.0, 1.0)
                if at_sides is not None:
                    at_sides(sides.copy())
            resume = False
            ws = new_ws()
            ev = _NO_EV.copy()
            if not fixed_step:
                h = 0.0
            status = MAX_STEPS  # keep going (the budget check below still applies)
        if status == EVENT:
            # Take the integration exactly to the event (the right end of its bracket, already
            # on the new side), filling the outputs before it, then restart there afresh.
            t_ev, comp, new_side = float(ev[0]), int(ev[1]), (1 if ev[3] >= 0.0 else -1)
            pending = tt[done:]
            k_in = int(np.searchsorted(pending, t_ev, side="right"))
            sub_t = pending[:k_in]
            if k_in == 0 or sub_t[-1] < t_ev:
                sub_t = np.concatenate([sub_t, [t_ev]])
            sub_out = np.empty((sub_t.size, n))
            ws_sub = new_ws()
            status, t, h_sub, nd = _call_kernel(method, rhs, t, y, sub_t, p, rtol, atol_v, h,
                                                h_max, max(budget, 1), sub_out, stats,
                                                fixed_step, ws_sub, False)  # fmt: skip
            n_fill = min(int(nd), k_in)
            y_out[done : done + n_fill] = sub_out[:n_fill]
            done += n_fill
            if status != OK:
                break
            events.append((t, comp, new_side))
            if at_sides is not None:
                # every other component from the state: one that changed side twice inside a
                # step (not seen) must not keep a stale branch; such a change is reported here
                g = event_values_at(event, t, y, p, ne)
                for c in range(ne):
                    s_c = float(new_side) if c == comp else (-1.0 if g[c] < 0.0 else 1.0)
                    if c != comp and s_c != sides[c]:
                        events.append((t, c, int(s_c)))
                    sides[c] = s_c
                at_sides(sides.copy())
            resume = False  # RADAU5's workspace holds the uncommitted step: start afresh
            ws = new_ws()
            if h_sub > 0.0:
                h = h_sub
            if terminal[comp]:
                stopped_by = comp
                if done == 0 or tt[done - 1] < t:
                    t_stop_row = (t, y.copy())
                break
            status = MAX_STEPS  # keep going (the budget check below still applies)
        dt = time.perf_counter() - c0
        steps = int(stats[ST_ACCEPTED]) - steps_before
        budget -= steps
        if progress is not None:
            progress(float(t))
        if status != MAX_STEPS or budget <= 0:
            break
        if checkpoint is not None:
            checkpoint(_loop_state(t, y, h, done, budget, stats, ev, ws, resume, events, sides))
        rate = steps / max(dt, 1e-9)
        chunk = int(min(max(rate * chunk_seconds, 1.0), chunk * _MAX_CHUNK_GROWTH))
    wall_s = time.perf_counter() - wall0

    status = int(status)
    t = float(t)
    h = float(h)
    stats_d = {
        "n_accepted": int(stats[ST_ACCEPTED]),
        "n_rejected": int(stats[ST_REJECTED]),
        "n_rhs": int(stats[ST_NRHS]),
        "n_jac": int(stats[ST_NJAC]),
        "n_lu": int(stats[ST_NLU]),
        "rhs_status": int(stats[ST_RHS_STATUS]),
        "n_newton_fail": int(stats[ST_NEWTON_FAIL]),
        "n_chunks": n_chunks,
        "wall_s": wall_s,
        "compile_s": compile_s,
    }
    if method == "radau5":
        stats_d["newton_matrix"] = solver.name
    msg = status_message(status, t, h, stats_d["rhs_status"], stats_d["n_newton_fail"], max_steps)
    # Only rows that were computed are returned; a failed run's unused rows are dropped (copied
    # out so the unused tail of a large buffer is freed).
    # A caller's buffer is returned as a view (it may be a file larger than memory).
    y_res = y_out if done == m else (y_out[:done] if external else y_out[:done].copy())
    t_res = tt[:done].copy()
    if stopped_by is not None:
        msg = f"stopped by terminal event {stopped_by} at t={t!r}"
        if t_stop_row is not None:  # the stop state itself is the last row
            t_res = np.concatenate([t_res, [t_stop_row[0]]])
            if external and done < m:  # the first unreached row of the buffer holds it
                y_out[done] = t_stop_row[1]
                y_res = y_out[: done + 1]
            else:
                y_res = np.concatenate([y_res, t_stop_row[1][None, :]])
    stats_d["n_events"] = len(events)
    return IntegrationResult(
        t=t_res, y=y_res, status=status, message=msg, t_end=t, y_end=y.copy(),
        stats=stats_d, events=tuple(events), stopped_by=stopped_by,
    )  # fmt: skip


def _newton_choice(method, newton):
    """The NewtonSolver of a RADAU5 run (None for the other methods)."""
    if not isinstance(newton, NewtonSolver) and newton not in ("auto", "dense"):
        hint = (" ('structured' is the model's to give: e.g. tetherlab.tether.newton_solver.choose(p, n, "
                "second_order, 'structured'))" if newton == "structured" else "")  # fmt: skip
        raise ValueError(f"newton: expected a NewtonSolver, 'auto' or 'dense'; got {newton!r}{hint}")
    if method != "radau5":
        return None
    if isinstance(newton, NewtonSolver):
        return newton
    return dense("requested" if newton == "dense" else "no structured solver handed in")


def _ws_arrays(ws):
    """The workspace's arrays in order, its tuples (radau5_workspace) expanded; the Newton solver's
    functions at its end are not state."""
    out = []
    for a in ws:
        out.extend(x for x in (a if isinstance(a, tuple) else (a,)) if isinstance(x, np.ndarray))
    return out


def _loop_state(t, y, h, done, budget, stats, ev, ws, resume, events, sides=()) -> dict:
    """Everything :func:`integrate`'s loop carries between kernel calls (copies), for
    ``checkpoint``/``restart``: with ``p`` it determines the rest of the run."""
    return {
        "t": float(t), "h": float(h), "done": int(done), "budget": int(budget), "y": y.copy(),
        "stats": stats.copy(), "ev": ev.copy(), "ws": [a.copy() for a in _ws_arrays(ws)], "resume": bool(resume),
        "events": [tuple(e) for e in events], "sides": [float(x) for x in sides],
    }  # fmt: skip


def _check_breaks(breaks, t0, tt, at_interval, at_sides=None) -> np.ndarray:
    """The breakpoints strictly inside (t0, last output time), sorted, each once (and the two
    callbacks checked)."""
    for name, f in (("at_interval", at_interval), ("at_sides", at_sides)):
        if f is not None and not callable(f):
            raise ValueError(f"{name}: expected a callable or None; got {type(f).__name__}")
    b = _as_vector("breaks", breaks).ravel()
    if not np.all(np.isfinite(b)):
        raise ValueError("breaks: expected finite times; got NaN or Inf")
    b = np.unique(b)
    return np.ascontiguousarray(b[(b > t0) & (b < tt[-1])])


def event_values_at(event, t, y, p, ne) -> np.ndarray:
    """g(t, y) of the event function, called from Python (at the start, at a located event, at a
    breakpoint once per side)."""
    import ctypes

    g = np.zeros(ne)
    yc = np.ascontiguousarray(y, dtype=np.float64)
    P = ctypes.POINTER(ctypes.c_double)
    event.ctypes(float(t), yc.ctypes.data_as(P), g.ctypes.data_as(P), p.ctypes.data_as(P))
    return g


def _check_events(method, event, n_events, terminal):
    if event is None:
        if n_events not in (0, None) or len(terminal):
            raise ValueError(f"event: expected a cfunc when n_events={n_events!r} or terminal "
                             f"is given; got None")  # fmt: skip
        return 0, ()
    if method not in NATIVE_METHODS:
        raise ValueError(f"event: expected None with a scipy method (events are located by the "
                         f"native methods {NATIVE_METHODS}); got an event function with "
                         f"{method!r}")  # fmt: skip
    if not isinstance(event, CFunc) or event._sig != RHS_SIG:
        raise ValueError(f"event: expected a numba cfunc with signature {RHS_SIG}; got "
                         f"{getattr(event, '_sig', None) or type(event).__name__}")  # fmt: skip
    if isinstance(n_events, bool) or not isinstance(n_events, numbers.Integral) or n_events < 1:
        raise ValueError(f"n_events: expected an integer >= 1 with an event function; got "
                         f"{n_events!r}")  # fmt: skip
    term = tuple(bool(x) for x in terminal)
    if len(term) not in (0, n_events):
        raise ValueError(f"terminal: expected {n_events} flags (one per event component) or "
                         f"none; got {len(term)}")  # fmt: skip
    return int(n_events), term or (False,) * int(n_events)
