"""What the TMED tether models conserve, and how well they reproduce a continuous tether.

Measures, for the model kinds "paper" (eq. 26 with the eq. 20 sign corrected), "energy"
(Lagrangian variant, docs/model.md section 5) and "printed" (eq. 20 exactly as printed):

  A. the power balance dE/dt of one state, from the kernel's accelerations, against the closed
     form of docs/model.md section 6 (which says where the paper model's energy goes);
  B. linear momentum, angular momentum and energy over short runs, free space and central gravity,
     n = 1, 2, 4 with unequal rod masses;
  C. long runs: is the paper model's energy error a bounded oscillation or a secular drift?
  D. static strain of a tether hanging in the gravity gradient of a circular orbit (relative
     equilibrium) against the exact continuous extensible tether in exact 1/r^2 gravity, n = 1..8;
  E. libration frequencies of a two-rod tether, printed sign against corrected sign, against the
     linearised rigid-link chain.

Prints Markdown tables (quoted in docs/model.md section 6).  Reproduce with

    PYTHONPATH=. python studies/model_properties.py            # everything, < 3 min
    PYTHONPATH=. python studies/model_properties.py --only D   # one part

Integration: the compiled DOP853 of tetherlab.integrators.driver (scipy's DOP853 through the
cfunc's ctypes pointer when the driver is not importable).
"""

from __future__ import annotations

import argparse
import ctypes
import math
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp
from scipy.linalg import eigh
from scipy.optimize import brentq, least_squares, root

from tetherlab import diagnostics as D
from tetherlab.forces import EFFECTS
from tetherlab.formulations.cowell import cowell_rhs
from tetherlab.model.params import ParamView
from tetherlab.system import TetherSpec, build_model, center_of_mass, chain_state, point_positions, tolerance_scales
from tetherlab.tether.solve import accelerations

SQ3 = math.sqrt(3.0)
MU = 3.986004418e14  # m^3/s^2, Earth (the scenes' "earth" preset, WGS 84: tetherlab/scene.py)
R0 = 7.4e6  # m, circular orbit of paper section 4.3
OMEGA = math.sqrt(MU / R0**3)
T_ORB = 2.0 * math.pi / OMEGA
KINDS = ("paper", "energy", "printed")

try:
    from tetherlab.integrators.driver import integrate as _integrate
except ImportError:  # pragma: no cover - fallback while the driver is not there
    _integrate = None

_P = ctypes.POINTER(ctypes.c_double)


def propagate(model, y0, t_out, rtol=1e-12, atol=1e-12):
    """(t, Y) at the output times; raises if the integration fails."""
    p = model.fresh_params()
    if _integrate is not None:
        r = _integrate("dop853", cowell_rhs, 0.0, y0, t_out, p, rtol, atol)
        if r.status != 0:
            raise RuntimeError(r.message)
        return r.t, r.y
    f = cowell_rhs.ctypes

    def fun(t, y):
        y = np.ascontiguousarray(y)
        dy = np.empty_like(y)
        st = f(t, y.ctypes.data_as(_P), dy.ctypes.data_as(_P), p.ctypes.data_as(_P))
        if st:
            raise RuntimeError(f"rhs status {st}")
        return dy

    sol = solve_ivp(fun, (0.0, t_out[-1]), y0, method="DOP853", rtol=rtol, atol=atol, t_eval=t_out)
    if sol.status != 0:
        raise RuntimeError(sol.message)
    return sol.t, sol.y.T


def md_table(headers, rows):
    out = ["| " + " | ".join(headers) + " |", "|" + "|".join("---" for _ in headers) + "|"]
    for r in rows:
        out.append("| " + " | ".join(str(c) for c in r) + " |")
    return "\n".join(out)


def g(x, digits=2):
    """Compact scientific formatting for the tables."""
    if isinstance(x, str):
        return x
    if x == 0:
        return "0"
    return f"{x:.{digits}g}" if 1e-3 <= abs(x) < 1e4 else f"{x:.{digits - 1}e}"


