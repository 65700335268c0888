"""The bordered structured Newton matrix of RADAU5 for scenes with rigid bodies (
docs/integrators.md section 13).

* The bordered solve (tether solve S_t + Schur complement on the attitude and wheel unknowns w)
  equals a dense LU solve of the same bordered matrix, assembled here in numpy: the tether block
  from S_t's columns, the border from the finite-difference columns A_w, B_w and the directional
  differences B_qv applied to unit vectors (real and complex shift), to round-off once the
  forward difference's non-linearity on the very vectors the solve applied it to is accounted
  (without it they differ by up to 1e-6, the difference error).
* Negative control: with B_w dropped from the border the solve no longer agrees.
* Whole runs with newton="structured" and newton="dense" agree within the tolerance on the rigid
  scenes of studies/scenes (shortened, a few rods), on a hub spinning with four tethers attached
  off its centre, and on tests/test_rigid.py's tree (a rigid tip body carrying a further tether).
* newton="auto" takes the bordered matrix for rigid scenes from AUTO_BORDERED_MIN_RODS rods on.

Scenes: rigid-example (wheels, PD control), deorbit-ed-rigid, hub-spoke-spin (structure: one root).
"""

from __future__ import annotations

import numpy as np
import pytest

from tetherlab.formulations.cowell import cowell_rhs
from tetherlab.integrators import radau5 as r5
from tetherlab.integrators.driver import integrate
from tetherlab.pipeline import prepare
from tetherlab.scene import load_scene
from tetherlab.tether import newton as nw
from tetherlab.tether.newton_solver import KERNELS, choose

from tests.helpers import assert_runs_agree, dense_and_structured_runs
from tests.helpers import ROOT

# RADAU5's two shifts at h = 0.5 s (U1/h and (ALPH + i BETA)/h)
G_REAL = 3.6378342527444962 / 0.5
G_CPLX = complex(2.6810828736277523, 3.0504301992474105) / 0.5


def _prep(name, rods, duration):
    if name == "rigid-tree":
        # tests/test_rigid.py's tree: a rigid root with a wheel, a rigid tip body with a wheel
        # carrying a further tether, a reversed tether, every attachment off the centres
        from tests.test_rigid import rigid_tree_scene

        return prepare(rigid_tree_scene().replace(duration=duration))
    if name == "rigid-forest":
        # tests/test_newton_forest.py's forest with both a free rigid body (a wheel) and the second
        # tree's root rigid, its tether attached off its centre: the border over several roots
        from tests.test_newton_forest import forest_scene

        return prepare(forest_scene(duration=duration, free="rigid", h2_rigid=True))
    sc = load_scene(ROOT / "studies" / "scenes" / f"{name}.toml")
    if name == "hub-spoke-spin":  # four tethers on a hub spinning at 0.1 rad/s, attached 1 m off its centre
        return prepare(sc.replace(duration=duration, **{f"tethers.s{k}.rods": rods for k in range(1, 5)}))
    return prepare(sc.replace(**{"tethers.main.rods": rods, "duration": duration}))


def _state(prep, seed=3):
    """The scene's start with the rods' velocities and the body rates off the rigid motion, so
    every block of the Jacobian is exercised."""
    rng = np.random.default_rng(seed)
    y = prep.y0.copy()
    m1 = prep.model.n_qt
    y[m1 + 3 : 2 * m1] += rng.normal(size=m1 - 3) * 0.01
    y[2 * m1 + 4 : 2 * m1 + 7] += rng.normal(size=3) * 1e-3  # the first rigid body's rates
    return y


