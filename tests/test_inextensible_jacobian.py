"""The Jacobian of the inextensible chain's accelerations, derived in docs/inextensible.md section 8
(a constant bar mass matrix in joint coordinates, the geometric stiffness of the multipliers and
the linearised stabilised constraint, bordered), against central differences of the compiled rhs.

This checks the equations an O(n) Newton matrix for RADAU5 is to be built from; the assembly here
is dense (numpy), written from the document and independent of the kernels."""

from __future__ import annotations

import math

import numpy as np

import tetherlab
from tetherlab.formulations.cowell import cowell_rhs_py
from tetherlab.pipeline import prepare
from tests.helpers import SCENES

SQ3 = math.sqrt(3.0)
N_RODS = 8
RATE = 0.7  # 1/s, the Baumgarte rate a: not 1, so that its terms are told apart
LINE_KG = 1.0
TIP_KG = 0.5
LENGTH_M = 10.0
G = np.array([0.0, 0.0, -9.80665])  # the scene's uniform gravity


def _state(seed):
    """The hanging chain (studies/scenes/hanging-chain.toml), inextensible, at a random state off
    the constraint: every rod turned and stretched by ~5 %, random rates of ~0.3 m/s."""
    s = tetherlab.load_scene(SCENES / "hanging-chain.toml").replace(**{
        "tethers.main.model": "inextensible", "integrator.method": "vern9", "tethers.main.rods": N_RODS,
        "tethers.main.constraint_rate": f"{RATE} 1/s"})  # fmt: skip
    prep = prepare(s)
    y = prep.y0.copy()
    m1 = y.size // 2
    rng = np.random.default_rng(seed)
    h = LENGTH_M / N_RODS / (2 * SQ3)
    y[3:m1] += rng.normal(size=3 * N_RODS) * 0.05 * h
    y[m1 + 3 :] += rng.normal(size=3 * N_RODS) * 0.3
    return prep.model, y


def _derived_jacobian(y, f):
    """A_q = d(d'')/dd, A_v = d(d'')/dd' over the rods (the nail fixed) from section 8: joints x_j,
    M x'' + G^T nu = F (M the uniform bars' consistent mass, m/3 and m/6, plus the tip), nu from the
    accelerations f of the rhs, and the linearisation
        M y + G^T dnu = -K dx,    G y = -E dx - F_v dv."""
    n = N_RODS
    m1 = y.size // 2
    m = LINE_KG / n
    # joints 1..n from the rods' d (x_0, the nail, fixed): x_j = x_{j-1} + 2 sqrt3 d_j
    T = np.kron(np.tril(np.ones((n, n))), 2 * SQ3 * np.eye(3))
    x, xd, xdd = T @ y[3:m1], T @ y[m1 + 3 :], T @ f[m1 + 3 :]

    def rod(v, i):  # D_i = x_i - x_{i-1} of a joint vector (x_0 = 0)
        return v[3 * i - 3 : 3 * i] - (v[3 * i - 6 : 3 * i - 3] if i > 1 else 0.0)

    def blk(i):
        return slice(3 * i - 3, 3 * i)

    M = np.zeros((3 * n, 3 * n))
    Gm = np.zeros((n, 3 * n))
    K = np.zeros((3 * n, 3 * n))
    E = np.zeros((n, 3 * n))
    Fv = np.zeros((n, 3 * n))
    lump = np.full(n, m)
    lump[-1] = m / 2 + TIP_KG
    F = (lump[:, None] * G[None, :]).ravel()  # uniform gravity: each joint half of its rods' weight
    D = [rod(x, i) for i in range(1, n + 1)]
    ell = [np.linalg.norm(v) for v in D]
    U = [v / e for v, e in zip(D, ell)]
    for i in range(1, n + 1):
        M[blk(i), blk(i)] += m / 3 * np.eye(3)
        Gm[i - 1, blk(i)] = U[i - 1]
        if i > 1:
            M[blk(i - 1), blk(i - 1)] += m / 3 * np.eye(3)
            M[blk(i), blk(i - 1)] = M[blk(i - 1), blk(i)] = m / 6 * np.eye(3)
            Gm[i - 1, blk(i - 1)] = -U[i - 1]
    M[blk(n), blk(n)] += TIP_KG * np.eye(3)
    # the multipliers of the constant-mass form, from the rhs's own accelerations (3n equations for n
    # unknowns: their residual checks M and F)
    nu, *_ = np.linalg.lstsq(Gm.T, F - M @ xdd, rcond=None)
    resid = np.linalg.norm(Gm.T @ nu - (F - M @ xdd)) / np.linalg.norm(F)
    for i in range(1, n + 1):
        u, e = U[i - 1], ell[i - 1]
        k = nu[i - 1] / e * (np.eye(3) - np.outer(u, u))
        Dd, Ddd = rod(xd, i), rod(xdd, i)
        E[i - 1, blk(i)] = (Ddd + 2 * RATE * Dd + RATE**2 * D[i - 1]) / e
        Fv[i - 1, blk(i)] = 2 * (Dd + RATE * D[i - 1]) / e
        K[blk(i), blk(i)] += k
        if i > 1:
            E[i - 1, blk(i - 1)] = -E[i - 1, blk(i)]
            Fv[i - 1, blk(i - 1)] = -Fv[i - 1, blk(i)]
            K[blk(i - 1), blk(i - 1)] += k
            K[blk(i), blk(i - 1)] -= k
            K[blk(i - 1), blk(i)] -= k
    kkt = np.block([[M, Gm.T], [Gm, np.zeros((n, n))]])
    ax = np.linalg.solve(kkt, np.vstack([-K, -E]))[: 3 * n]
    av = np.linalg.solve(kkt, np.vstack([np.zeros((3 * n, 3 * n)), -Fv]))[: 3 * n]
    Ti = np.linalg.inv(T)
    return Ti @ ax @ T, Ti @ av @ T, resid, (T, M, Gm, K, E, Fv)


