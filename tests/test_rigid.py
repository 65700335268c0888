"""Rigid bodies, momentum wheels, attachment points and tether trees (docs/model.md 12).

What is checked, and the source of every expected value:

* the kernel's elimination over a tree against the **dense linear system of the same constraints**
  assembled here in numpy from the Newton-Euler equations of every element (docs/model.md 4.2,
  12.2-12.4) and solved with numpy.linalg: a chain m0 - m1 - m2, a star with tethers written in
  both directions, a rigid root with offset attachments carrying a rigid tip; agreement to the
  round-off bound cond(A) eps;
* momentum exchange: a constant motor torque on a wheel of a free body (analytic solution,
  docs/model.md 12.2): the body's rate, the wheel's momentum, the energy = the motor's work;
* first integrals at the right-hand-side level with everything on (asymmetric tree, two rigid
  bodies, offset attachments, spinning wheels, motors off, energy model, free space): dP/dt,
  dH/dt and dE/dt computed here from (y, y') vanish to round-off, and the two deliberate defects
  of kernel/layout.py (attachment vector unrotated; omega x (omega x rho) dropped) break them;
  plus a short integrated run holding P, H and E to 1e-10 relative (Basilisk's reaction-wheel
  level, _Documentation/secTest.tex);
* untethered bodies in one scene: the same right-hand side, bit for bit, as single-body scenes;
* bad input: a SceneError naming the key for each bad rigid-body, wheel, control or attachment key.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from tetherlab.errors import SceneError
from tetherlab.formulations.cowell import cowell_rhs_py
from tetherlab.model import params as L
from tetherlab.model.params import ParamView
from tetherlab.pipeline import prepare, simulate
from tetherlab.scene import Scene
from tetherlab.tether.solve import system_accelerations

EPS = np.finfo(float).eps
SQ3 = math.sqrt(3.0)
MU = 3.986004418e14


# ------------------------------------------------------------------------------------------------
# scenes
# ------------------------------------------------------------------------------------------------
def _tether(frm, to, rods=3, length="200 m", **extra):
    t = {"from": frm, "to": to, "rods": rods, "length": length, "EA": "2e4 N", "mass": "2 kg"}
    t.update(extra)
    return t


def _orbit_scene(bodies, tethers, effects=None, **top):
    d = {
        "duration": "20 s",
        "effects": {"central_gravity": {}} if effects is None else effects,
        "bodies": bodies,
        "tethers": tethers,
        "orbit": {"reference": "center_of_mass", "elements": {"a": "7000 km", "e": 0.01, "i": "30 deg", "nu": "10 deg"}},
        "output": {"count": 3},
    }
    d.update(top)
    return Scene.from_dict(d)


RIGID_ROOT = {
    "mass": "500 kg",
    "rigid": {
        "inertia": {"xx": "400 kg m2", "yy": "300 kg m2", "zz": "200 kg m2", "xy": "20 kg m2", "xz": "-10 kg m2", "yz": "5 kg m2"},
        "attitude": {"euler": ["20 deg", "-10 deg", "35 deg"], "sequence": "ZYX", "frame": "orbit"},
        "angular_velocity": {"vector": ["0.02 rad/s", "-0.01 rad/s", "0.03 rad/s"], "frame": "body"},
    },
    "wheels": {
        "w1": {"axis": [1.0, 0.2, 0.0], "inertia": "0.1 kg m2", "speed": "50 rad/s"},
        "w2": {"axis": [0.0, 1.0, 0.3], "inertia": "0.08 kg m2", "speed": "-30 rad/s"},
    },
}
RIGID_TIP = {
    "mass": "40 kg",
    "rigid": {
        "inertia": {"xx": "6 kg m2", "yy": "5 kg m2", "zz": "4 kg m2"},
        "attitude": {"quaternion": [0.9, 0.1, -0.3, 0.2 + 0.0]},
        "angular_velocity": {"vector": ["0.1 rad/s", "0.05 rad/s", "-0.02 rad/s"], "frame": "body"},
    },
    "wheels": {"w": {"axis": [0.0, 0.0, 1.0], "inertia": "0.01 kg m2", "speed": "100 rad/s"}},
}


def _norm_quat(q):
    q = np.asarray(q, float)
    return list(q / np.linalg.norm(q))


RIGID_TIP["rigid"]["attitude"]["quaternion"] = _norm_quat(RIGID_TIP["rigid"]["attitude"]["quaternion"])


def chain_scene():
    return _orbit_scene(
        {"m0": {"mass": "100 kg"}, "m1": {"mass": "20 kg"}, "m2": {"mass": "10 kg"}},
        {"a": _tether("m0", "m1"), "b": _tether("m1", "m2", initial={"theta": "20 deg"})},
    )


def star_both_ways_scene():
    return _orbit_scene(
        {"hub": {"mass": "100 kg"}, "p": {"mass": "20 kg"}, "q": {"mass": "10 kg"}, "r": {"mass": "5 kg"}},
        {
            "t1": _tether("hub", "p", initial={"theta": "10 deg"}),
            "t2": _tether("q", "hub", rods=2, initial={"theta": "40 deg", "side": "down"}),
            "t3": _tether("r", "hub", rods=4, initial={"phi": "30 deg"}),
        },
    )


def rigid_tree_scene(effects=None, model="paper", **top):
    return _orbit_scene(
        {"sat": RIGID_ROOT, "sub": RIGID_TIP, "m": {"mass": "15 kg"}, "n": {"mass": "8 kg"}},
        {
            "t1": _tether("sat", "sub", from_point=["1 m", "0.5 m", "-2 m"], to_point=["0.3 m", "-0.2 m", "0.5 m"],
                          initial={"theta": "15 deg"}, model=model),
            "t2": _tether("n", "sat", rods=2, to_point=["-1 m", "0 m", "1.5 m"], initial={"theta": "-30 deg", "side": "up"},
                          model=model),
            "t3": _tether("sub", "m", rods=2, from_point=["0 m", "0.4 m", "-0.5 m"], initial={"theta": "40 deg"}, model=model),
        },
        effects=effects,
        **top,
    )


# ------------------------------------------------------------------------------------------------
# an independent numpy model of the same equations
# ------------------------------------------------------------------------------------------------
def _skew(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _rot(q):
    w, x, y, z = q
    return Rotation.from_quat([x, y, z, w]).as_matrix()


class Numpy:
    """Kinematics, forces and the dense constraint system of a prepared model, written from
    docs/model.md 4.2 and 12.2-12.4 without the kernel's elimination."""

    def __init__(self, prep, y, p):
        m = prep.model
        self.m = m
        self.y = y
        self.p = p  # after a kernel evaluation: rod forces R, Q, C, u in its scratch
        nqt = m.n_qt
        self.q, self.qd = y[:nqt], y[nqt : 2 * nqt]
        self.N = m.n_rods
        self.names = [b.name for b in m.bodies]
        self.kidx = {n: i for i, n in enumerate(self.names) if n}
        self.d = self.q[3 : 3 + 3 * self.N].reshape(self.N, 3)
        self.dd = self.qd[3 : 3 + 3 * self.N].reshape(self.N, 3)
        view = ParamView(p)
        self.rod_m = view.rods.mass_kg[: self.N].copy()
        sr = [view.rod_scratch[g] for g in range(self.N)]
        self.R = np.array([s.r1 + s.r2 for s in sr])
        self.Q = np.array([s.q for s in sr])
        self.C = [s.c[0] * np.eye(3) + s.c[1] * np.outer(s.u, s.u) for s in sr]
        # bodies: attitude, then positions root to leaves
        self.Rm, self.wI, self.wb, self.h = {}, {}, {}, {}
        for b, off in m.rigid_index.items():
            self.Rm[b] = _rot(y[off : off + 4])
            self.wb[b] = y[off + 4 : off + 7]
            self.wI[b] = self.Rm[b] @ self.wb[b]
            self.h[b] = np.array([y[m.wheel_index[(b, w.name)]] for w in m.bodies[b].rigid.wheels])
        self.r, self.v = {}, {}
        for b in m.roots:
            qo = m.root_offset(b)
            self.r[b], self.v[b] = self.q[qo : qo + 3], self.qd[qo : qo + 3]
        self.A = {}
        self.rho_a, self.rho_c = {}, {}
        todo = list(range(len(m.tethers)))
        while todo:
            for k in list(todo):
                t = m.tethers[k]
                par = self.kidx[t.parent]
                if par not in self.r:
                    continue
                todo.remove(k)
                ra = self.Rm[par] @ np.asarray(t.from_point_m) if par in self.Rm else np.zeros(3)
                va = np.cross(self.wI[par], ra) if par in self.Rm else np.zeros(3)
                self.rho_a[k] = ra
                A, vA = self.r[par] + ra, self.v[par] + va
                self.A[k] = (A, vA)
                sl = m.rod_slices[k]
                B = A + 2 * SQ3 * self.d[sl].sum(axis=0)
                vB = vA + 2 * SQ3 * self.dd[sl].sum(axis=0)
                c = 1 + k
                rc = self.Rm[c] @ np.asarray(t.to_point_m) if c in self.Rm else np.zeros(3)
                vc = np.cross(self.wI[c], rc) if c in self.Rm else np.zeros(3)
                self.rho_c[k] = rc
                self.r[c], self.v[c] = B - rc, vB - vc

    def J_s(self, b):
        rs = self.m.bodies[b].rigid
        return np.asarray(rs.inertia_kg_m2) - sum(
            (w.inertia_kg_m2 * np.outer(w.axis, w.axis) for w in rs.wheels), np.zeros((3, 3))
        )

    def body_force(self, b, mu):
        mass = self.m.bodies[b].mass_kg
        r = self.r[b]
        return -mu * mass * r / np.linalg.norm(r) ** 3 if mu > 0 else np.zeros(3)

    def body_torque_inertial(self, b, mu, tau=None):
        """R [M_gg - sum a tau - w x (J_s w + h_w)] (docs/model.md 12.2, 12.5)."""
        rs = self.m.bodies[b].rigid
        Rm, w = self.Rm[b], self.wb[b]
        axes = np.array([wh.axis for wh in rs.wheels]).reshape(-1, 3)
        hw = axes.T @ self.h[b] if len(rs.wheels) else np.zeros(3)
        tq = np.zeros(3) if tau is None else axes.T @ tau
        JB = np.asarray(rs.inertia_kg_m2)
        mgg = np.zeros(3)
        if mu > 0:
            rb = Rm.T @ self.r[b]
            mgg = 3 * mu / np.linalg.norm(rb) ** 5 * np.cross(rb, JB @ rb)
        return Rm @ (mgg - tq - np.cross(w, self.J_s(b) @ w + hw))

    def kappa(self, b, rho):
        return np.cross(self.wI[b], np.cross(self.wI[b], rho)) if b in self.Rm else np.zeros(3)

    def solve(self, mu):
        """Dense solve of rods' d'', joint reactions and body accelerations (a or (a, alpha))."""
        m = self.m
        N = self.N
        tet = m.tethers
        jstart, n = [], 3 * N
        for t in tet:
            jstart.append(n)
            n += 3 * (t.rods + 1)
        bstart = {}
        for b, body in enumerate(m.bodies):
            if body.name and body.mass_kg > 0 and not body.fixed:
                bstart[b] = n
                n += 6 if b in self.Rm else 3
        A = np.zeros((n, n))
        rhs = np.zeros(n)
        row = 0

        def a_point(b, rho, kap):
            """(coefficient matrix over x, constant) of the acceleration of body b's point rho."""
            M = np.zeros((3, n))
            if b not in bstart:
                return M, np.zeros(3)
            s = bstart[b]
            M[:, s : s + 3] = np.eye(3)
            if b in self.Rm:
                M[:, s + 3 : s + 6] = -_skew(rho)
                return M, kap
            return M, np.zeros(3)

        for k, t in enumerate(tet):
            sl = m.rod_slices[k]
            par, ch = self.kidx[t.parent], 1 + k
            aA, cA = a_point(par, self.rho_a.get(k, np.zeros(3)), self.kappa(par, self.rho_a.get(k, np.zeros(3))))
            for i, g in enumerate(range(sl.start, sl.stop)):
                mg = self.rod_m[g]
                Jm, Jp = jstart[k] + 3 * i, jstart[k] + 3 * (i + 1)
                # m a_G,i - J_{i-1} + J_i = R_i,  a_G,i = a_A + 2 sqrt3 sum_{j<i} d''_j + sqrt3 d''_i
                A[row : row + 3] += mg * aA
                rhs[row : row + 3] -= mg * cA
                for j in range(sl.start, g):
                    A[row : row + 3, 3 * j : 3 * j + 3] += mg * 2 * SQ3 * np.eye(3)
                A[row : row + 3, 3 * g : 3 * g + 3] += mg * SQ3 * np.eye(3)
                A[row : row + 3, Jm : Jm + 3] -= np.eye(3)
                A[row : row + 3, Jp : Jp + 3] += np.eye(3)
                rhs[row : row + 3] += self.R[g]
                row += 3
                # m d'' + C (J_{i-1} + J_i) = Q
                A[row : row + 3, 3 * g : 3 * g + 3] = mg * np.eye(3)
                A[row : row + 3, Jm : Jm + 3] += self.C[g]
                A[row : row + 3, Jp : Jp + 3] += self.C[g]
                rhs[row : row + 3] = self.Q[g]
                row += 3
            # tip: a_B,n (rod end) = the child's attachment point acceleration
            Jn = jstart[k] + 3 * t.rods
            if t.tip_mass_kg > 0:
                A[row : row + 3] += aA
                rhs[row : row + 3] -= cA
                for j in range(sl.start, sl.stop):
                    A[row : row + 3, 3 * j : 3 * j + 3] += 2 * SQ3 * np.eye(3)
                rc = self.rho_c[k]
                aC, cC = a_point(ch, rc, self.kappa(ch, rc))
                A[row : row + 3] -= aC
                rhs[row : row + 3] += cC
            else:
                A[row : row + 3, Jn : Jn + 3] = np.eye(3)
            row += 3
        for b, s in bstart.items():
            # translation: m a = R + sum (+J_n from its parent tether) - sum J_0 of its children
            mass = m.bodies[b].mass_kg
            A[row : row + 3, s : s + 3] = mass * np.eye(3)
            rhs[row : row + 3] = self.body_force(b, mu)
            rot = b in self.Rm
            if rot:
                A[row + 3 : row + 6, s + 3 : s + 6] = self.Rm[b] @ self.J_s(b) @ self.Rm[b].T
                rhs[row + 3 : row + 6] = self.body_torque_inertial(b, mu)
            for k, t in enumerate(tet):
                if 1 + k == b:
                    Jn = jstart[k] + 3 * t.rods
                    A[row : row + 3, Jn : Jn + 3] -= np.eye(3)
                    if rot:
                        A[row + 3 : row + 6, Jn : Jn + 3] -= _skew(self.rho_c[k])
                if self.kidx[t.parent] == b:
                    J0 = jstart[k]
                    A[row : row + 3, J0 : J0 + 3] += np.eye(3)
                    if rot:
                        A[row + 3 : row + 6, J0 : J0 + 3] += _skew(self.rho_a[k])
            row += 6 if rot else 3
        assert row == n
        x = np.linalg.solve(A, rhs)
        # forward error bound of two backward-stable computations of x (ours and the kernel's)
        # with inputs known to eps: |dx| <= c eps |A^-1| (|A| |x| + |b|)  (Higham 2002, 7.1)
        ainv = np.linalg.norm(np.linalg.inv(A), 2)
        return x, bstart, ainv * (np.linalg.norm(A, 2) * np.linalg.norm(x) + np.linalg.norm(rhs))


