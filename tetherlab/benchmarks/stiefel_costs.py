"""Where the Stiefel-Scheifele time goes: tetherlab's pick (:data:`PICKS`: DROMO sigma form with
Vern9 on Example 2, with the linear time element and ABM on Example 1) against heyoka, per
right-hand-side call, per step and per Taylor order (docs/integrators.md section 8).

For each case (Example 2, J2 + Moon; Example 1, J2 only) and target final error (1 m, 1 mm), the
loosest tolerance of the bench grid (:data:`.stiefel.TOLS`, :data:`.stiefel.HEYOKA_TOLS`) that
reaches the target is taken for each side, as ``--only stiefel`` does, and the two runs are timed
alternately, then the probes below alternately right after (minimum of ``repeats`` each; the
machine has 2 shared cores, so absolute times move with its load: compare within a row).
Beside the wall times:

* ``rhs_ns``: one evaluation of the DROMO sigma right-hand side (:func:`dromo_sigma_rhs`) with
  the scene's effects, measured as a *dependent chain* (each call's input is built from the
  previous call's output, as the stages of a Runge-Kutta step are): its latency, which is what a
  step pays 16 times in sequence;
* ``step_overhead_ns``: the method's own work per step (Vern9: stage sums, solution, error norm,
  controller, bookkeeping; ABM: the two history sums, error norm, ring update) measured with a
  trivial 8-component rhs (dy = -y) and that rhs's calls subtracted;
* ``glue_ms``: the driver call minus the compiled loop (set-up, conversions, the dispatch);
* ``floor_ratio``: n_rhs x rhs_ns / heyoka's wall: the ratio tetherlab would have if step
  overhead and glue were zero and the rhs kept its latency -- how far constant factors outside
  the rhs can take it;
* heyoka: steps, Taylor order, wall per step and per (step x order).

The trend over the problem's size here is over accuracy: the last rows fit n_rhs ~ error^-x
(tetherlab) and steps x order ~ error^-x (heyoka) over the tolerance grid, 1e-4 m <= error <= 1e3 m.
"""

from __future__ import annotations

import numpy as np
from numba import carray

from .._jit import njit, ptr, rhs_cfunc
from ..integrators.common import ST_ACCEPTED, ST_NRHS, ST_REJECTED
from ..integrators.erk import VERN9, erk_core
from . import stiefel as S


@rhs_cfunc
def _trivial_rhs(t, y_ptr, dy_ptr, p_ptr):
    """dy = -y on 8 components: a right-hand side of negligible cost (the step-overhead probe)."""
    y = carray(y_ptr, (8,))
    dy = carray(dy_ptr, (8,))
    for i in range(8):
        dy[i] = -y[i]
    return 0


@njit(cache=True)
def _rhs_chain(rhs, z0, p, n_calls, dsig):
    """n_calls evaluations, each one's state built from the previous one's output (latency)."""
    ys = z0.copy()
    dy = np.empty(z0.shape[0])
    for k in range(n_calls):
        rhs(k * dsig, ptr(ys), ptr(dy), ptr(p))
        for i in range(z0.shape[0]):
            ys[i] = z0[i] + 1e-30 * dy[i]
    return ys[1]


@njit(cache=True)
def _vern9_trivial(rhs, t_end, rtol):
    """A Vern9 run of the trivial rhs to t_end; returns the statistics array."""
    y = np.ones(8)
    t_out = np.array([t_end])
    y_out = np.empty((1, 8))
    stats = np.zeros(8, dtype=np.int64)
    ev = np.array([0.0, -1.0, -1.0, 0.0])
    p = np.zeros(4)
    erk_core(VERN9, rhs, 0.0, y, t_out, p, rtol, np.full(8, rtol), 0.0, 0.0, 10**9, y_out, stats,
             False, rhs, 0, ev)  # fmt: skip
    return stats


def _rhs_probe(case: str, n_calls: int = 20_000, time_element: str = "none"):
    """A zero-argument function making n_calls chained DROMO sigma rhs calls with the case's
    effects (and the sigma form's time variable), and n_calls."""
    from ..formulations import dromo
    from ..model.params import FORM_DROMO_SIGMA
    from ..pipeline import prepare
    from ..scene import load_scene

    prep = prepare(load_scene(S.CASES[case][0]).replace(**{"integrator.method": "vern9",
                                                             "output.count": 2}))  # fmt: skip
    lay = prep.model.state
    L = float(np.linalg.norm(prep.y0[:3]))
    te = dromo.TIME_ELEMENTS[time_element]
    p = dromo.attach(prep.model.fresh_params(), FORM_DROMO_SIGMA, prep.mu_m3_s2, L, prep.y0.size, te)
    z0 = dromo.sigma_state(prep.y0[:3], prep.y0[lay.root_v], prep.mu_m3_s2, L, 0.0, 0.0, te)
    dsig = 100.0 * np.pi / n_calls  # sigma over 50 revolutions: the run's trigonometric arguments
    _rhs_chain(dromo.dromo_sigma_rhs, z0, p, 10, dsig)
    return (lambda: _rhs_chain(dromo.dromo_sigma_rhs, z0, p, n_calls, dsig)), n_calls