# ------------------------------------------------------------------------------------------------
# scenarios
# ------------------------------------------------------------------------------------------------
def set_rod_masses(model, weights):
    """Redistribute the tether's mass over its rods in proportion to ``weights`` (total kept)."""
    rods = ParamView(model.p).rods
    w = np.asarray(weights, float)
    w = w / w.sum()
    mt = model.tethers[0].mass_kg
    for gi, f in enumerate(w):
        rods[gi].mass_kg = mt * f


def unequal(n):
    """Rod mass weights 1 : 1.5 : 2 : ... (equal for n = 1)."""
    return 1.0 + 0.5 * np.arange(n)


def free_case(kind, n, strain=0.01):
    """Free space: root 50 kg, tip 20 kg, 100 m tether of 5 kg, EA 1 kN, bent chain, spinning and
    translating, initial stretch ``strain`` (1 %: 5 J of elastic energy)."""
    m = build_model(root_mass_kg=50.0, tethers=[TetherSpec("t", n, 100.0, 1e3, 5.0, 0.0, kind, 20.0, "tip")],
                    effects=[], central={})  # fmt: skip
    set_rod_masses(m, unequal(n))
    dirs = np.array([[1, 0, 0], [0.8, 0.6, 0], [0.6, 0.8, 0.1], [0.3, 0.9, 0.3]][:n], float)
    y0 = chain_state(m, np.zeros(3), np.array([0.3, -0.2, 0.1]), [dirs], [strain], np.array([0.0, 0.02, 0.05]))
    return m, y0


def orbit_case(kind, n, strain=0.01):
    """Circular orbit r0 = 7400 km: root 500 kg, tip 20 kg, 1 km tether of 5 kg, EA 1 kN, rods
    tilted in and out of the orbit plane (theta_i = 0.3 + 0.1 i, phi_i = 0.2 - 0.1 i rad),
    rotating with the orbit, initial stretch ``strain`` (1 %: 50 J of elastic energy)."""
    m = build_model(root_mass_kg=500.0, tethers=[TetherSpec("t", n, 1000.0, 1e3, 5.0, 0.0, kind, 20.0, "tip")],
                    effects=[(EFFECTS["central_gravity"], {})], central={"mu_m3_s2": MU})  # fmt: skip
    set_rod_masses(m, unequal(n))
    r0 = np.array([R0, 0.0, 0.0])
    v0 = np.array([0.0, OMEGA * R0, 0.0])
    dirs = np.array([D.direction_from_angles(r0, v0, 0.3 + 0.1 * i, 0.2 - 0.1 * i) for i in range(n)])
    y0 = chain_state(m, r0, v0, [dirs], [strain], np.array([0.0, 0.0, OMEGA]))
    return m, y0


def orbit_atol(model):
    return 1e-12 * tolerance_scales(model, R0, 1.0 / OMEGA)


