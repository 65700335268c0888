"""Where the Stiefel-Scheifele time goes: tetherlab's DROMO sigma form with Vern9 against heyoka,
per right-hand-side call, per step and per Taylor order (issue 12; docs/integrators.md section 8).

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
* ``step_overhead_ns``: Vern9's own work per step (stage sums, solution, error norm, controller,
  bookkeeping) measured with a trivial 8-component rhs (dy = -y) and that rhs's calls subtracted;
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


def _rhs_probe(case: str, n_calls: int = 20_000):
    """A zero-argument function making n_calls chained DROMO sigma rhs calls with the case's
    effects, and n_calls."""
    from ..formulations import dromo
    from ..kernel.layout import FORM_DROMO_SIGMA
    from ..pipeline import prepare
    from ..scene import load_scene

    prep = prepare(load_scene(S.CASES[case][0]).replace(**{"integrator.method": "vern9",
                                                             "output.count": 2}))  # fmt: skip
    h = prep.y0.size // 2
    L = float(np.linalg.norm(prep.y0[:3]))
    p = dromo.attach(prep.model.fresh_params(), FORM_DROMO_SIGMA, prep.mu_m3_s2, L, prep.y0.size)
    z0 = np.concatenate([[0.0], dromo.cartesian_to_dromo(prep.y0[:3], prep.y0[h : h + 3], prep.mu_m3_s2, L)])
    dsig = 100.0 * np.pi / n_calls  # sigma over 50 revolutions: the run's trigonometric arguments
    _rhs_chain(dromo.dromo_sigma_rhs, z0, p, 10, dsig)
    return (lambda: _rhs_chain(dromo.dromo_sigma_rhs, z0, p, n_calls, dsig)), n_calls


def _overhead_probes():
    """(Vern9 run of the trivial rhs, its rhs calls, its steps; chained trivial rhs calls, count)."""
    stats = _vern9_trivial(_trivial_rhs, 1000.0, 1e-12)
    z0 = np.ones(8)
    p = np.zeros(4)
    _rhs_chain(_trivial_rhs, z0, p, 10, 1e-6)
    n = int(stats[ST_NRHS])
    return ((lambda: _vern9_trivial(_trivial_rhs, 1000.0, 1e-12)), n, int(stats[ST_ACCEPTED] + stats[ST_REJECTED]),
            (lambda: _rhs_chain(_trivial_rhs, z0, p, n, 1e-6)))  # fmt: skip


def _fit(x, err):
    x, err = np.asarray(x, float), np.asarray(err, float)
    m = np.isfinite(err) & (err >= 1e-4) & (err <= 1e3)
    if m.sum() < 3:
        return None
    return float(np.polyfit(np.log(1.0 / err[m]), np.log(x[m]), 1)[0])


def run(case: str = "ex2", repeats: int = 21) -> list[dict]:
    ref = S.reference_position_m(case)
    tl = []
    for tol in S.TOLS:
        f = S.runner("dromo", "vern9", tol, case)
        r, st = f()
        tl.append({"tol": tol, "run": f, "error_m": float(np.linalg.norm(r - ref)), "n_rhs": st["n_rhs"],
                   "steps": st["n_accepted"] + st["n_rejected"]})  # fmt: skip
    hk = S.heyoka_rows(case=case)
    rhs_probe, n_probe = _rhs_probe(case)
    v9_probe, v9_rhs, v9_steps, triv_probe = _overhead_probes()
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
            "case": case, "target_m": target, "tl_tol": a["tol"], "tl_error_m": a["error_m"],
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
