"""Diagnostics computed from the state at every output time (compiled, one pass over the rows).

Per row: total linear momentum P, angular momentum H about the central body's centre, kinetic
energy, potential energy of the conservative effects named by the scene (the same quadrature as
the forces, so it is the exact potential of the discretised model), elastic energy of the rods
(1/2 EA L_u eps^2 per rod: the energy of the elastic bar the TMED stands for), and per rod the
strain, the axial force of eq. 1 and the joint reactions of the solve.  Libration angles are
computed from the tether's end points in the centre of mass's orbital frame (docs/model.md, 7).

The energy the paper's model conserves, if any, is discussed with numbers in docs/model.md.
"""

from __future__ import annotations

import math

import numpy as np

from ._jit import njit
from .model.params import ParamView
from .bodies.rigid import gravity_gradient_potential, mat_t_vec, mat_vec
from .kernel.effects import potential_per_mass
from .kernel.layout import (
    BS_ROT,
    BS_R,
    BS_SIZE,
    BS_U,
    BT_AOFF,
    BT_JB,
    BT_JS,
    BT_M,
    BT_NW,
    BT_RIGID,
    BT_SIZE,
    BT_W0,
    H_MU_GG,
    H_NBODY,
    H_NQ,
    H_NQT,
    H_NRODS,
    H_NTETH,
    H_NWHEEL,
    H_OFF_ATT,
    H_OFF_BODY,
    H_OFF_BSCR,
    H_OFF_QUAD,
    H_OFF_ROD,
    H_OFF_SCR,
    H_OFF_TETH,
    H_OFF_WHL,
    H_OFF_WT,
    H_MUTANT,
    MUT_NO_ELASTIC_E,
    RT_EA,
    RT_LU,
    RT_M,
    RT_SIZE,
    SJ_J,
    SJ_SIZE,
    SR_EPS,
    SR_FE,
    SR_SIZE,
    TS_A,
    TS_SIZE,
    TT_NRODS,
    TT_ROD0,
    TT_SIZE,
    TT_TENSION_ONLY,
    WS_SAT,
    WS_SIZE,
    WS_TAU,
    WT_AX,
    WT_I,
    WT_SIZE,
)
from .tether.chain import SQ3, next_joint, system_accelerations

# columns of the global diagnostics array
G_PX, G_PY, G_PZ, G_HX, G_HY, G_HZ, G_KE, G_VG, G_VE, G_E, G_KROT = range(11)
G_NCOL = 11