# ------------------------------------------------------------------------------------------------
# A. power balance of one state
# ------------------------------------------------------------------------------------------------
def power_balance(model, y, mu):
    """(dE/dt from the kernel's accelerations, the closed form of docs/model.md 6, power scale).

    dE/dt = sum_bodies m v.a + sum_rods m (v_G.a_G + d'.d'') - P_grav + sum_rods EA L_u eps eps'
    closed form: sum_rods |d|' [ (R_2 - R_1 - Q_lag).u + (sqrt3 - 1)(2 F_E - (T_B - T_A).u) ]
    (zero for the energy model, whose own terms are written the other way round).
    """
    p = model.fresh_params()
    nr = model.n_rods
    lay = model.state
    q, qd = y[lay.q].copy(), y[lay.qd].copy()
    acc = np.zeros(lay.n_qt)
    assert accelerations(0.0, q, qd, p, acc) == 0
    view = ParamView(p)
    nodes = view.quadrature_nodes
    wts = view.quadrature_weights
    masses = model.rod_masses()
    lus = model.rod_lengths()
    ea = model.tethers[0].ea_n

    def grav(r):
        return -mu * r / np.linalg.norm(r) ** 3 if mu else np.zeros(3)

    m0 = model.root_mass_kg
    a_pt = acc[:3].copy()
    v_pt = qd[:3].copy()
    x_pt = q[:3].copy()
    dEdt = m0 * v_pt @ a_pt
    pgrav = m0 * grav(x_pt) @ v_pt
    closed = 0.0
    scale = 0.0
    for i in range(nr):
        # q, q' and the accelerations each start at offset 0, as y does: rod(i) slices all three
        sl = lay.rod(i)
        d, dd, ddd = q[sl], qd[sl], acc[sl]
        m = masses[i]
        vG = v_pt + SQ3 * dd
        aG = a_pt + SQ3 * ddd
        dEdt += m * (vG @ aG + dd @ ddd)
        dn = np.linalg.norm(d)
        u = d / dn
        eps = 2 * SQ3 * dn / lus[i] - 1
        epsd = 2 * SQ3 * (u @ dd) / lus[i]
        dEdt += ea * lus[i] * eps * epsd
        qlag = np.zeros(3)
        for xi, w in zip(nodes, wts):
            s = 1.0 + xi
            f = 0.5 * m * grav(x_pt + s * SQ3 * d)
            pgrav += w * f @ (v_pt + s * SQ3 * dd)
            qlag += SQ3 * xi * w * f
        rs = view.rod_scratch[i]
        r1, r2 = rs.r1, rs.r2
        fe = rs.fe
        ja = view.joint_scratch[i].j_N
        jb = view.joint_scratch[i + 1].j_N
        dT_u = (-jb - ja) @ u  # T_A = J_{i-1}, T_B = -J_i
        if model.tethers[0].model != "energy":
            closed += (u @ dd) * ((r2 - r1 - qlag) @ u + (SQ3 - 1) * (2 * fe - dT_u))
        scale += abs(2 * SQ3 * fe * (u @ dd))
        x_pt = x_pt + 2 * SQ3 * d
        v_pt = v_pt + 2 * SQ3 * dd
        a_pt = a_pt + 2 * SQ3 * ddd
    mf = model.tethers[0].tip_mass_kg
    dEdt += mf * v_pt @ a_pt
    pgrav += mf * grav(x_pt) @ v_pt
    return dEdt - pgrav, closed, scale


def part_a():
    rows = []
    for env in ("free", "orbit"):
        for kind in ("paper", "energy"):
            for n in (1, 3):
                m, y0 = free_case(kind, n) if env == "free" else orbit_case(kind, n)
                # a state along the trajectory, not the (symmetric) initial one
                T = 7.3 if env == "free" else 0.1 * T_ORB
                atol = 1e-12 if env == "free" else orbit_atol(m)
                _, Y = propagate(m, y0, np.array([0.0, T]), atol=atol)
                meas, closed, scale = power_balance(m, Y[-1], 0.0 if env == "free" else MU)
                rows.append([env, kind, n, g(meas, 4), g(closed, 4), g(abs(meas - closed) / scale, 2), g(scale, 3)])
    return (
        "### A. Power balance of one state (W)\n\n"
        + md_table(["env", "model", "n", "dE/dt from the kernel", "closed form (docs/model.md 6)",
                    "|difference| / scale", "scale sum 2 sqrt3 |F_E d|'| (W)"], rows)  # fmt: skip
    )


# ------------------------------------------------------------------------------------------------
# B. short runs
# ------------------------------------------------------------------------------------------------
def invariants(model, ts, Y, free):
    dg = D.compute(model, ts, Y)["global"]
    P = dg[:, D.G_PX : D.G_PZ + 1]
    H = dg[:, D.G_HX : D.G_HZ + 1]
    E = dg[:, D.G_E]
    Ve = dg[:, D.G_VE]
    out = {}
    masses = model.total_mass()
    rc0, vc0 = center_of_mass(model, Y[0])
    # internal angular momentum scale: H about the centre of mass at t0, sum of |m rho x nu|
    pts = point_positions(model, Y[0])
    hint = 0.0
    mr = model.rod_masses()
    bodies = [(model.root_mass_kg, pts["r0"], pts["v0"]), (model.tethers[0].tip_mass_kg, pts["joints"][0][-1], pts["jvel"][0][-1])]
    for i in range(model.n_rods):
        for s in (-1.0, 1.0):
            bodies.append((0.5 * mr[i], pts["rG"][i] + s * pts["d"][i], pts["vG"][i] + s * pts["dd"][i]))
    for mb, rb, vb in bodies:
        hint += mb * np.linalg.norm(np.cross(rb - rc0, vb - vc0))
    out["dH_rel"] = np.linalg.norm(H - H[0], axis=1).max() / np.linalg.norm(H[0])
    out["dH_int"] = np.linalg.norm(H - H[0], axis=1).max() / hint
    out["dE_ve"] = np.abs(E - E[0]).max() / Ve.max()
    out["dE_big"] = np.abs(E - E[0]).max() / max(np.abs(dg[0, D.G_KE]), np.abs(dg[0, D.G_VG]), Ve.max())
    if free:
        pscale = sum(mb * np.linalg.norm(vb) for mb, _, vb in bodies)
        out["dP"] = np.linalg.norm(P - P[0], axis=1).max() / pscale
        cm = np.array([center_of_mass(model, y)[0] for y in Y])
        drift = cm - (rc0 + np.outer(ts, vc0))
        out["dCM"] = np.linalg.norm(drift, axis=1).max() / 100.0  # in tether lengths
    return out