def _kernel(prep, y):
    p = prep.model.fresh_params()
    nqt = prep.model.n_qt
    acc = np.zeros(nqt)
    datt = np.zeros(y.size - 2 * nqt)
    y = np.ascontiguousarray(y, float)
    assert system_accelerations(0.0, y[:nqt], y[nqt : 2 * nqt], y[2 * nqt :], p, acc, datt) == 0
    return acc, datt, p


@pytest.mark.parametrize("make", [chain_scene, star_both_ways_scene, rigid_tree_scene], ids=["chain", "star-both-ways", "rigid-tree"])
def test_tree_solve_matches_the_dense_system(make):
    prep = prepare(make())
    y = prep.y0.copy()
    # a non-trivial state: the rods breathing and swinging (the layout starts them corotating)
    rng = np.random.default_rng(1)
    nqt = prep.model.n_qt
    y[nqt + 3 : nqt + 3 + 3 * prep.model.n_rods] += 0.05 * rng.standard_normal(3 * prep.model.n_rods)
    acc, datt, p = _kernel(prep, y)
    ref = Numpy(prep, y, p)
    x, bstart, scale = ref.solve(MU)
    N = prep.model.n_rods
    bound = 10 * EPS * scale  # c = 10 for the few roundings in forming R, Q and the body terms
    assert np.max(np.abs(acc[3 : 3 + 3 * N] - x[: 3 * N])) <= bound
    # and not trivially: the bound is far below the rods' own accelerations
    assert bound < 1e-6 * np.max(np.abs(x[: 3 * N]))
    for b in prep.model.roots:
        if b in bstart:
            qo = prep.model.root_offset(b)
            s = bstart[b]
            assert np.max(np.abs(acc[qo : qo + 3] - x[s : s + 3])) <= bound
    for b, off in prep.model.rigid_index.items():
        s = bstart[b]
        alpha_b = ref.Rm[b].T @ x[s + 3 : s + 6]  # omega' in body axes
        o = off - 2 * nqt
        assert np.max(np.abs(datt[o + 4 : o + 7] - alpha_b)) <= bound