@njit(cache=True)
def evaluate_rows(ts, Y, p, glob, rods, joints, acc, datt, ctrl, wheels):
    """Fill ``glob`` (rows x G_NCOL), ``rods`` (rows x nrods x 2: strain, axial force),
    ``joints`` (rows x njoints x 3: reaction vectors J_k), ``ctrl`` (rows x nbody x 3: commanded
    control torque, body axes) and ``wheels`` (rows x nwheel x 2: motor torque, saturation flag)
    for every state row of Y.  Rigid bodies add J omega + R h_w to the angular momentum and
    1/2 w.J_s w + sum h_k^2/(2 I_k) to the kinetic energy (docs/model.md 12; also in G_KROT), the
    gravity-gradient (MacCullagh) term to the potential.

    Returns the index of the first row whose right-hand side failed, or -1.
    """
    nrows = Y.shape[0]
    h = int(p[H_NQT])
    nrods = int(p[H_NRODS])
    nteth = int(p[H_NTETH])
    nbody = int(p[H_NBODY])
    offr = int(p[H_OFF_ROD])
    offt = int(p[H_OFF_TETH])
    offb = int(p[H_OFF_BODY])
    bscr = int(p[H_OFF_BSCR])
    tscr = bscr + nbody * BS_SIZE
    wscr = tscr + nteth * TS_SIZE
    offw = int(p[H_OFF_WT])
    nwh = int(p[H_NWHEEL])
    oatt = int(p[H_OFF_ATT])
    whl = int(p[H_OFF_WHL]) - oatt
    scr = int(p[H_OFF_SCR])
    offq = int(p[H_OFF_QUAD])
    nq = int(p[H_NQ])
    jscr = scr + nrods * SR_SIZE
    mu_gg = p[H_MU_GG]
    elastic = p[H_MUTANT] != MUT_NO_ELASTIC_E  # always true but in tetherlab.mutants' control
    for row in range(nrows):
        t = ts[row]
        q = Y[row, :h]
        qd = Y[row, h : 2 * h]
        att = Y[row, 2 * h :]
        code = system_accelerations(t, q, qd, att, p, acc, datt)
        if code != 0:
            return row
        px = 0.0
        py = 0.0
        pz = 0.0
        hx = 0.0
        hy = 0.0
        hz = 0.0
        ke = 0.0
        krot = 0.0
        vg = 0.0
        ve = 0.0
        for b in range(nbody):
            bt = offb + b * BT_SIZE
            m = p[bt + BT_M]
            if not m > 0.0:
                continue
            bs = bscr + b * BS_SIZE
            rx = p[bs + BS_R]
            ry = p[bs + BS_R + 1]
            rz = p[bs + BS_R + 2]
            vx = p[bs + BS_R + 3]
            vy = p[bs + BS_R + 4]
            vz = p[bs + BS_R + 5]
            px += m * vx
            py += m * vy
            pz += m * vz
            hx += m * (ry * vz - rz * vy)
            hy += m * (rz * vx - rx * vz)
            hz += m * (rx * vy - ry * vx)
            ke += 0.5 * m * (vx * vx + vy * vy + vz * vz)
            vg += m * potential_per_mass(p, t, rx, ry, rz)
            for j in range(3):
                ctrl[row, b, j] = p[bs + BS_U + j]
            if p[bt + BT_RIGID] == 0.0:
                continue
            ao = int(p[bt + BT_AOFF]) - oatt
            wx = att[ao + 4]
            wy = att[ao + 5]
            wz = att[ao + 6]
            jx, jy, jz = mat_vec(p, bt + BT_JS, wx, wy, wz)
            er = 0.5 * (wx * jx + wy * jy + wz * jz)
            w0 = int(p[bt + BT_W0])
            for k in range(w0, w0 + int(p[bt + BT_NW])):
                wt = offw + k * WT_SIZE
                hk = att[whl + k]
                jx += p[wt + WT_AX] * hk
                jy += p[wt + WT_AX + 1] * hk
                jz += p[wt + WT_AX + 2] * hk
                er += 0.5 * hk * hk / p[wt + WT_I]
            lx, ly, lz = mat_vec(p, bs + BS_ROT, jx, jy, jz)
            hx += lx
            hy += ly
            hz += lz
            ke += er
            krot += er
            if mu_gg > 0.0:
                rbx, rby, rbz = mat_t_vec(p, bs + BS_ROT, rx, ry, rz)
                vg += gravity_gradient_potential(p, bt + BT_JB, mu_gg, rbx, rby, rbz)
        for k in range(nwh):
            wheels[row, k, 0] = p[wscr + k * WS_SIZE + WS_TAU]
            wheels[row, k, 1] = p[wscr + k * WS_SIZE + WS_SAT]
        for k in range(nteth):
            tb = offt + k * TT_SIZE
            ts_ = tscr + k * TS_SIZE
            nk = int(p[tb + TT_NRODS])
            g0 = int(p[tb + TT_ROD0])
            ax = p[ts_ + TS_A]
            ay = p[ts_ + TS_A + 1]
            az = p[ts_ + TS_A + 2]
            avx = p[ts_ + TS_A + 3]
            avy = p[ts_ + TS_A + 4]
            avz = p[ts_ + TS_A + 5]
            for g in range(g0, g0 + nk):
                rb = offr + g * RT_SIZE
                m = p[rb + RT_M]
                dx = q[3 + 3 * g]
                dy = q[4 + 3 * g]
                dz = q[5 + 3 * g]
                ddx = qd[3 + 3 * g]
                ddy = qd[4 + 3 * g]
                ddz = qd[5 + 3 * g]
                gx = ax + SQ3 * dx
                gy = ay + SQ3 * dy
                gz = az + SQ3 * dz
                gvx = avx + SQ3 * ddx
                gvy = avy + SQ3 * ddy
                gvz = avz + SQ3 * ddz
                px += m * gvx
                py += m * gvy
                pz += m * gvz
                # TMED: masses m/2 at r_G -/+ d, so H = m r_G x v_G + m d x d'
                hx += m * (gy * gvz - gz * gvy + dy * ddz - dz * ddy)
                hy += m * (gz * gvx - gx * gvz + dz * ddx - dx * ddz)
                hz += m * (gx * gvy - gy * gvx + dx * ddy - dy * ddx)
                ke += 0.5 * m * (gvx**2 + gvy**2 + gvz**2 + ddx**2 + ddy**2 + ddz**2)
                for j in range(2 * nq):
                    xi = p[offq + j]
                    w = p[offq + 2 * nq + j]
                    s = 1.0 + xi
                    vg += w * 0.5 * m * potential_per_mass(
                        p, t, ax + s * SQ3 * dx, ay + s * SQ3 * dy, az + s * SQ3 * dz
                    )
                eps = p[scr + g * SR_SIZE + SR_EPS]
                if elastic and (eps > 0.0 or p[tb + TT_TENSION_ONLY] == 0.0):  # slack: stores nothing
                    ve += 0.5 * p[rb + RT_EA] * p[rb + RT_LU] * eps * eps
                rods[row, g, 0] = eps
                rods[row, g, 1] = p[scr + g * SR_SIZE + SR_FE]
                ax, ay, az, avx, avy, avz = next_joint(q, qd, g, ax, ay, az, avx, avy, avz)
            for j in range(nk + 1):
                jb = jscr + (g0 + k + j) * SJ_SIZE + SJ_J
                joints[row, g0 + k + j, 0] = p[jb]
                joints[row, g0 + k + j, 1] = p[jb + 1]
                joints[row, g0 + k + j, 2] = p[jb + 2]
        glob[row, G_PX] = px
        glob[row, G_PY] = py
        glob[row, G_PZ] = pz
        glob[row, G_HX] = hx
        glob[row, G_HY] = hy
        glob[row, G_HZ] = hz
        glob[row, G_KE] = ke
        glob[row, G_VG] = vg
        glob[row, G_VE] = ve
        glob[row, G_E] = ke + vg + ve
        glob[row, G_KROT] = krot
    return -1