def part_b():
    rows = []
    for env in ("free", "orbit"):
        for kind in KINDS:
            for n in (1, 2, 4):
                if env == "free":
                    m, y0 = free_case(kind, n)
                    ts = np.linspace(0.0, 500.0, 501)
                    ts, Y = propagate(m, y0, ts)
                else:
                    m, y0 = orbit_case(kind, n)
                    ts = np.linspace(0.0, 3 * T_ORB, 601)
                    ts, Y = propagate(m, y0, ts, atol=orbit_atol(m))
                r = invariants(m, ts, Y, env == "free")
                rows.append([
                    env, kind, n,
                    g(r["dP"]) if "dP" in r else "(external force)",
                    g(r["dCM"]) if "dCM" in r else "",
                    g(r["dH_rel"]), g(r["dH_int"]), g(r["dE_ve"]), g(r["dE_big"]),
                ])  # fmt: skip
    return (
        "### B. Invariants over short runs (free: 500 s; orbit: 3 orbits; DOP853 rtol 1e-12)\n\n"
        + md_table(["env", "model", "n", "max|dP| / sum m|v|", "CM off uniform motion / L",
                    "max|dH| / |H0|", "max|dH| / H_int", "max|dE| / max V_e", "max|dE| / largest term"], rows)  # fmt: skip
    )


# ------------------------------------------------------------------------------------------------
# C. long runs
# ------------------------------------------------------------------------------------------------
def part_c():
    rows = []
    # (env, model, n, T, rtol, initial strain): the two extra n = 3 rows re-run the same motion at
    # another tolerance and from a strain perturbed by 1e-8, to see whether the wander is systematic
    cases = [("free", "paper", 1, 1e5, 1e-12, 0.01), ("free", "paper", 2, 1e5, 1e-12, 0.01),
             ("free", "paper", 3, 1e5, 1e-12, 0.01), ("free", "paper", 3, 1e5, 1e-10, 0.01),
             ("free", "paper", 3, 1e5, 1e-12, 0.01 + 1e-8), ("free", "energy", 3, 5e4, 1e-12, 0.01),
             ("orbit", "paper", 1, 30 * T_ORB, 1e-12, 0.01), ("orbit", "paper", 2, 30 * T_ORB, 1e-12, 0.01),
             ("orbit", "energy", 2, 30 * T_ORB, 1e-12, 0.01)]  # fmt: skip
    for env, kind, n, T, rtol, strain in cases:
        m, y0 = free_case(kind, n, strain) if env == "free" else orbit_case(kind, n, strain)
        ts = np.linspace(0.0, T, 10001)
        ts, Y = propagate(m, y0, ts, rtol=rtol, atol=rtol if env == "free" else orbit_atol(m) * rtol / 1e-12)
        dg = D.compute(m, ts, Y)["global"]
        dE = dg[:, D.G_E] - dg[0, D.G_E]
        ve = dg[:, D.G_VE].mean()
        k = len(dE) // 10
        tenths = [dE[i * k : (i + 1) * k] for i in range(10)]
        rows.append([
            env, kind, n, g(T), g(rtol), f"{strain:.8g}", g(ve, 3),
            g(tenths[0].mean() / ve), g(tenths[4].mean() / ve), g(tenths[9].mean() / ve),
            g(np.abs(tenths[0]).max() / ve), g(np.abs(tenths[9]).max() / ve),
        ])  # fmt: skip
    return (
        "### C. Long runs: energy error dE = E(t) - E(0) in units of the mean elastic energy V_e\n\n"
        + md_table(["env", "model", "n", "T (s)", "rtol", "strain0", "mean V_e (J)", "mean dE, 1st tenth", "mean dE, 5th tenth",
                    "mean dE, last tenth", "max|dE|, 1st tenth", "max|dE|, last tenth"], rows)  # fmt: skip
    )