# ------------------------------------------------------------------------------------------------
# momentum exchange (analytic)
# ------------------------------------------------------------------------------------------------
def _free_body(wheels, omega=("0 rad/s",) * 3, duration="30 s", count=7, **extra):
    body = {
        "mass": "100 kg",
        "position": ["1000 m", "0 m", "0 m"],
        "velocity": ["0 m/s", "0 m/s", "0 m/s"],
        "rigid": {
            "inertia": {"xx": "30 kg m2", "yy": "20 kg m2", "zz": "12 kg m2"},
            "attitude": {"quaternion": [1.0, 0.0, 0.0, 0.0]},
            "angular_velocity": {"vector": list(omega), "frame": "body"},
        },
        "wheels": wheels,
    }
    body.update(extra)
    return Scene.from_dict({
        "duration": duration, "effects": {}, "bodies": {"b": body},
        "integrator": {"rtol": 1e-13, "atol": 1e-13}, "output": {"count": count},
    })


def test_motor_torque_exchanges_momentum_with_the_body():
    # wheel on the principal z axis, constant motor torque tau, body at rest (docs/model.md 12.2):
    # h(t) = tau t;  J_s omega_z = -tau t  (J_s = J_zz - I);  H = J_s omega + h a = 0;
    # energy = tau^2 t^2 / 2 (1/I + 1/J_s) = the motor's work int tau Omega dt, Omega = h/I - omega_z
    tau, I, Jzz = 0.02, 0.05, 12.0
    res = simulate(_free_body({"w": {"axis": [0, 0, 1], "inertia": f"{I} kg m2", "torque": f"{tau} N m"}}), progress=False)
    t = res.timeseries["t_s"].to_numpy()
    Js = Jzz - I
    wz = res.timeseries["b.omega_z_rad_s"].to_numpy()
    h = res.timeseries["b.w.momentum_N_m_s"].to_numpy()
    assert np.max(np.abs(h - tau * t)) <= 1e-12 * tau * t[-1]
    assert np.max(np.abs(wz + tau * t / Js)) <= 1e-12 * tau * t[-1] / Js
    speed = res.timeseries["b.w.speed_rad_s"].to_numpy()
    assert np.max(np.abs(speed - tau * t * (1 / I + 1 / Js))) <= 1e-11 * tau * t[-1] / I
    E = res.diagnostics["rotational_J"].to_numpy()
    work = 0.5 * tau**2 * t**2 * (1 / I + 1 / Js)
    assert np.max(np.abs(E - work)) <= 1e-11 * work[-1]
    H = res.diagnostics[["angmom_x_kg_m2_s", "angmom_y_kg_m2_s", "angmom_z_kg_m2_s"]].to_numpy()
    assert np.max(np.abs(H)) <= 1e-12 * tau * t[-1]