def test_derived_jacobian_matches_central_differences_of_the_rhs():
    model, y = _state(3)
    m1 = y.size // 2
    f0 = cowell_rhs_py(model, y)
    aq, av, resid, _ = _derived_jacobian(y, f0)
    # the constant-mass form reproduces the rhs's accelerations: round-off of sums of ~10 N forces
    assert resid < 1e-11
    jq = np.empty((3 * N_RODS, 3 * N_RODS))
    jv = np.empty_like(jq)
    for c in range(3 * N_RODS):
        for j, out, step in ((3 + c, jq, 1e-5 * max(1.0, abs(y[3 + c]))), (m1 + 3 + c, jv, 1e-4)):
            yp, ym = y.copy(), y.copy()
            yp[j] += step
            ym[j] -= step
            out[:, c] = (cowell_rhs_py(model, yp)[m1 + 3 :] - cowell_rhs_py(model, ym)[m1 + 3 :]) / (2 * step)
    # Budget (relative to the largest entry): the rhs of a state ~5 % off its length carries the
    # elastic stand-in's 2 EA eps ~ 1e6 N, added and removed (tether/inextensible.py), so its
    # accelerations have round-off ~ eps 1e6 N / m ~ 2e-9 m/s^2; over the 2 x 1e-5 difference that is
    # ~1e-4 1/s^2 against entries of ~200 1/s^2 (5e-7), times the rods' sums (~8); the difference's
    # truncation (step/|d|)^2 ~ 1e-9.  Bound 1e-5.  (Measured: 1.8e-6 at this step, and 2.9e-5,
    # 1.2e-4 at steps 10 and 100 times smaller, the growth of round-off.)
    assert np.max(np.abs(jq - aq)) <= 1e-5 * np.max(np.abs(jq))
    assert np.max(np.abs(jv - av)) <= 1e-5 * np.max(np.abs(jv))
    # the stiffness of the multipliers is what the Newton matrix is for: it is no small part here
    assert np.max(np.abs(aq)) > 10.0


def test_bordered_newton_system_solves_radau5s_systems():
    """(J3) of docs/inextensible.md 8, the system the O(n) factorisation is to solve, assembled
    densely in joint coordinates: its solution is (g I - J)^-1 b with J = [[0, I], [A_q, A_v]] of
    (J2), for a real and a complex shift of RADAU5's sizes (g ~ 1/h, h = 0.1 s)."""
    model, y = _state(5)
    m1 = y.size // 2
    aq, av, _, (T, M, Gm, K, E, Fv) = _derived_jacobian(y, cowell_rhs_py(model, y))
    nq = 3 * N_RODS
    jac = np.block([[np.zeros((nq, nq)), np.eye(nq)], [aq, av]])
    rng = np.random.default_rng(11)
    for g in (36.0, 27.0 + 16.0j):
        b = rng.normal(size=2 * nq) + (1j * rng.normal(size=2 * nq) if isinstance(g, complex) else 0.0)
        z = np.linalg.solve(g * np.eye(2 * nq) - jac, b)
        bq, bv = T @ b[:nq], T @ b[nq:]
        lhs = np.block([[g * M + K / g, Gm.T], [g * Gm + E / g + Fv, np.zeros((N_RODS, N_RODS))]])
        w = np.linalg.solve(lhs, np.concatenate([M @ bv - K @ bq / g, Gm @ bv - E @ bq / g]))[:nq]
        zv = np.linalg.solve(T, w)
        zq = (b[:nq] + zv) / g
        # two dense solves of matrices of condition ~6e2 (measured 593 and 605): round-off ~1e-13 of |z|
        assert np.max(np.abs(zv - z[nq:])) <= 1e-10 * np.max(np.abs(z))
        assert np.max(np.abs(zq - z[:nq])) <= 1e-10 * np.max(np.abs(z))