# ------------------------------------------------------------------------------------------------
# D. static strain in the gravity gradient
# ------------------------------------------------------------------------------------------------
D_M0, D_MF, D_MT, D_L, D_EA = 1000.0, 20.0, 40.0, 20e3, 1e4  # kg, kg, kg, m, N


def exact_hanging():
    """Continuous extensible tether hanging radially above a root body at r0, rotating rigidly with
    the spin rate Omega that makes it a relative equilibrium (exact 1/r^2 gravity):

        dx/ds = 1 + T/EA,  dT/ds = rho (mu/x^2 - Omega^2 x),  T(0) = m0 (mu/r0^2 - Omega^2 r0),
        T(L) = mf (Omega^2 x(L) - mu/x(L)^2)  (shooting on Omega),

    s the unstretched arc length.  Returns Omega and the cumulative elongation int_0^s T/EA ds at
    s = k L / 840 (840 = lcm(1..8)), from which each rod's exact mean strain follows.
    """
    rho = D_MT / D_L
    s_eval = np.linspace(0.0, D_L, 841)

    def shoot(w, full=False):
        def f(s, y):
            x, T, _ = y
            return [1.0 + T / D_EA, rho * (MU / x**2 - w * w * x), T / D_EA]

        T0 = D_M0 * (MU / R0**2 - w * w * R0)
        sol = solve_ivp(f, (0.0, D_L), [R0, T0, 0.0], method="DOP853", rtol=1e-13, atol=[1e-9, 1e-14, 1e-14],
                        t_eval=s_eval)  # fmt: skip
        x, T, _ = sol.y[:, -1]
        res = T - D_MF * (w * w * x - MU / x**2)
        return (res, sol) if full else res

    w = brentq(shoot, OMEGA * (1 - 1e-3), OMEGA * (1 + 1e-3), xtol=1e-18, rtol=1e-15)
    return w, shoot(w, True)[1].y[2]


def discrete_hanging(kind, n, w_guess):
    """Relative equilibrium of the model: root at r0, rods radial, everything rotating with Omega.
    Unknowns Omega and the rod strains; equations: the root's radial acceleration is -Omega^2 r0
    and every d_i'' = -Omega^2 d_i (axial components; the transverse ones vanish by symmetry)."""
    m = build_model(root_mass_kg=D_M0, tethers=[TetherSpec("t", n, D_L, D_EA, D_MT, 0.0, kind, D_MF, "tip")],
                    effects=[(EFFECTS["central_gravity"], {})], central={"mu_m3_s2": MU})  # fmt: skip
    p = m.fresh_params()
    lu = m.rod_lengths()

    def res(z):
        w = w_guess * (1.0 + 1e-3 * z[0])
        eps = 1e-3 * z[1:]
        q = np.zeros(m.state.n_qt)
        qd = np.zeros_like(q)
        q[0] = R0
        qd[1] = w * R0
        dm = lu * (1.0 + eps) / (2.0 * SQ3)
        q[3::3] = dm
        qd[4::3] = w * dm
        acc = np.zeros_like(q)
        assert accelerations(0.0, q, qd, p, acc) == 0
        out = np.empty(n + 1)
        out[0] = (acc[0] + w * w * R0) / (w * w * D_L)
        out[1:] = (acc[3::3] + w * w * dm) / (w * w * D_L)
        return out

    sol = root(res, np.zeros(n + 1), method="hybr", options={"xtol": 1e-13})
    assert np.abs(res(sol.x)).max() < 1e-10, res(sol.x)
    return 1e-3 * sol.x[1:]