def test_motor_on_a_tumbling_body_keeps_the_total_angular_momentum():
    # off-axis wheel, body tumbling: no external torque, so R (J_s omega + h_w) is constant and the
    # energy changes by the motor's work only (docs/model.md 12.2); checked against the integral of
    # tau Omega by Simpson's rule on 61 outputs (error ~ (dt)^4 E'''' << the 1e-6 bound)
    tau = 0.01
    sc = _free_body({"w": {"axis": [1, 1, 0.5], "inertia": "0.05 kg m2", "speed": "20 rad/s", "torque": f"{tau} N m"}},
                    omega=("0.1 rad/s", "-0.05 rad/s", "0.2 rad/s"), count=61)
    res = simulate(sc, progress=False)
    H = res.diagnostics[["angmom_x_kg_m2_s", "angmom_y_kg_m2_s", "angmom_z_kg_m2_s"]].to_numpy()
    assert np.max(np.linalg.norm(H - H[0], axis=1)) <= 1e-10 * np.linalg.norm(H[0])
    from scipy.integrate import simpson

    t = res.timeseries["t_s"].to_numpy()
    power = tau * res.timeseries["b.w.speed_rad_s"].to_numpy()
    work = simpson(power, x=t)
    E = res.diagnostics["rotational_J"].to_numpy()
    assert abs((E[-1] - E[0]) - work) <= 1e-6 * abs(work)