def test_structured_kernel_solves_radau5s_systems():
    """tether/newton_inextensible.py (form by one rhs call, 4x4 block Thomas, solve) against a
    dense solve of (g I - J) with J of the derived Jacobian, real and complex shift."""
    from tetherlab.tether import newton_inextensible as ni

    model, y = _state(5)
    m1 = y.size // 2
    p = model.fresh_params()
    assert ni.structure_supported(p, y.size, True) == ""
    aq, av, _, _ = _derived_jacobian(y, cowell_rhs_py(model, y))
    jac = np.zeros((2 * m1, 2 * m1))
    jac[:m1, m1:] = np.eye(m1)
    jac[m1 + 3 :, 3:m1] = aq
    jac[m1 + 3 :, m1 + 3 :] = av
    blk, fr, fc = ni.workspace(p)
    assert ni.form_blocks(0.0, y, p, m1, blk) == 0
    rng = np.random.default_rng(1)
    for g, fac in ((36.0, fr), (27.0 + 16.0j, fc)):
        assert ni.factor(p, blk, g, fac) == 0
        b = rng.normal(size=2 * m1) + (1j * rng.normal(size=2 * m1) if fac is fc else 0.0)
        z = np.linalg.solve(g * np.eye(2 * m1) - jac, b)
        ni.solve(p, blk, g, fac, m1, b)
        # condition ~6e2 (above) times round-off: measured 2.9e-12 and 1.8e-12
        assert np.max(np.abs(b - z)) <= 1e-10 * np.max(np.abs(z))


def _kernel_against_differences(rhs, p, y, steps, shifts, seed):
    """The largest relative difference between the structured kernel's (g I - J)^-1 b (built on the
    parameter block ``p``) and a dense solve with J from central differences of ``rhs`` (every
    component, root included), per shift."""
    from tetherlab.tether import newton_inextensible as ni

    m1 = y.size // 2
    assert ni.structure_supported(p, y.size, True) == ""
    jac = np.empty((y.size, y.size))
    for j in range(y.size):
        yp, ym = y.copy(), y.copy()
        yp[j] += steps[j]
        ym[j] -= steps[j]
        jac[:, j] = (rhs(yp) - rhs(ym)) / (2 * steps[j])
    blk, fr, fc = ni.workspace(p)
    assert ni.form_blocks(0.0, y, p, m1, blk) == 0
    rng = np.random.default_rng(seed)
    out = []
    for g in shifts:
        fac = fc if isinstance(g, complex) else fr
        assert ni.factor(p, blk, g, fac) == 0
        b = rng.normal(size=2 * m1) + (1j * rng.normal(size=2 * m1) if fac is fc else 0.0)
        z = np.linalg.solve(g * np.eye(2 * m1) - jac, b)
        ni.solve(p, blk, g, fac, m1, b)
        out.append(np.max(np.abs(b - z)) / np.max(np.abs(z)))
    return out