def part_d():
    w, cum = exact_hanging()
    rows = []
    prev = {}
    for n in range(1, 9):
        idx = np.arange(0, 841, 840 // n)
        exact = np.diff(cum[idx]) / (D_L / n)
        row = [n]
        for kind in ("paper", "energy"):
            eps = discrete_hanging(kind, n, w)
            e_tot = eps.sum() / exact.sum() - 1.0
            e_max = np.abs(eps / exact - 1.0).max()
            row += [g(e_tot, 3), g(e_max, 3)]
            prev.setdefault(kind, []).append(e_tot)
        rows.append(row)
    ratio = [g(prev["paper"][0] / prev["paper"][1], 3), g(prev["paper"][1] / prev["paper"][3], 3),
             g(prev["paper"][3] / prev["paper"][7], 3)]  # fmt: skip
    return (
        f"### D. Static strain in the gravity gradient (relative equilibrium, r0 = 7400 km)\n\n"
        f"Root {D_M0:g} kg below, tip {D_MF:g} kg above, tether {D_L / 1e3:g} km of {D_MT:g} kg, EA = {D_EA:g} N. "
        f"Exact continuous mean strain {cum[-1] / D_L:.6e}. Relative errors of the model's strains against the exact "
        f"mean strain of the same stretch of tether:\n\n"
        + md_table(["n", "paper: total elongation", "paper: worst rod", "energy: total elongation", "energy: worst rod"], rows)
        + f"\n\nPaper-model error ratios n=1/2, 2/4, 4/8: {', '.join(ratio)} (second order in 1/n)."
    )


# ------------------------------------------------------------------------------------------------
# E. libration frequencies
# ------------------------------------------------------------------------------------------------
E_M0, E_MF, E_MT, E_L, E_EA, E_N = 1e9, 5.0, 20.0, 1000.0, 200.0, 2  # root ~ on its Kepler orbit


def rigid_chain_modes():
    """Linearised libration of a chain of E_N rigid uniform rods with a tip mass, hinged to a
    point on a circular orbit (Hill frame; docs/model.md 9):  M th'' + K th = 0 with
    M_jk = int lam_j lam_k dm, K_in = 3 w^2 diag(int X lam_j dm), K_out = K_in + w^2 M."""
    n = E_N
    lr = np.full(n, E_L / n)
    mr = np.full(n, E_MT / n)
    xg, wg = np.polynomial.legendre.leggauss(4)
    M = np.zeros((n, n))
    K = np.zeros((n, n))
    for k in range(n):
        for s, ws in zip(lr[k] * (xg + 1) / 2, wg * lr[k] / 2):
            lam = np.r_[lr[:k], s, np.zeros(n - k - 1)]
            dm = mr[k] / lr[k] * ws
            M += dm * np.outer(lam, lam)
            K += 3 * OMEGA**2 * dm * (lr[:k].sum() + s) * np.diag(lam)
    M += E_MF * np.outer(lr, lr)
    K += 3 * OMEGA**2 * E_MF * E_L * np.diag(lr)
    w_in, v_in = eigh(K, M)
    w_out, v_out = eigh(K + OMEGA**2 * M, M)
    return (np.sqrt(w_in) / OMEGA, v_in), (np.sqrt(w_out) / OMEGA, v_out)


def libration_run(kind, shape, plane, amp=0.01, orbits=4.0):
    m = build_model(root_mass_kg=E_M0, tethers=[TetherSpec("t", E_N, E_L, E_EA, E_MT, 0.0, kind, E_MF, "tip")],
                    effects=[(EFFECTS["central_gravity"], {})], central={"mu_m3_s2": MU})  # fmt: skip
    ang = amp * shape / np.abs(shape).max()
    r0 = np.array([R0, 0.0, 0.0])
    v0 = np.array([0.0, OMEGA * R0, 0.0])
    dirs = np.array([D.direction_from_angles(r0, v0, a, 0.0) if plane == "in" else D.direction_from_angles(r0, v0, 0.0, a)
                     for a in ang])  # fmt: skip
    y0 = chain_state(m, r0, v0, [dirs], [0.0], np.array([0.0, 0.0, OMEGA]))
    ts = np.linspace(0.0, orbits * T_ORB, 4001)
    ts, Y = propagate(m, y0, ts, rtol=1e-11, atol=orbit_atol(m) * 10)
    frame = D.orbital_frame(Y[:, m.state.root_r], Y[:, m.state.root_v])
    angles = []
    for k in range(E_N):
        d = Y[:, m.state.rod(k)]
        e = np.einsum("nij,nj->ni", frame, d / np.linalg.norm(d, axis=1)[:, None])
        angles.append(np.arctan2(e[:, 1], e[:, 0]) if plane == "in" else np.arcsin(e[:, 2]))
    return ts, np.array(angles)


def dominant_frequency(ts, sig):
    """Frequency (rad/s) of the strongest line: zero-padded Hann FFT peak, refined by a
    least-squares fit of c + a cos(w t) + b sin(w t).  Also returns the fit's rms residual / rms."""
    sig = sig - sig.mean()
    nfft = 16 * len(sig)
    spec = np.abs(np.fft.rfft(sig * np.hanning(len(sig)), nfft))
    spec[0] = 0.0
    w0 = np.fft.rfftfreq(nfft, ts[1] - ts[0])[np.argmax(spec)] * 2 * math.pi

    def resid(x):
        B = np.column_stack([np.ones_like(ts), np.cos(x[0] * ts), np.sin(x[0] * ts)])
        c, *_ = np.linalg.lstsq(B, sig, rcond=None)
        return B @ c - sig

    r = least_squares(resid, [w0], x_scale=[1e-3 * w0])
    return r.x[0], math.sqrt(np.mean(r.fun**2)) / math.sqrt(np.mean(sig**2))


def part_e():
    (win, vin), (wout, vout) = rigid_chain_modes()
    rows = []
    for plane, wref, vecs in (("in", win, vin), ("out", wout, vout)):
        for mode in (0, 1):
            row = [f"{plane}-plane", "rigid (1)" if mode == 0 else "lateral (2)", f"{wref[mode]:.5f}"]
            for kind in KINDS:
                ts, ang = libration_run(kind, vecs[:, mode], plane)
                # modal coordinate of the reference chain (M-orthonormal eigenvectors)
                eta = (vecs.T @ _mass_matrix() @ ang)[mode]
                w, rr = dominant_frequency(ts, eta)
                row += [f"{w / OMEGA:.5f}", g((w / OMEGA) / wref[mode] - 1.0, 2)]
            rows.append(row)
    hdr = ["plane", "mode", "rigid-link chain / w"]
    for kind in KINDS:
        hdr += [f"{kind} / w", f"{kind} rel. err"]
    return (
        f"### E. Libration frequencies of a two-rod tether (in units of the orbit rate w)\n\n"
        f"Root {E_M0:g} kg (stays on its circular orbit), {E_L:g} m tether of {E_MT:g} kg in {E_N} rods, tip {E_MF:g} kg, "
        f"EA = {E_EA:g} N (static strain ~2e-4); started in the reference mode shape with 0.01 rad amplitude, "
        f"4 orbits, frequency of the excited modal coordinate:\n\n" + md_table(hdr, rows)
    )


def _mass_matrix():
    n = E_N
    lr = np.full(n, E_L / n)
    mr = np.full(n, E_MT / n)
    xg, wg = np.polynomial.legendre.leggauss(4)
    M = np.zeros((n, n))
    for k in range(n):
        for s, ws in zip(lr[k] * (xg + 1) / 2, wg * lr[k] / 2):
            lam = np.r_[lr[:k], s, np.zeros(n - k - 1)]
            M += mr[k] / lr[k] * ws * np.outer(lam, lam)
    return M + E_MF * np.outer(lr, lr)


PARTS = {"A": part_a, "B": part_b, "C": part_c, "D": part_d, "E": part_e}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", default="ABCDE", help="parts to run, e.g. 'BD' (default: all)")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    print("## Model properties (studies/model_properties.py)\n")
    print(f"Integrator: {'tetherlab dop853' if _integrate else 'scipy DOP853'}.\n")
    for key in args.only.upper():
        t1 = time.perf_counter()
        print(PARTS[key]())
        print(f"\n({key}: {time.perf_counter() - t1:.1f} s)\n", flush=True)
    print(f"Total {time.perf_counter() - t0:.1f} s.")
    return 0


if __name__ == "__main__":
    sys.exit(main())