def _bordered(prep, y, drop_bw=False):
    """(the bordered solve (g, fac, b) -> (x, its w-row non-linearity term), the dense bordered
    matrix as a function of (g, fac), the real and complex factor arrays, n_w)."""
    p = prep.model.fresh_params()
    n = y.size
    m1 = prep.model.n_qt
    n2 = 2 * m1
    nb = n - n2
    assert nw.structure_supported(p, n, m1) == ""
    blk, f1, f2 = nw.workspace(p)
    assert nw.rod_blocks(y, p, m1, blk) == 0
    stats = np.zeros(8, dtype=np.int64)
    bcol = np.zeros((n, nb))
    bw = np.zeros((r5._B_ROWS, n))
    assert r5._border_jacobian(cowell_rhs, 0.0, y.copy(), p, m1, nb, bcol, bw, stats) == 0

    def bfd(v):
        """The kernel's directional difference B_qv v (real and imaginary parts apart)."""
        out = np.zeros(nb, dtype=v.dtype)
        for part, unit in ((v.real, 1.0), (v.imag, 1j)):
            if np.any(part != 0.0):
                bw[r5._B_XR, :] = 0.0
                bw[r5._B_XR, :n2] = part[:n2]
                r5._border_dir(cowell_rhs, 0.0, p, m1, nb, bw, r5._B_XR, r5._B_OR, stats)
                out = out + unit * bw[r5._B_OR, :nb]
        return out

    # B_qv by the same directional differences, applied to the unit vectors of (q, v)
    bqv = np.zeros((nb, n2))
    for k in range(n2):
        bqv[:, k] = bfd(np.eye(n2)[k])
    aw = bcol[m1:n2, :].copy()
    bww = bcol[n2:, :].copy()
    if drop_bw:
        bcol[n2:, :] = 0.0  # the deliberate defect of the negative control

    def dense(g, fac):
        assert nw.factor(p, blk, g, fac) == 0
        cols = np.zeros((n2, n2), dtype=fac.dtype)
        for k in range(n2):  # S_t's columns: the tether block's inverse
            e = np.zeros(n2, dtype=fac.dtype)
            e[k] = 1.0
            nw.solve(p, blk, g, fac, m1, e)
            cols[:, k] = e
        a = np.zeros((n, n), dtype=fac.dtype)
        a[:n2, :n2] = np.linalg.inv(cols)
        a[m1:n2, n2:] = -aw
        a[n2:, :n2] = -bqv
        a[n2:, n2:] = g * np.eye(nb) - bww
        return a

    def solve(g, fac, b):
        iu = 0.0 if fac.dtype == np.float64 else 1j
        bz = np.zeros((nb, n), dtype=fac.dtype)
        bs = np.zeros((nb, nb), dtype=fac.dtype)
        bp = np.zeros(nb, dtype=np.int64)
        assert nw.factor(p, blk, g, fac) == 0
        solve_fn = KERNELS[3] if fac.dtype == np.float64 else KERNELS[4]  # the handed-in solve of this type
        assert r5._border_factor(cowell_rhs, 0.0, p, blk, m1, nb, g, fac, solve_fn, bcol, bz, bs, bp, bw, iu,
                                 stats) == 0  # fmt: skip
        x = b.astype(fac.dtype)
        z0 = x.copy()
        nw.solve(p, blk, g, fac, m1, z0)
        r5._lin(True, np.zeros((1, 1), dtype=fac.dtype), bp, np.zeros((1, 1)), g, m1, x, p, blk, fac,
                solve_fn, cowell_rhs, nb, bz, bs, bp, bw, 0.0, iu, stats)  # fmt: skip
        # the forward difference is not exactly linear: the w rows of the dense system at x are
        # off by e(z0) + sum_j x_w,j e(z^j), e(v) = B_qv(v) - (unit-vector assembly) v, on the
        # very vectors the solve applied it to (algebra of docs/integrators.md section 13)
        e = lambda v: bfd(v) - bqv @ v[:n2]  # noqa: E731
        r_w = e(z0) + sum(x[n2 + j] * e(bz[j]) for j in range(nb))
        return x, r_w

    return solve, dense, (f1, f2), nb


def _mismatch(prep, y, drop_bw=False, seed=5):
    """Per shift (real, complex): (relative residual of the tether rows of the dense bordered
    system at the bordered solution, relative difference of the bordered solution from the dense
    LU solution of the system whose w rows carry the forward difference's known non-linearity)."""
    solve, dense, (f1, f2), nb = _bordered(prep, y, drop_bw)
    n2 = y.size - nb
    rng = np.random.default_rng(seed)
    out = []
    for g, fac in ((G_REAL, f1), (G_CPLX, f2)):
        b = rng.normal(size=y.size) * (1.0 if fac is f1 else 1.0 + 0.5j)
        x, r_w = solve(g, fac, b)
        a = dense(g, fac)
        res_t = np.max(np.abs((a @ x - b)[:n2])) / (np.max(np.abs(a[:n2])) * np.max(np.abs(x)))
        xd = np.linalg.solve(a, b + np.concatenate([np.zeros(n2), r_w]))
        out.append((res_t, np.max(np.abs(x - xd)) / np.max(np.abs(xd))))
    return out