def test_structured_kernel_with_a_free_root():
    """The hanging chain hung from a 2 kg point mass instead of the nail (falling freely with it
    under uniform gravity): the root's joint is one more block of the elimination."""
    s = tetherlab.load_scene(SCENES / "hanging-chain.toml").replace(**{
        "tethers.main.model": "inextensible", "integrator.method": "radau5", "tethers.main.rods": N_RODS,
        "tethers.main.constraint_rate": f"{RATE} 1/s",
        "bodies.nail": {"mass": "2 kg", "position": ["0 m", "0 m", "0 m"], "velocity": ["0 m/s", "0 m/s", "0 m/s"]},
        "tethers.main.initial": None,
    })  # fmt: skip
    prep = prepare(s)
    model = prep.model
    p = model.fresh_params()
    y = prep.y0.copy()
    m1 = y.size // 2
    rng = np.random.default_rng(7)
    h = LENGTH_M / N_RODS / (2 * SQ3)
    y[3:m1] += rng.normal(size=3 * N_RODS) * 0.05 * h
    y[m1:] += rng.normal(size=m1) * 0.3
    steps = np.concatenate([1e-5 * np.maximum(1.0, np.abs(y[:m1])), np.full(m1, 1e-4)])
    errs = _kernel_against_differences(lambda v: cowell_rhs_py(model, v), p, y, steps, (36.0, 27.0 + 16.0j), 2)
    # Budget: the central differences hold to 1e-5 of the Jacobian's largest entry (the first
    # test's budget; uniform gravity has no derivative, so the matrix omits nothing), which enters
    # (g I - J)^-1 b relative to g^2 ~ 1e3 against entries of ~200 /s^2: 1e-5 of |z| at most.
    # (Measured 2.4e-7 and 8.0e-7.)
    assert max(errs) <= 1e-5


def test_structured_kernel_in_the_frame_turning_with_the_orbit():
    """The in-plane libration scene (5 km, 10 kg between 1000 kg and 100 kg at 7400 km), inextensible,
    4 rods, formulation cowell-orbit: a free root on an orbit, the state in the turning frame."""
    import ctypes

    from tetherlab.pipeline import segment_plan

    s = tetherlab.load_scene(SCENES / "libration-inplane.toml").replace(**{
        "tethers.main.model": "inextensible", "tethers.main.rods": 4, "integrator.method": "radau5",
        "integrator.formulation": "cowell-orbit"})  # fmt: skip
    prep = prepare(s)
    plan = segment_plan(prep, prep.model.fresh_params())
    y, _ = plan.enter(prep.t0_s, prep.y0)
    y = np.array(y, dtype=float)
    m1 = y.size // 2
    pe = plan.pe
    P = ctypes.POINTER(ctypes.c_double)

    def rhs(v):
        v = np.ascontiguousarray(v)
        dv = np.empty_like(v)
        assert plan.rhs.ctypes(prep.t0_s, v.ctypes.data_as(P), dv.ctypes.data_as(P), pe.ctypes.data_as(P)) == 0
        return dv

    rng = np.random.default_rng(9)
    y[3:m1] *= 1.0 + 0.01 * rng.normal(size=m1 - 3)  # the rods 1 % off their lengths and turned
    y[m1:] += rng.normal(size=m1) * 0.1
    steps = np.concatenate([1e-6 * np.maximum(1.0, np.abs(y[:m1])), np.full(m1, 1e-4)])
    shifts = (36.0, 27.0 + 16.0j, 0.05, 0.04 + 0.02j)
    errs = _kernel_against_differences(rhs, pe, y, steps, shifts, 4)
    # Budget: the matrix leaves out the loads' derivative, here the gravity gradient, ~3 mu/r^3 =
    # 3.0e-6 /s^2 on each mass, against the g^2 of the Newton matrix: 2.3e-9 of |z| at g = 36/s and
    # 1.2e-3 at g = 0.05/s (a step of 20 s), each times the matrix's amplification (tens at most:
    # bound 1e-7 and 5e-3); the central differences' round-off on accelerations of ~7 m/s^2 over
    # steps of 7 m (the root) and 0.4 m (the rods) is ~1e-15 /s^2, nothing beside.
    # (Measured 2.2e-8, 2.9e-8, 3.5e-4, 5.7e-4.)
    assert max(errs[:2]) <= 1e-7
    assert max(errs[2:]) <= 5e-3
    # The frame's Coriolis and centrifugal terms (2 W, W^2 / g in the mass blocks) are what the
    # turning frame adds: the inertial matrix on the same state misses them (2 omega / g = 6e-5 at
    # g = 36/s, 0.04 at 0.05/s) and fails both bounds.
    from tetherlab.model.params import ParamView

    inertial = pe.copy()
    ParamView(inertial).formulation = ParamView(prep.model.fresh_params()).formulation  # the model's: Cowell's
    assert ParamView(inertial).formulation != ParamView(pe).formulation
    bad = _kernel_against_differences(rhs, inertial, y, steps, shifts, 4)
    assert max(bad[:2]) > 1e-7 and max(bad[2:]) > 5e-3