def test_wheel_limits_saturate_and_say_so():
    # torque limit: the constant 0.5 N m is clipped to 0.1 N m (h = 0.1 t); speed limit 40 rad/s:
    # the motor stops once the wheel's relative speed reaches it (flags: 1 torque, 2 speed)
    sc = _free_body({"w": {"axis": [0, 0, 1], "inertia": "0.05 kg m2", "torque": "0.5 N m", "max_torque": "0.1 N m",
                           "max_speed": "40 rad/s"}}, duration="30 s", count=31)
    res = simulate(sc, progress=False)
    speed = res.timeseries["b.w.speed_rad_s"].to_numpy()
    sat = res.diagnostics["b.w.saturated"].to_numpy()
    t = res.timeseries["t_s"].to_numpy()
    Js = 12.0 - 0.05
    early = t < 10
    assert np.allclose(res.timeseries["b.w.momentum_N_m_s"].to_numpy()[early], 0.1 * t[early], rtol=1e-10, atol=1e-12)
    assert set(sat[early][1:]) == {1.0}
    # speed limit: reached at 0.1 t (1/I + 1/Js) = 40, t = 19.84 s; it overshoots by at most one
    # step's worth of acceleration (the cut-off is a discontinuity the step control resolves)
    assert speed.max() <= 40.0 * (1 + 1e-3)
    assert sat[-1] == 2.0


# ------------------------------------------------------------------------------------------------
# first integrals with everything on (rhs level and a short run), and the negative controls
# ------------------------------------------------------------------------------------------------
def _rates(prep, y, defect=L.DEFECT_NONE):
    """dP/dt, dH/dt, dE/dt of the free-space model at state y, from the kernel's y' and an
    independent numpy evaluation of the mass points' accelerations (docs/model.md 6, 12.2).
    Returns the rates and the scales |sum of the terms| they are made of."""
    p = prep.model.fresh_params()
    ParamView(p).defect = defect
    nqt = prep.model.n_qt
    acc = np.zeros(nqt)
    datt = np.zeros(y.size - 2 * nqt)
    assert system_accelerations(0.0, y[:nqt], y[nqt : 2 * nqt], y[2 * nqt :], p, acc, datt) == 0
    m = prep.model
    ref = Numpy(prep, y, p)
    N = m.n_rods
    dd2 = acc[3 : 3 + 3 * N].reshape(N, 3)
    # body accelerations: roots from acc, attitude rates from datt; non-root bodies from their
    # tether's end: a_G = a_B - alpha x rho - omega x (omega x rho)
    a, alpha = {}, {}
    for b, off in m.rigid_index.items():
        o = off - 2 * nqt
        alpha[b] = ref.Rm[b] @ datt[o + 4 : o + 7]
    for b in m.roots:
        qo = m.root_offset(b)
        a[b] = acc[qo : qo + 3]
    aA = {}
    todo = list(range(len(m.tethers)))
    while todo:
        for k in list(todo):
            t = m.tethers[k]
            par = ref.kidx[t.parent]
            if par not in a:
                continue
            todo.remove(k)
            ra = ref.rho_a[k]
            a0 = a[par] + (np.cross(alpha[par], ra) + ref.kappa(par, ra) if par in alpha else 0.0)
            sl = m.rod_slices[k]
            aA[k] = a0
            aB = a0 + 2 * SQ3 * dd2[sl].sum(axis=0)
            c = 1 + k
            rc = ref.rho_c[k]
            a[c] = aB - (np.cross(alpha[c], rc) + ref.kappa(c, rc) if c in alpha else 0.0)
    P_rate = np.zeros(3)
    H_rate = np.zeros(3)
    E_rate = 0.0
    sP = sH = sE = 0.0
    for b, body in enumerate(m.bodies):
        if not (body.name and body.mass_kg > 0):
            continue
        f = body.mass_kg * a[b]
        P_rate += f
        H_rate += np.cross(ref.r[b], f)
        E_rate += ref.v[b] @ f
        sP += np.linalg.norm(f)
        sH += np.linalg.norm(np.cross(ref.r[b], f))
        sE += abs(ref.v[b] @ f)
        if b in ref.Rm:
            rs = body.rigid
            o = m.rigid_index[b] - 2 * nqt
            wdot = datt[o + 4 : o + 7]
            w = ref.wb[b]
            Js = ref.J_s(b)
            axes = np.array([wh.axis for wh in rs.wheels]).reshape(-1, 3)
            hw = axes.T @ ref.h[b] if len(rs.wheels) else np.zeros(3)
            hdot = np.array([datt[m.wheel_index[(b, wh.name)] - 2 * nqt] for wh in rs.wheels])
            hwdot = axes.T @ hdot if len(rs.wheels) else np.zeros(3)
            L_b = Js @ w + hw
            dL = ref.Rm[b] @ (np.cross(w, L_b) + Js @ wdot + hwdot)  # d/dt (R L_b)
            H_rate += dL
            sH += np.linalg.norm(ref.Rm[b] @ np.cross(w, L_b)) + np.linalg.norm(ref.Rm[b] @ Js @ wdot)
            er = w @ Js @ wdot + (ref.h[b] / np.array([wh.inertia_kg_m2 for wh in rs.wheels])) @ hdot if len(rs.wheels) else w @ Js @ wdot
            E_rate += er
            sE += abs(w @ Js @ wdot)
    rods = ParamView(p).rods
    for k, t in enumerate(m.tethers):
        sl = m.rod_slices[k]
        A0, vA0 = ref.A[k]
        ax, vx = A0.copy(), vA0.copy()
        acx = aA[k].copy()
        for g in range(sl.start, sl.stop):
            mg = ref.rod_m[g]
            d, dv, dacc = ref.d[g], ref.dd[g], dd2[g]
            rG, vG, aG = ax + SQ3 * d, vx + SQ3 * dv, acx + SQ3 * dacc
            P_rate += mg * aG
            sP += np.linalg.norm(mg * aG)
            # TMED: masses m/2 at r_G -/+ d: H' = m r_G x a_G + m d x d''
            H_rate += mg * (np.cross(rG, aG) + np.cross(d, dacc))
            sH += mg * (np.linalg.norm(np.cross(rG, aG)) + np.linalg.norm(np.cross(d, dacc)))
            E_rate += mg * (vG @ aG + dv @ dacc)
            sE += mg * (abs(vG @ aG) + abs(dv @ dacc))
            # elastic power EA L eps eps' (energy model: V = 1/2 EA L eps^2)
            lu = rods[g].length_m
            ea = rods[g].ea_N
            dn = np.linalg.norm(d)
            eps = 2 * SQ3 * dn / lu - 1
            epsd = 2 * SQ3 * (d @ dv) / (dn * lu)
            E_rate += ea * lu * eps * epsd
            sE += abs(ea * lu * eps * epsd)
            ax, vx, acx = ax + 2 * SQ3 * d, vx + 2 * SQ3 * dv, acx + 2 * SQ3 * dacc
    return (P_rate, H_rate, E_rate), (sP, sH, sE)