@pytest.mark.parametrize("scene", ["rigid-example", "deorbit-ed-rigid", "rigid-tree", "hub-spoke-spin",
                                   "rigid-forest"])
def test_bordered_solve_equals_dense_lu(scene):
    prep = _prep(scene, 4, "10 s")
    for res_t, rel in _mismatch(prep, _state(prep)):
        # The tether rows involve no finite difference: (q, v) = z0 + sum_j z_w,j z^j with
        # E_tt z0 = b_t and E_tt z^j = A_w e_j exactly, so their residual is round-off
        # (cond(E_tt) ~ 1e3 times eps ~ 2e-13; bound with a factor 50 of margin).
        assert res_t <= 1e-11
        # The w rows hold B_qv, a forward difference along the vector it is applied to, which is
        # linear only to its truncation error (relative ~ sqrt(eps) = 1.5e-8; without the term
        # r_w the two solutions differ by 4e-13 ... 1e-6 on these scenes).  With that known term
        # the bordered solve is the exact solution of the dense system: round-off (measured
        # 3e-16 ... 4e-15; bound 1e-10 leaves room for the condition of other states).
        assert rel <= 1e-10


def test_bordered_solve_without_b_w_disagrees():
    # negative control: the same comparison with the border's w-w block B_w dropped from the
    # solve (the dense matrix keeps it) must fail the bound above by orders of magnitude
    prep = _prep("rigid-example", 4, "10 s")
    for _, rel in _mismatch(prep, _state(prep), drop_bw=True):
        assert rel > 1e-4


@pytest.mark.parametrize("scene, rods, duration", [("rigid-example", 4, "60 s"), ("deorbit-ed-rigid", 4, "600 s"),
                                                    ("rigid-tree", 0, "20 s"), ("hub-spoke-spin", 4, "20 s")])
def test_structured_and_dense_runs_agree(scene, rods, duration):
    # Budget (tests/helpers.assert_runs_agree): the sum of both runs' mapped local tolerances over
    # their steps.  Measured: at most 3e-3 of it on the four scenes; the rod vectors agree to
    # 2.4e-10 ... 5.3e-7 m.
    prep = _prep(scene, rods, duration)
    assert_runs_agree(prep, dense_and_structured_runs(prep, prep.model.n_qt))


def test_auto_takes_the_bordered_matrix_from_its_rod_count():
    # newton_solver.AUTO_BORDERED_MIN_RODS (docs/integrators.md section 13: measured slower below it)
    from tetherlab.tether import newton_solver

    for rods, kind in ((4, "dense"), (newton_solver.AUTO_BORDERED_MIN_RODS, "structured")):
        prep = _prep("deorbit-ed-rigid", rods, "10 s")
        m1 = prep.model.n_qt
        solver = newton_solver.choose(prep.model.fresh_params(), prep.y0.size, m1)
        assert solver.name.startswith(kind) and solver.structured == (kind == "structured")
    # forests are structured too (tests/test_newton_forest.py); a root count that does not match
    # the state's layout (set to 2 on a copy: q has one root block) is refused with the reason
    from tetherlab.model.params import ParamView

    p = prep.model.fresh_params()
    ParamView(p).n_roots = 2
    assert "is not the Cowell layout" in nw.structure_supported(p, prep.y0.size, m1)


def test_bordered_run_restarts_bit_for_bit():
    # The border's arrays and its base time are part of RADAU5's workspace (the driver's
    # checkpoint holds them), so a run continued from a checkpoint reproduces the uninterrupted
    # one exactly (driver.integrate's contract).
    prep = _prep("rigid-example", 4, "30 s")
    m1 = prep.model.n_qt
    states = []
    args = ("radau5", cowell_rhs, 0.0, prep.y0, prep.t_out)
    kw = dict(h_max=prep.h_max, max_steps=prep.max_steps, second_order=m1,
              newton=choose(prep.model.fresh_params(), prep.y0.size, m1, "structured"))
    full = integrate(*args, prep.model.fresh_params(), prep.rtol, prep.atol, checkpoint=states.append, **kw)
    assert full.status == 0 and len(states) >= 1  # a chunk ends after 64 steps (~5 s of 30 s)
    mid = states[len(states) // 2]
    cont = integrate(*args, prep.model.fresh_params(), prep.rtol, prep.atol, restart=mid, **kw)
    assert cont.status == 0
    assert np.array_equal(cont.y_end, full.y_end)
    assert cont.stats["n_accepted"] == full.stats["n_accepted"]