def _abm_trivial(rhs, n_steps):
    """A constant-step ABM (k = 12) run of the trivial rhs over n_steps steps; returns the
    statistics array."""
    import math

    from ..integrators import abm

    ws = abm.workspace(8)
    stats = np.zeros(8, dtype=np.int64)
    h = 1e-3
    abm.abm_core(rhs, 0.0, np.ones(8), h, abm.DEFAULT_ORDER, ws["F"], ws["S"], -1, np.zeros(4), 1e-12,
                 np.full(8, 1e-12), (n_steps + abm.DEFAULT_ORDER) * h, -1, 0.0, 2 * math.pi, 10**9, False,
                 stats, ws["K"], ws["w"], ws["fix"], rhs, False)  # fmt: skip
    return stats


def _overhead_probes(method: str = "vern9"):
    """(the method's run with the trivial rhs, its rhs calls, its steps; chained trivial rhs calls,
    count): Vern9 to t = 1000 at 1e-12, or 5 000 constant ABM steps."""
    if method == "abm":
        def run():
            return _abm_trivial(_trivial_rhs, 5000)
    else:
        def run():
            return _vern9_trivial(_trivial_rhs, 1000.0, 1e-12)
    stats = run()
    z0 = np.ones(8)
    p = np.zeros(4)
    _rhs_chain(_trivial_rhs, z0, p, 10, 1e-6)
    n = int(stats[ST_NRHS])
    return (run, n, int(stats[ST_ACCEPTED] + stats[ST_REJECTED]), (lambda: _rhs_chain(_trivial_rhs, z0, p, n, 1e-6)))


def _fit(x, err):
    x, err = np.asarray(x, float), np.asarray(err, float)
    m = np.isfinite(err) & (err >= 1e-4) & (err <= 1e3)
    if m.sum() < 3:
        return None
    return float(np.polyfit(np.log(1.0 / err[m]), np.log(x[m]), 1)[0])


#: the method profiled per case: the bench's pick (``--only stiefel``; docs/dromo.md section 11)
PICKS = {"ex2": ("dromo", "vern9"), "ex1": ("dromo+te", "abm")}


def run(case: str = "ex2", repeats: int = 21, formulation: str | None = None, method: str | None = None) -> list[dict]:
    formulation = formulation or PICKS[case][0]
    method = method or PICKS[case][1]
    ref = S.reference_position_m(case)
    tl = []
    for tol in S.TOLS:
        f = S.runner(formulation, method, tol, case)
        r, st = f()
        tl.append({"tol": tol, "run": f, "error_m": float(np.linalg.norm(r - ref)), "n_rhs": st["n_rhs"],
                   "steps": st["n_accepted"] + st["n_rejected"]})  # fmt: skip
    hk = S.heyoka_rows(case=case)
    rhs_probe, n_probe = _rhs_probe(case, time_element="linear" if formulation == "dromo+te" else "none")
    v9_probe, v9_rhs, v9_steps, triv_probe = _overhead_probes(method)
    rows = []
    for target in S.TARGETS_M:
        a = S._loosest(tl, target)
        b = S._loosest(hk, target)
        if a is None or b is None:
            rows.append({"case": case, "target_m": target, "note": "not reached by both on the grid"})
            continue
        kern = []

        def run_tl():
            kern.append(a["run"]()[1]["wall_s"])

        # the two runs alternately (as --only stiefel), then the probes alternately, right after:
        # probes interleaved with the runs evict the runs' caches and predictors (measured: the
        # glue tripled), so they get their own round robin
        load_before = S._load()
        (w_tl, w_hy), _ = S._round_robin([run_tl, b["run"]], repeats)
        (w_rhs, w_v9, w_triv), _ = S._round_robin([rhs_probe, v9_probe, triv_probe], repeats)
        k_min = min(kern)
        rhs_ns = w_rhs / n_probe * 1e9
        ovh_ns = (w_v9 - w_triv) / v9_steps * 1e9
        rows.append({
            "case": case, "target_m": target, "tl_method": f"{formulation} {method}", "tl_tol": a["tol"], "tl_error_m": a["error_m"],
            "tl_n_rhs": a["n_rhs"], "tl_steps": a["steps"], "rhs_ns": rhs_ns, "step_overhead_ns": ovh_ns,
            "tl_wall_ms": w_tl * 1e3, "tl_kernel_ms": k_min * 1e3, "glue_ms": (w_tl - k_min) * 1e3,
            "rhs_share": a["n_rhs"] * rhs_ns * 1e-9 / k_min,
            "hy_tol": b["tol"], "hy_error_m": b["error_m"], "hy_steps": b["steps"], "hy_order": b["order"],
            "hy_wall_ms": w_hy * 1e3, "hy_us_per_step": w_hy / b["steps"] * 1e6,
            "hy_ns_per_step_order": w_hy / (b["steps"] * b["order"]) * 1e9,
            "ratio": w_tl / w_hy, "floor_ratio": a["n_rhs"] * rhs_ns * 1e-9 / w_hy,
            "load_avg": f"{load_before:.2f} -> {S._load():.2f}",
        })  # fmt: skip
    rows.append({"case": case, "target_m": "trend",
                 "note": f"n_rhs ~ error^-x, x = {_fit([r['n_rhs'] for r in tl], [r['error_m'] for r in tl])}; "
                         f"heyoka steps x order ~ error^-x, x = "
                         f"{_fit([r['steps'] * r['order'] for r in hk], [r['error_m'] for r in hk])}"})  # fmt: skip
    return rows


def bench_rows() -> list[dict]:
    """``make bench`` entry (section ``stiefel_costs``): both cases."""
    rows = run("ex2") + run("ex1")
    keys = []
    for r in rows:
        keys += [k for k in r if k not in keys]
    return [{k: r.get(k, "") for k in keys} for r in rows]


if __name__ == "__main__":
    for r in bench_rows():
        print(r)
