"""Shared helpers for the physics tests (not a test module)."""

from __future__ import annotations

from pathlib import Path


ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "studies" / "scenes"
MU_EARTH = 3.986004418e14  # m^3/s^2, the scene preset "earth" (tetherlab/scene/data.py)

from tetherlab.diagnostics import zero_crossing_frequency  # noqa: E402,F401  (re-export for the tests)
from tetherlab.model.params import ParamView  # noqa: E402
import numpy as np  # noqa: E402


def import_study(name: str):
    """Import studies/NAME.py as a module (the studies are scripts, not a package); the caller
    removes it from sys.modules when done (:func:`forget_study`)."""
    import importlib.util
    import sys

    spec = importlib.util.spec_from_file_location(f"tetherlab_study_{name}", ROOT / "studies" / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod


def forget_study(name: str) -> None:
    import sys

    sys.modules.pop(f"tetherlab_study_{name}", None)


# -- the dense Newton matrix the structured solve is checked against (tetherlab/tether/newton.py)

def newton_roots(p):
    """[(body, its position offset in q, mass or 0 when fixed)] of every root (tetherlab/system.py)."""
    v = ParamView(p)
    out = []
    for b in v.roots.astype(int):
        body = v.body(b)
        out.append((int(b), body.qtrans_index, body.mass_kg if body.inv_mass_1_kg > 0 else 0.0))
    return out


def dense_newton_A(p, blk, m1):
    """A_q, A_v of the structured matrix for any star, tree or forest of point-mass trees, assembled
    densely in numpy from the rod blocks and the parameter block (independent of
    newton.factor/solve; tests/test_newton_structured.py and test_newton_forest.py): T of sums from every root's own position block,
    M_x, K_x, C_x rod by rod, each root's row its mass (a fixed root: no row, A = 0 there)."""
    tethers = ParamView(p).tethers
    nteth = len(tethers)
    roots = newton_roots(p)
    qoff = {b: qo for b, qo, _ in roots}
    fixed = {qo for _, qo, m in roots if m == 0.0}

    def joint_of_body(body):
        if body in qoff:
            return qoff[body]
        t = tethers[body - 1]
        return 3 + 3 * (t.rod0 + t.n_rods - 1)

    T = np.zeros((m1, m1))
    M = np.zeros((m1, m1))
    K = np.zeros((m1, m1))
    C = np.zeros((m1, m1))
    for _, qo, m in roots:
        T[qo : qo + 3, qo : qo + 3] = np.eye(3)
        M[qo : qo + 3, qo : qo + 3] = np.eye(3) * (1.0 if m == 0.0 else m)
    placed = set(qoff)
    order = []
    while len(order) < nteth:  # parents before children, for T
        for k in range(nteth):
            par = tethers[k].parent
            if k not in order and par in placed:
                order.append(k)
                placed.add(1 + k)
    for k in order:
        t = tethers[k]
        n, g0 = t.n_rods, t.rod0
        pa = joint_of_body(t.parent)
        for i in range(n):
            g = g0 + i
            oa, ob = (pa if i == 0 else 3 * g), 3 + 3 * g
            T[ob : ob + 3] = T[oa : oa + 3]
            T[ob : ob + 3, ob : ob + 3] += 2 * np.sqrt(3.0) * np.eye(3)
            b = blk[g]
            maa, mab, kel, kv = (b[9 * j : 9 * j + 9].reshape(3, 3) for j in range(4))
            for o, sg, diag, off in ((oa, 1.0, (oa, maa), (ob, mab)), (ob, -1.0, (ob, maa), (oa, mab))):
                if o in fixed:
                    continue
                M[o : o + 3, diag[0] : diag[0] + 3] += diag[1]
                M[o : o + 3, off[0] : off[0] + 3] += off[1]
                K[o : o + 3, oa : oa + 3] -= sg * kel
                K[o : o + 3, ob : ob + 3] += sg * kel
                C[o : o + 3, oa : oa + 3] -= sg * kv
                C[o : o + 3, ob : ob + 3] += sg * kv
            if i == n - 1:
                M[ob : ob + 3, ob : ob + 3] += t.tip_mass_kg * np.eye(3)
    Ti = np.linalg.inv(T)
    return Ti @ np.linalg.solve(M, K) @ T, Ti @ np.linalg.solve(M, C) @ T


def dense_and_structured_runs(prep, m1):
    """RADAU5 runs of a prepared Cowell scene with the dense and the structured Newton matrix."""
    from tetherlab.formulations.cowell import cowell_rhs
    from tetherlab.integrators.driver import integrate
    from tetherlab.pipeline import _event_args

    from tetherlab.tether.newton_solver import choose

    runs = {}
    for kind in ("dense", "structured"):
        p = prep.model.fresh_params()
        runs[kind] = integrate("radau5", cowell_rhs, 0.0, prep.y0, prep.t_out, p, prep.rtol, prep.atol,
                               h_max=prep.h_max, max_steps=prep.max_steps, second_order=m1,
                               newton=choose(p, prep.y0.size, m1, kind), **_event_args(prep))  # fmt: skip
        assert runs[kind].status == 0, runs[kind].message
    assert runs["structured"].stats["newton_matrix"] == "structured"
    assert runs["dense"].stats["newton_matrix"] == "dense (requested)"
    return runs


def assert_runs_agree(prep, runs):
    """The two runs of :func:`dense_and_structured_runs` agree within the tolerance's budget."""
    # Error budget: each run holds its local error per step below
    # Hairer's mapped tolerance atol' + rtol' |y_i| (rtol' = 0.1 rtol^(2/3), atol' = atol rtol'/rtol,
    # radau5.py), so the two differ by at most the sum of both runs' local errors over their steps,
    # each component in its own unit.
    a, b = runs["dense"].y, runs["structured"].y
    rtol_m = 0.1 * prep.rtol ** (2.0 / 3.0)
    atol_m = prep.atol * (rtol_m / prep.rtol)
    steps = runs["dense"].stats["n_accepted"] + runs["structured"].stats["n_accepted"]
    bound = steps * (atol_m + rtol_m * np.maximum(np.abs(a), np.abs(b)))
    assert np.all(np.abs(a - b) <= bound)


def structured_vs_dense_lu(p, y, blk_p=None, seed=11, omega=None):
    """max |x - x_dense| / max |x_dense| for both shifts: the structured solve with the parameter
    block ``p`` against a dense LU of the matrix assembled from ``blk_p`` (default: p).  ``omega``:
    the state is in the frame turning with omega, whose Coriolis and centrifugal terms add -2 W
    and -W^2 to every joint's A_v and A_q (formulations/cowell_orbit.py)."""
    from tetherlab.tether import newton as nw

    # RADAU5's two shifts at h = 0.5 s: U1/h and (ALPH + i BETA)/h
    blk_p = p if blk_p is None else blk_p
    m1 = ParamView(blk_p).n_qtrans
    blk, f1, f2 = nw.workspace(blk_p)
    assert nw.rod_blocks(y, blk_p, m1, blk) == 0
    aq, av = dense_newton_A(blk_p, blk, m1)
    if omega is not None:
        W = np.array([[0.0, -omega[2], omega[1]], [omega[2], 0.0, -omega[0]], [-omega[1], omega[0], 0.0]])
        aq = aq - np.kron(np.eye(m1 // 3), W @ W)
        av = av - np.kron(np.eye(m1 // 3), 2 * W)
    rng = np.random.default_rng(seed)
    out = []
    for g, fac in ((3.6378342527444962 / 0.5, f1), (complex(2.6810828736277523, 3.0504301992474105) / 0.5, f2)):
        assert nw.factor(p, blk, g, fac) == 0
        E = g * np.eye(2 * m1) - np.block([[np.zeros((m1, m1)), np.eye(m1)], [aq, av]])
        b = rng.normal(size=2 * m1) * (1.0 if fac is f1 else 1.0 + 0.5j)
        x = b.astype(fac.dtype)
        nw.solve(p, blk, g, fac, m1, x)
        xd = np.linalg.solve(E, b)
        out.append(np.max(np.abs(x - xd)) / np.max(np.abs(xd)))
    return out


def call_cfunc(f, t: float, y, p, n_out: int | None = None) -> tuple[int, np.ndarray]:
    """One call of a compiled cfunc with the integrators' RHS signature (rhs or event) from Python:
    (its status, its output of ``n_out`` values, default len(y))."""
    import ctypes

    P = ctypes.POINTER(ctypes.c_double)
    y = np.ascontiguousarray(y, dtype=float)
    out = np.empty(y.size if n_out is None else n_out)
    st = f.ctypes(t, y.ctypes.data_as(P), out.ctypes.data_as(P), np.ascontiguousarray(p).ctypes.data_as(P))
    return st, out


def interrupt_at_birth(monkeypatch, n: int):
    """A Ctrl-C while the n-th birth remaps the state (between two phases)."""
    import signal

    from tetherlab import deployment

    calls = [0]
    real = deployment.birth_state

    def birth(*args, **kw):
        calls[0] += 1
        if calls[0] == n:
            signal.raise_signal(signal.SIGINT)
        return real(*args, **kw)

    monkeypatch.setattr(deployment, "birth_state", birth)