def _free_tree(model="energy"):
    """The rigid tree in free space (no effect): P, H about the origin and E are invariants."""
    return rigid_tree_scene(effects={}, model=model)


def _stirred(prep):
    y = prep.y0.copy()
    rng = np.random.default_rng(7)
    nqt = prep.model.n_qt
    y[nqt + 3 : nqt + 3 + 3 * prep.model.n_rods] += 0.02 * rng.standard_normal(3 * prep.model.n_rods)
    return y


def test_first_integrals_at_the_rhs_level():
    # exact invariants of the model (docs/model.md 6.1, 12.2): their rates vanish up to round-off,
    # bound 1e3 eps x the sum of the magnitudes of the terms (each term carries a few roundings,
    # the sums run over ~40 terms)
    prep = prepare(_free_tree())
    y = _stirred(prep)
    (dP, dH, dE), (sP, sH, sE) = _rates(prep, y)
    assert np.linalg.norm(dP) <= 1e3 * EPS * sP
    assert np.linalg.norm(dH) <= 1e3 * EPS * sH
    assert abs(dE) <= 1e3 * EPS * sE


@pytest.mark.parametrize("defect,broken", [(L.DEFECT_UNROTATED_ATTACHMENT, "H"), (L.DEFECT_NO_CENTRIPETAL, "P")])
def test_negative_controls_break_the_first_integrals(defect, broken):
    # the same check must fail by far (> 1e6 x its bound) with either deliberate defect
    prep = prepare(_free_tree())
    y = _stirred(prep)
    (dP, dH, dE), (sP, sH, sE) = _rates(prep, y, defect)
    if broken == "H":
        assert np.linalg.norm(dH) > 1e6 * 1e3 * EPS * sH
    else:
        assert np.linalg.norm(dP) > 1e6 * 1e3 * EPS * sP


def test_first_integrals_over_a_run():
    # DOP853 at rtol = atol = 1e-13 over 20 s: P (not linear in the state once a rigid body sits
    # at a tether's end), H and E drift by the integration error only; bound 1e-10 of the
    # internal scales (Basilisk's reaction-wheel tests' level)
    sc = _free_tree().replace(**{"integrator.rtol": 1e-13, "integrator.atol": 1e-13, "output.count": 5})
    res = simulate(sc, progress=False)
    g = res.diagnostics
    P = g[[f"momentum_{a}_N_s" for a in "xyz"]].to_numpy()
    H = g[[f"angmom_{a}_kg_m2_s" for a in "xyz"]].to_numpy()
    E = g["energy_J"].to_numpy()
    m_tot = prepare(sc).model.total_mass()
    v_scale = 1.0  # m/s: the rods move at ~0.1-1 m/s, the bodies spin at 0.02-0.1 rad/s x metres
    assert np.max(np.linalg.norm(P - P[0], axis=1)) <= 1e-10 * m_tot * v_scale
    assert np.max(np.linalg.norm(H - H[0], axis=1)) <= 1e-10 * np.linalg.norm(H[0])
    assert np.max(np.abs(E - E[0])) <= 1e-10 * abs(g["kinetic_J"].iloc[0])