def compute(model, ts: np.ndarray, Y: np.ndarray) -> dict:
    """Diagnostics for every row of Y (outputs of a run).  Returns numpy arrays in a dict."""
    p = model.fresh_params()
    nrows = Y.shape[0]
    nr = model.n_rods
    nj = nr + len(model.tethers)
    nb = len(model.bodies)
    nw = ParamView(p).n_wheels
    glob = np.full((nrows, G_NCOL), np.nan)
    rods = np.full((nrows, nr, 2), np.nan)
    joints = np.full((nrows, nj, 3), np.nan)
    ctrl = np.full((nrows, nb, 3), np.nan)
    wheels = np.full((nrows, nw, 2), np.nan)
    nqt = model.n_qt
    acc = np.zeros(nqt)
    datt = np.zeros(Y.shape[1] - 2 * nqt)
    if nrows:
        evaluate_rows(
            np.ascontiguousarray(ts, float), np.ascontiguousarray(Y, float), p, glob, rods, joints, acc, datt,
            ctrl, wheels,
        )
    return {"global": glob, "rods": rods, "joints": joints, "control": ctrl, "wheels": wheels}


def orbital_frame(r: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rows: x radial (outward), y = z x x (along-track for a circular orbit), z along r x v."""
    x = r / np.linalg.norm(r, axis=-1, keepdims=True)
    hvec = np.cross(r, v)
    z = hvec / np.linalg.norm(hvec, axis=-1, keepdims=True)
    y = np.cross(z, x)
    return np.stack([x, y, z], axis=-2)


def libration_angles(r_cm, v_cm, r_from, r_to, side: float = 1.0):
    """In-plane theta and out-of-plane phi (rad) of the line from `from` to `to` (docs/model.md 7).

    With e = (r_to - r_from)/|.| in the orbital frame (x radial, y along-track, z normal):
    e = side * (cos phi cos theta, cos phi sin theta, sin phi); side = +1 when the `to` body
    is above (radially outward of) the `from` body at theta = phi = 0, -1 when below.
    """
    frame = orbital_frame(np.atleast_2d(r_cm), np.atleast_2d(v_cm))
    e = np.atleast_2d(r_to - r_from)
    e = side * e / np.linalg.norm(e, axis=-1, keepdims=True)
    ex = np.einsum("nij,nj->ni", frame, e)
    theta = np.arctan2(ex[:, 1], ex[:, 0])
    phi = np.arcsin(np.clip(ex[:, 2], -1.0, 1.0))
    return theta, phi


def direction_from_angles(r, v, theta, phi, side: float = 1.0) -> np.ndarray:
    """Unit vector (inertial) for in-plane theta, out-of-plane phi in the orbital frame of (r, v)."""
    frame = orbital_frame(np.atleast_2d(r), np.atleast_2d(v))[0]
    e = side * np.array([math.cos(phi) * math.cos(theta), math.cos(phi) * math.sin(theta), math.sin(phi)])
    return frame.T @ e


def zero_crossing_frequency(t: np.ndarray, x: np.ndarray, smooth_s: float = 0.0) -> float:
    """Angular frequency (rad/s) from the mean spacing of the zero crossings of x(t).

    ``smooth_s > 0``: x is first convolved with a Gaussian of standard deviation ``smooth_s``
    seconds (t must be uniformly spaced; the 4 sigma at either end, where the kernel would run off
    the data, are dropped).  That removes oscillations much faster than the one measured, which
    otherwise shift every crossing a little and, through the first and last crossings, the mean
    spacing.  A symmetric kernel moves no crossing of a signal that is odd about its crossings
    (a libration: conservative and time-reversible), so the frequency is not biased by it; the
    libration period of studies/convergence.toml needs it (the lateral modes riding on theta shift
    crossings by ~1e-5 s, more than the period changes from n = 8 on).
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    if smooth_s < 0 or not math.isfinite(smooth_s):
        raise ValueError(f"smooth_s: expected a non-negative number of seconds, got {smooth_s!r}")
    if smooth_s > 0:
        dt = (t[-1] - t[0]) / (len(t) - 1)
        if not np.allclose(np.diff(t), dt, rtol=1e-9, atol=0.0):
            raise ValueError("t: smoothing needs uniformly spaced samples (an [output] count or step)")
        half = int(math.ceil(4.0 * smooth_s / dt))
        if 2 * half + 1 > len(t):
            raise ValueError(f"smooth_s: {smooth_s:g} s needs a record longer than 8 sigma, got {t[-1] - t[0]:g} s")
        kernel = np.exp(-0.5 * (np.arange(-half, half + 1) * dt / smooth_s) ** 2)
        x = np.convolve(x, kernel / kernel.sum(), mode="valid")
        t = t[half : len(t) - half]
    s = np.sign(x)
    idx = np.where(s[:-1] * s[1:] < 0)[0]
    if len(idx) < 3:
        raise ValueError(f"only {len(idx)} zero crossings: run longer")
    tz = t[idx] - x[idx] * (t[idx + 1] - t[idx]) / (x[idx + 1] - x[idx])
    return math.pi / ((tz[-1] - tz[0]) / (len(tz) - 1))


def internal_angular_momentum_scale(model, y) -> float:
    """sum m |(r - r_cm) x (v - v_cm)| over the root, the tips and every TMED mass (m/2 at
    r_G -/+ d): the size of the system's own angular momentum about its centre of mass.

    The total angular momentum about the attracting centre is almost all orbital, so a relative
    change of it cannot see an error in the tether's own rotation; this is the scale to measure
    that against (references/gates.toml [angular_momentum_internal]).
    """
    from .system import center_of_mass, point_positions

    pts = point_positions(model, y)
    rc, vc = center_of_mass(model, y)
    mr = model.rod_masses()
    items = [
        (b.mass_kg, pts["bodies"][i, :3], pts["bodies"][i, 3:])
        for i, b in enumerate(model.bodies)
        if b.name and b.mass_kg > 0 and not b.fixed
    ]
    spin = 0.0  # rigid bodies: |J_s omega + h_w| (their own angular momentum about G)
    for b, off in model.rigid_index.items():
        rs = model.bodies[b].rigid
        w = np.asarray(y[off + 4 : off + 7], float)
        js = np.asarray(rs.inertia_kg_m2, float) - sum(
            (wh.inertia_kg_m2 * np.outer(wh.axis, wh.axis) for wh in rs.wheels), np.zeros((3, 3))
        )
        hw = sum((np.asarray(wh.axis) * y[model.wheel_index[(b, wh.name)]] for wh in rs.wheels), np.zeros(3))
        spin += float(np.linalg.norm(js @ w + hw))
    for i in range(model.n_rods):
        for s in (-1.0, 1.0):
            items.append((0.5 * mr[i], pts["rG"][i] + s * pts["d"][i], pts["vG"][i] + s * pts["dd"][i]))
    return spin + float(sum(m * np.linalg.norm(np.cross(r - rc, v - vc)) for m, r, v in items))