# ------------------------------------------------------------------------------------------------
# untethered bodies
# ------------------------------------------------------------------------------------------------
def test_untethered_bodies_have_the_single_body_rhs():
    # a formation: the right-hand side of each body in the joint scene is that of a scene holding
    # it alone, bit for bit (the kernel treats every root independently)
    p1 = {"mass": "10 kg", "elements": {"a": "7000 km", "e": 0.01, "nu": "10 deg"}}
    p2 = {"mass": "20 kg", "elements": {"a": "7100 km", "e": 0.02, "i": "5 deg", "nu": "20 deg"}}
    rb = dict(RIGID_ROOT)
    rb = {**rb, "elements": {"a": "7050 km", "e": 0.0, "i": "1 deg", "nu": "30 deg"}}
    base = {"duration": "10 s", "effects": {"central_gravity": {}}, "output": {"count": 2}}
    joint = prepare(Scene.from_dict({**base, "bodies": {"a": p1, "b": p2, "c": rb}}))
    dyj = cowell_rhs_py(joint.model, joint.y0)
    nqt = joint.model.n_qt
    for name, body in (("a", p1), ("b", p2), ("c", rb)):
        single = prepare(Scene.from_dict({**base, "bodies": {name: body}}))
        dys = cowell_rhs_py(single.model, single.y0)
        b = [x.name for x in joint.model.bodies].index(name)
        qo = joint.model.root_offset(b)
        assert np.array_equal(joint.y0[qo : qo + 3], single.y0[:3])
        assert np.array_equal(dyj[nqt + qo : nqt + qo + 3], dys[3:6])
        if name == "c":
            off = joint.model.rigid_index[b]
            assert np.array_equal(dyj[off:], dys[6:])


# ------------------------------------------------------------------------------------------------
# bad input
# ------------------------------------------------------------------------------------------------
def _scene_with(body_changes=None, tether_changes=None):
    bodies = {"sat": {**RIGID_ROOT}, "tip": {"mass": "10 kg"}}
    bodies["sat"]["rigid"] = dict(RIGID_ROOT["rigid"])
    tether = _tether("sat", "tip")
    if body_changes:
        for k, v in body_changes.items():
            target = bodies
            parts = k.split(".")
            for part in parts[:-1]:
                target[part] = dict(target[part])
                target = target[part]
            if v is None:
                target.pop(parts[-1], None)
            else:
                target[parts[-1]] = v
    if tether_changes:
        tether.update(tether_changes)
    return {
        "duration": "10 s", "effects": {"central_gravity": {}}, "bodies": bodies, "tethers": {"main": tether},
        "orbit": {"reference": "sat", "elements": {"a": "7000 km", "e": 0.0}}, "output": {"count": 2},
    }


BAD = {
    "inertia not positive definite": (
        {"sat.rigid.inertia": {"xx": "1 kg m2", "yy": "1 kg m2", "zz": "1 kg m2", "xy": "2 kg m2"}},
        None, "bodies.sat.rigid.inertia", "positive definite"),
    "inertia triangle inequality": (
        {"sat.rigid.inertia": {"xx": "1 kg m2", "yy": "1 kg m2", "zz": "3 kg m2"}},
        None, "bodies.sat.rigid.inertia", "triangle inequality"),
    "inertia without unit": ({"sat.rigid.inertia": {"xx": 1, "yy": 1, "zz": 1}}, None, "bodies.sat.rigid.inertia.xx", "missing unit"),
    "wheel zero axis": ({"sat.wheels": {"w": {"axis": [0, 0, 0], "inertia": "0.1 kg m2"}}}, None, "bodies.sat.wheels.w.axis", "non-zero"),
    "wheel on a point mass": ({"tip.wheels": {"w": {"axis": [0, 0, 1], "inertia": "0.1 kg m2"}}}, None, "bodies.tip.wheels", "rigid"),
    "control on a point mass": ({"tip.control": {"target": "orbit", "kp": "1 N m", "kd": "1 N m s"}}, None, "bodies.tip.control", "rigid"),
    "quaternion far from unit": ({"sat.rigid.attitude": {"quaternion": [1.0, 0.1, 0.0, 0.0]}}, None,
                                 "bodies.sat.rigid.attitude.quaternion", "unit quaternion"),
    "unknown euler sequence": ({"sat.rigid.attitude": {"euler": ["1 deg"] * 3, "sequence": "ZYY"}}, None,
                               "bodies.sat.rigid.attitude.sequence", "did you mean"),
    "attachment on a point mass": (None, {"to_point": ["1 m", "0 m", "0 m"]}, "tethers.main.to_point", "point mass"),
    "controller without a target": ({"sat.control": {"kp": "1 N m", "kd": "1 N m s"},
                                     "sat.wheels": {"w": {"axis": [0, 0, 1], "inertia": "0.1 kg m2", "torque": "control"}}},
                                    None, "bodies.sat.control.target", "needs a target"),
    "controller without control wheels": ({"sat.control": {"target": "orbit", "kp": "1 N m", "kd": "1 N m s"}}, None,
                                          "bodies.sat.control", "torque = 'control'"),
    "control wheel without controller": ({"sat.wheels": {"w": {"axis": [0, 0, 1], "inertia": "0.1 kg m2", "torque": "control"}}},
                                         None, "bodies.sat.wheels.w.torque", "control] table"),
    "wheels too big": ({"sat.wheels": {"w": {"axis": [0, 0, 1], "inertia": "250 kg m2"}}}, None, "bodies.sat.wheels", "positive definite"),
    "rigid fixed body": ({"sat.fixed": True, "sat.position": ["7000 km", "0 km", "0 km"]}, None, "bodies.sat.rigid", "fixed"),
}


@pytest.mark.parametrize("case", list(BAD), ids=list(BAD))
def test_bad_rigid_input(case):
    bc, tc, key, fragment = BAD[case]
    with pytest.raises(SceneError) as info:
        Scene.from_dict(_scene_with(bc, tc))
    assert info.value.key == key, str(info.value)
    assert fragment in str(info.value), str(info.value)


def test_loop_of_tethers_names_the_closing_tether():
    d = _scene_with()
    d["bodies"]["third"] = {"mass": "1 kg"}
    d["tethers"]["b"] = _tether("tip", "third")
    d["tethers"]["c"] = _tether("third", "sat")
    with pytest.raises(SceneError) as info:
        Scene.from_dict(d)
    assert info.value.key == "tethers.c" and "closes a loop" in str(info.value)


def test_rigid_bodies_run_dromo_time_unless_it_has_no_orbit():
    """The time form carries the attitude and wheel blocks through (tests/test_formulations_rigid.py
    checks the numbers); what it still refuses is a scene without central_gravity."""
    d = _scene_with()
    d["integrator"] = {"formulation": "dromo-time"}
    assert prepare(Scene.from_dict(d)).formulation == "dromo-time"
    d["effects"] = {"j2": {}}
    with pytest.raises(SceneError) as info:
        prepare(Scene.from_dict(d))
    assert info.value.key == "integrator.formulation" and "central_gravity" in str(info.value)


# ------------------------------------------------------------------------------------------------
# attitude control
# ------------------------------------------------------------------------------------------------
def test_pd_control_follows_its_single_axis_ode():
    # free body at rest, 40 deg off an inertial target about z, three axis wheels under the PD law
    # (docs/model.md 12.6).  Body + wheels start with H = 0 and no external torque acts, so
    # J_s omega + h_w = 0 for ever and the gyroscopic term vanishes: the motion stays about z and
    # the yaw angle obeys exactly  J_s,zz th'' = -kp 2 sin(th/2) - kd th'  (J_s,zz = J_zz - I_wz),
    # integrated here by scipy (rtol 1e-12) as the reference.
    from scipy.integrate import solve_ivp

    kp, kd, Jzz, Iw, th0 = 0.5, 4.0, 12.0, 0.05, math.radians(40.0)
    wheels = {n: {"axis": a, "inertia": f"{Iw} kg m2", "torque": "control"}
              for n, a in (("wx", [1, 0, 0]), ("wy", [0, 1, 0]), ("wz", [0, 0, 1]))}
    q0 = [math.cos(th0 / 2), 0.0, 0.0, math.sin(th0 / 2)]
    sc = _free_body(wheels, duration="60 s", count=13,
                    control={"target": {"quaternion": [1.0, 0.0, 0.0, 0.0]}, "kp": f"{kp} N m", "kd": f"{kd} N m s"})
    sc = sc.replace(**{"bodies.b.rigid.attitude": {"quaternion": q0}})
    res = simulate(sc, progress=False)
    ts = res.timeseries
    t = ts["t_s"].to_numpy()
    yaw = 2 * np.arctan2(ts["b.qz"].to_numpy(), ts["b.qw"].to_numpy())
    Js = Jzz - Iw
    ref = solve_ivp(lambda _t, x: [x[1], (-kp * 2 * math.sin(x[0] / 2) - kd * x[1]) / Js], (0, t[-1]), [th0, 0.0],
                    t_eval=t, rtol=1e-12, atol=1e-14, method="DOP853")
    assert np.max(np.abs(yaw - ref.y[0])) <= 1e-8
    # the commanded torque at t = 0 is -kp e with e = 2 sin(th0/2) z (omega = 0), the z wheel's
    # motor torque its opposite (tau = -A^+ u, A = I)
    d = res.diagnostics
    assert d["b.control_z_N_m"].iloc[0] == pytest.approx(-kp * 2 * math.sin(th0 / 2), rel=1e-14)
    assert d["b.wz.torque_N_m"].iloc[0] == pytest.approx(kp * 2 * math.sin(th0 / 2), rel=1e-14)
    assert abs(d["b.control_x_N_m"].iloc[0]) < 1e-15 and abs(d["b.control_y_N_m"].iloc[0]) < 1e-15


def test_radau5_second_order_split_with_the_attitude_block():
    # The driver passes RADAU5 M1 = NQT (y = [q, q', attitude, wheels], q' exact for the first NQT
    # components; docs/model.md 12.1).  The reduced Newton systems are exact reformulations of
    # the full ones, so the run matches the full-Newton run (M1 = 0) up to the Newton stopping
    # and round-off in each step: bound N_steps x atol per component (the local tolerance summed
    # over the steps taken).
    from tetherlab.formulations.cowell import cowell_rhs
    from tetherlab.integrators.driver import integrate

    sc = rigid_tree_scene().replace(duration="5 s")
    prep = prepare(sc)
    runs = {}
    for m1 in (prep.model.n_qt, 0):
        p = prep.model.fresh_params()
        runs[m1] = integrate("radau5", cowell_rhs, 0.0, prep.y0, prep.t_out, p, 1e-9, prep.atol * 1e-1, second_order=m1)
        assert runs[m1].status == 0
    n_steps = runs[0].stats["n_accepted"] + runs[0].stats["n_rejected"]
    diff = np.abs(runs[prep.model.n_qt].y - runs[0].y) / (prep.atol * 1e-1)
    assert diff.max() <= n_steps
