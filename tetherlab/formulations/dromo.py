"""DROMO: the orbit in ideal-frame elements (Pelaez, Hedo & Rodriguez de Andres, CMDA 97, 2007).

Equations, conventions, derivation and checks: ``docs/dromo.md`` (built on the checked sheet
``shared/references/dromo.md``; its section numbers are cited as "sheet s5" etc.).

Non-dimensional units: length L = |r0| (the initial radius of the root body), time
T = sqrt(L^3/mu), so mu = 1.  Elements (sheet s1): q1, q2 = components of the eccentricity vector
on the ideal axes x, y; q3 = 1/h; eta1..eta4 = Euler parameters of the ideal frame (eta4 scalar).
Central gravity -mu r/r^3 is handled analytically; everything else the scene names (effects, and
for a tether the joint reactions) enters as the perturbing acceleration a_p.

Two forms, both compiled cfuncs with the integrators' RHS_SIG:

* :func:`dromo_sigma_rhs` -- a point mass, independent variable the ideal anomaly sigma,
  state z = [tau, q1, q2, q3, eta1, eta2, eta3, eta4] with tau = t/T (sheet s5, s6(a));
* :func:`dromo_time_rhs` -- any scene, independent variable t (s): the root body's orbit in DROMO
  elements with sigma as a state, the rods' d_i, d_i' exactly as in Cowell,
  state y = [sigma, q1, q2, q3, eta1..eta4, d_1..d_N, d_1'..d_N'].

Output at physical times with the sigma form (:func:`integrate_sigma`): with DOP853 or Vern9,
inside the compiled loop (:func:`_clock_run`): an event tau = t_k/T located on the dense output,
then one step of the same method from the crossing step's start to the located sigma; with the
other methods (RADAU5, scipy), sigma
is integrated on a coarse grid (8 points a revolution) and t(sigma) = t_k is solved by a
safeguarded Newton iteration whose evaluations are short integrations from the bracketing grid
state (dt/dsigma = T/(q3^3 s^2) is the Newton derivative).  Docs/dromo.md section 5 says why.
"""

from __future__ import annotations

import math

import numpy as np
from numba import carray

from .._jit import njit, rhs_cfunc
from ..kernel.effects import perturbing_body_force
from ..kernel.layout import (
    FORM_DROMO_SIGMA,
    FORM_DROMO_TIME,
    H_FORM,
    H_LEN,
    H_OFF_FORM,
    H_ROOT_M,
)
from ..integrators.common import EVENT as EVENT_STATUS
from ..integrators.common import MAX_STEPS as MAX_STEPS_STATUS
from ..integrators.common import NON_FINITE as NON_FINITE_STATUS
from ..integrators.common import OK as OK_STATUS
from ..integrators.common import RHS_FAILED as RHS_FAILED_STATUS
from ..integrators.common import ST_ACCEPTED, ST_RHS_STATUS
from ..integrators.erk import K_ROWS as ERK_K_ROWS
from ..integrators.erk import KINDS as ERK_KINDS
from ..integrators.erk import erk_core, erk_step
from ..tether.chain import accelerations

# Formulation block (at p[H_OFF_FORM]): mu, L, T, Cowell state length, DROMO state length;
# a scratch buffer (q, q', acc of the Cowell coordinates) starts at FP_BUF.
FP_MU, FP_L, FP_T, FP_NCOW, FP_NSTATE = 0, 1, 2, 3, 4
FP_CLOCK = 5  # sigma form: the output time tau_k = t_k/T the clock event looks for
FP_BUF = 8
N_EL = 7  # q1 q2 q3 eta1 eta2 eta3 eta4
TWO_PI = 2.0 * math.pi

#: Grid points per revolution of sigma in the sigma form's first pass.  Each grid point inside a
#: step costs DOP853 three extra stages (dense output), so few points keep the overhead small
#: (8 a revolution: ~4 % at 50 steps a revolution); the bracket width does not limit accuracy.
GRID_PER_REV = 8


# ------------------------------------------------------------------------------------------------
# compiled kernels
# ------------------------------------------------------------------------------------------------
@njit(cache=True)
def geometry(sigma, y):
    """s, kappa and the orbital-frame unit vectors i, j, k from (sigma, y[1:8]) (sheet s1, s2)."""
    q1 = y[1]
    q2 = y[2]
    e1 = y[4]
    e2 = y[5]
    e3 = y[6]
    e4 = y[7]
    c = math.cos(sigma)
    sn = math.sin(sigma)
    s = 1.0 + q1 * c + q2 * sn
    kap = q1 * sn - q2 * c
    # ideal axes x, y and normal k: columns of R(eta), the convention of sheet s1
    xx = 1.0 - 2.0 * (e2 * e2 + e3 * e3)
    xy = 2.0 * (e1 * e2 + e3 * e4)
    xz = 2.0 * (e1 * e3 - e2 * e4)
    yx = 2.0 * (e1 * e2 - e3 * e4)
    yy = 1.0 - 2.0 * (e1 * e1 + e3 * e3)
    yz = 2.0 * (e2 * e3 + e1 * e4)
    kx = 2.0 * (e1 * e3 + e2 * e4)
    ky = 2.0 * (e2 * e3 - e1 * e4)
    kz = 1.0 - 2.0 * (e1 * e1 + e2 * e2)
    ix = c * xx + sn * yx
    iy = c * xy + sn * yy
    iz = c * xz + sn * yz
    jx = -sn * xx + c * yx
    jy = -sn * xy + c * yy
    jz = -sn * xz + c * yz
    return c, sn, s, kap, ix, iy, iz, jx, jy, jz, kx, ky, kz


@njit(cache=True)
def sigma_rates(c, sn, y, fr, ft, fn, dy):
    """d/dsigma of [tau, q1, q2, q3, eta1..eta4] into dy[0:8], for the non-dimensional
    perturbation (fr, ft, fn) in the orbital frame (sheet s5; docs/dromo.md section 3);
    c, sn = cos sigma, sin sigma."""
    q1 = y[1]
    q2 = y[2]
    q3 = y[3]
    e1 = y[4]
    e2 = y[5]
    e3 = y[6]
    e4 = y[7]
    s = 1.0 + q1 * c + q2 * sn
    q3s = q3 * q3 * q3 * s * s
    den = q3s * q3 * s  # q3^4 s^3
    ax = fr / den
    ay = ft / den
    az = fn / den
    dy[0] = 1.0 / q3s
    dy[1] = s * sn * ax + (q1 + (1.0 + s) * c) * ay
    dy[2] = -s * c * ax + (q2 + (1.0 + s) * sn) * ay
    dy[3] = -q3 * ay
    h = 0.5 * az
    dy[4] = h * (e4 * c - e3 * sn)
    dy[5] = h * (e3 * c + e4 * sn)
    dy[6] = h * (-e2 * c + e1 * sn)
    dy[7] = h * (-e1 * c - e2 * sn)


@njit(cache=True)
def root_state(sigma, y, L, T):
    """Inertial position (m) and velocity (m/s) of the orbit, and the frame (sheet s7)."""
    c, sn, s, kap, ix, iy, iz, jx, jy, jz, kx, ky, kz = geometry(sigma, y)
    q3 = y[3]
    rn = L / (q3 * q3 * s)
    vr = (L / T) * q3 * kap
    vt = (L / T) * q3 * s
    return (rn * ix, rn * iy, rn * iz, vr * ix + vt * jx, vr * iy + vt * jy, vr * iz + vt * jz,
            ix, iy, iz, jx, jy, jz, kx, ky, kz, c, sn)  # fmt: skip


@njit(cache=True)
def _perturbation_rates(c, sn, y, ax_, ay_, az_, rx, ry, rz, ix, iy, iz, jx, jy, jz, kx, ky, kz,
                        mu, L, dy):  # fmt: skip
    """Subtract central gravity from the total acceleration (SI), then :func:`_projected_rates`."""
    r2 = rx * rx + ry * ry + rz * rz
    g = mu / (r2 * math.sqrt(r2))
    _projected_rates(c, sn, y, ax_ + g * rx, ay_ + g * ry, az_ + g * rz, ix, iy, iz, jx, jy, jz,
                     kx, ky, kz, mu, L, dy)  # fmt: skip


@njit(cache=True)
def _projected_rates(c, sn, y, px, py, pz, ix, iy, iz, jx, jy, jz, kx, ky, kz, mu, L, dy):
    """Project the perturbing acceleration (SI) on the orbital frame, scale, rates in dy."""
    scale = L * L / mu  # acceleration unit mu/L^2
    fr = (px * ix + py * iy + pz * iz) * scale
    ft = (px * jx + py * jy + pz * jz) * scale
    fn = (px * kx + py * ky + pz * kz) * scale
    sigma_rates(c, sn, y, fr, ft, fn, dy)


@rhs_cfunc
def dromo_sigma_rhs(sigma, y_ptr, dy_ptr, p_ptr):
    p = carray(p_ptr, (int(p_ptr[H_LEN]),))
    y = carray(y_ptr, (8,))
    dy = carray(dy_ptr, (8,))
    off = int(p[H_OFF_FORM])
    mu = p[off + FP_MU]
    L = p[off + FP_L]
    T = p[off + FP_T]
    rx, ry, rz, vx, vy, vz, ix, iy, iz, jx, jy, jz, kx, ky, kz, c, sn = root_state(sigma, y, L, T)
    m0 = p[H_ROOT_M]
    # central gravity is the Kepler part DROMO integrates analytically: only the rest is evaluated
    fx, fy, fz = perturbing_body_force(p, T * y[0], 0, rx, ry, rz, vx, vy, vz, m0)
    _projected_rates(c, sn, y, fx / m0, fy / m0, fz / m0, ix, iy, iz, jx, jy, jz, kx, ky, kz, mu,
                     L, dy)  # fmt: skip
    return 0


@rhs_cfunc
def dromo_clock_event(sigma, y_ptr, g_ptr, p_ptr):
    """Event g = tau - tau_k (tau_k at p[off + FP_CLOCK]): the sigma at which the physical time
    reaches an output time (the sigma form's outputs, :func:`integrate_sigma`)."""
    p = carray(p_ptr, (int(p_ptr[H_LEN]),))
    g = carray(g_ptr, (1,))
    g[0] = y_ptr[0] - p[int(p[H_OFF_FORM]) + FP_CLOCK]
    return 0


@rhs_cfunc
def dromo_time_rhs(t, y_ptr, dy_ptr, p_ptr):
    p = carray(p_ptr, (int(p_ptr[H_LEN]),))
    off = int(p[H_OFF_FORM])
    mu = p[off + FP_MU]
    L = p[off + FP_L]
    T = p[off + FP_T]
    h = int(p[off + FP_NCOW]) // 2  # 3 (1 + N)
    n = int(p[off + FP_NSTATE])  # 8 + 2 (h - 3)
    y = carray(y_ptr, (n,))
    dy = carray(dy_ptr, (n,))
    nd = h - 3
    b = off + FP_BUF
    q = p[b : b + h]
    qd = p[b + h : b + 2 * h]
    acc = p[b + 2 * h : b + 3 * h]
    sigma = y[0]
    rx, ry, rz, vx, vy, vz, ix, iy, iz, jx, jy, jz, kx, ky, kz, c, sn = root_state(sigma, y, L, T)
    q[0] = rx
    q[1] = ry
    q[2] = rz
    qd[0] = vx
    qd[1] = vy
    qd[2] = vz
    for i in range(nd):
        q[3 + i] = y[8 + i]
        qd[3 + i] = y[8 + nd + i]
    status = accelerations(t, q, qd, p, acc)
    if status != 0:
        return status
    _perturbation_rates(c, sn, y, acc[0], acc[1], acc[2], rx, ry, rz, ix, iy, iz, jx, jy, jz,
                        kx, ky, kz, mu, L, dy)  # fmt: skip
    # dsigma/dt = h/r^2 = q3^3 s^2 / T = 1 / (T dtau/dsigma); element rates by the chain rule
    dsig_dt = 1.0 / (T * dy[0])
    dy[0] = dsig_dt
    for i in range(1, 8):
        dy[i] *= dsig_dt
    for i in range(nd):
        dy[8 + i] = y[8 + nd + i]
        dy[8 + nd + i] = acc[3 + i]
    return 0


@njit(cache=True)
def _clock_run(kind, rhs, event, sig, z, h, targets, k, p, rtol, atol, sig_max, max_steps, out_sig,
               out_z, stats):  # fmt: skip
    """Sigma-form outputs k, k+1, ... at the non-dimensional times ``targets`` (compiled loop).

    The explicit method ``kind`` (DOP853 or Vern9, :mod:`tetherlab.integrators.erk`) runs with
    the event g = tau - targets[k]; at a crossing it returns with (sig, z) at the start of the
    crossing step and the located sigma in ev[0].  One step of the same method from there to
    ev[0] gives output k; the target moves on and the integration restarts from the same step
    start (redoing that step), so outputs do not move the path (a restart only forgets the
    controller's last rejection, which caps the next step).  Returns (status, sig, h, k,
    sig_max); status MAX_STEPS after ``max_steps`` accepted steps (the caller continues).
    """
    n = z.shape[0]
    off = int(p[H_OFF_FORM])
    m = targets.shape[0]
    ev = np.zeros(4)
    tout = np.empty(1)
    yout = np.empty((1, n))
    K = np.empty((ERK_K_ROWS, n))
    ys = np.empty(n)
    znew = np.empty(n)
    acc0 = stats[ST_ACCEPTED]
    while k < m:
        if targets[k] <= z[0]:  # an output at the start time
            out_sig[k] = sig
            out_z[k, :] = z
            k += 1
            continue
        p[off + FP_CLOCK] = targets[k]
        left = max_steps - (stats[ST_ACCEPTED] - acc0)
        if left <= 0:
            return MAX_STEPS_STATUS, sig, h, k, sig_max
        tout[0] = sig_max
        # no forced side on (re)start: the target is new, so g < 0 there is a fresh fact
        ev[0] = 0.0
        ev[1] = -1.0
        ev[2] = -1.0
        ev[3] = 0.0
        st, sig, h, nd = erk_core(kind, rhs, sig, z, tout, p, rtol, atol, h, 0.0, left, yout, stats,
                                  False, event, 1, ev)  # fmt: skip
        if st == EVENT_STATUS:
            st2 = erk_step(kind, rhs, sig, z, ev[0] - sig, p, K, ys, znew, stats)
            if st2 != 0:
                if st2 > 0:
                    stats[ST_RHS_STATUS] = st2
                    return RHS_FAILED_STATUS, sig, h, k, sig_max
                return NON_FINITE_STATUS, sig, h, k, sig_max
            out_sig[k] = ev[0]
            out_z[k, :] = znew
            k += 1
        elif st == OK_STATUS:
            sig_max += TWO_PI  # the Kepler prediction of the output sigma was short
        else:
            return st, sig, h, k, sig_max
    return OK_STATUS, sig, h, k, sig_max


# ------------------------------------------------------------------------------------------------
# conversions (set-up and output; NumPy)
# ------------------------------------------------------------------------------------------------
def units(mu_m3_s2: float, length_m: float) -> tuple[float, float]:
    """(L, T): the length unit and T = sqrt(L^3/mu) (sheet s3)."""
    if not (mu_m3_s2 > 0 and length_m > 0):
        raise ValueError(f"DROMO units: expected mu > 0 and L > 0; got mu={mu_m3_s2!r}, L={length_m!r}")
    return float(length_m), math.sqrt(length_m**3 / mu_m3_s2)


def quaternion_from_frame(R: np.ndarray) -> np.ndarray:
    """Euler parameters (eta1, eta2, eta3, eta4) of the rotation whose columns are x, y, k
    (the convention of sheet s1), by Shepperd's method: divide by the largest component, so no
    geometry (retrograde equatorial included) divides by zero (sheet s4 step 4)."""
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    cand = (tr, R[0, 0], R[1, 1], R[2, 2])
    k = int(np.argmax(cand))
    if k == 0:
        w = 0.5 * math.sqrt(1.0 + tr)
        f = 0.25 / w
        e = (f * (R[2, 1] - R[1, 2]), f * (R[0, 2] - R[2, 0]), f * (R[1, 0] - R[0, 1]), w)
    elif k == 1:
        x = 0.5 * math.sqrt(1.0 + R[0, 0] - R[1, 1] - R[2, 2])
        f = 0.25 / x
        e = (x, f * (R[0, 1] + R[1, 0]), f * (R[0, 2] + R[2, 0]), f * (R[2, 1] - R[1, 2]))
    elif k == 2:
        y = 0.5 * math.sqrt(1.0 - R[0, 0] + R[1, 1] - R[2, 2])
        f = 0.25 / y
        e = (f * (R[0, 1] + R[1, 0]), y, f * (R[1, 2] + R[2, 1]), f * (R[0, 2] - R[2, 0]))
    else:
        z = 0.5 * math.sqrt(1.0 - R[0, 0] - R[1, 1] + R[2, 2])
        f = 0.25 / z
        e = (f * (R[0, 2] + R[2, 0]), f * (R[1, 2] + R[2, 1]), z, f * (R[1, 0] - R[0, 1]))
    eta = np.array(e)
    return eta / np.linalg.norm(eta)


def frame_from_quaternion(eta) -> np.ndarray:
    """R = [x y k] (columns) from the Euler parameters (sheet s1)."""
    e1, e2, e3, e4 = (float(v) for v in eta)
    return np.array(
        [
            [1 - 2 * (e2 * e2 + e3 * e3), 2 * (e1 * e2 - e3 * e4), 2 * (e1 * e3 + e2 * e4)],
            [2 * (e1 * e2 + e3 * e4), 1 - 2 * (e1 * e1 + e3 * e3), 2 * (e2 * e3 - e1 * e4)],
            [2 * (e1 * e3 - e2 * e4), 2 * (e2 * e3 + e1 * e4), 1 - 2 * (e1 * e1 + e2 * e2)],
        ]
    )


def cartesian_to_dromo(r_m, v_m_s, mu_m3_s2: float, length_m: float, sigma0: float = 0.0) -> np.ndarray:
    """DROMO elements [q1, q2, q3, eta1..eta4] of (r, v) at ideal anomaly ``sigma0``.

    ``sigma0`` fixes the initial ideal frame (sheet s4 step 2); the default 0 puts it on the
    orbital frame, defined for every eccentricity (the perifocal choice sigma0 = f0 is not
    defined for e = 0).  Needs h != 0 (sheet s8).
    """
    L, T = units(mu_m3_s2, length_m)
    # plain floats: np.cross on 3-vectors costs ~10 us a call, and this runs once per integration
    rx, ry, rz = (float(a) / L for a in r_m)
    vs = L / T
    vx, vy, vz = (float(a) / vs for a in v_m_s)
    hx, hy, hz = _cross(rx, ry, rz, vx, vy, vz)
    h = math.sqrt(hx * hx + hy * hy + hz * hz)
    rr = math.sqrt(rx * rx + ry * ry + rz * rz)
    if not (h > 0.0 and rr > 0.0):
        raise ValueError(f"DROMO needs a non-zero angular momentum and radius; got |h|={h!r}, |r|={rr!r} (units L, T)")
    i = (rx / rr, ry / rr, rz / rr)
    k = (hx / h, hy / h, hz / h)
    j = _cross(*k, *i)
    vh = _cross(vx, vy, vz, hx, hy, hz)
    e = [vh[a] - i[a] for a in range(3)]
    c, sn = math.cos(sigma0), math.sin(sigma0)
    x = [c * i[a] - sn * j[a] for a in range(3)]
    y = [sn * i[a] + c * j[a] for a in range(3)]
    R = np.array([[x[a], y[a], k[a]] for a in range(3)])
    q1 = e[0] * x[0] + e[1] * x[1] + e[2] * x[2]
    q2 = e[0] * y[0] + e[1] * y[1] + e[2] * y[2]
    return np.concatenate([[q1, q2, 1.0 / h], quaternion_from_frame(R)])


def _cross(ax, ay, az, bx, by, bz):
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


def dromo_to_cartesian(sigma: float, elements, mu_m3_s2: float, length_m: float) -> tuple[np.ndarray, np.ndarray]:
    """(r in m, v in m/s) from the ideal anomaly and the DROMO elements (sheet s7)."""
    L, T = units(mu_m3_s2, length_m)
    q1, q2, q3 = (float(v) for v in elements[:3])
    R = frame_from_quaternion(elements[3:7])
    x, y = R[:, 0], R[:, 1]
    c, sn = math.cos(sigma), math.sin(sigma)
    i = c * x + sn * y
    j = -sn * x + c * y
    s = 1.0 + q1 * c + q2 * sn
    kap = q1 * sn - q2 * c
    r = (L / (q3 * q3 * s)) * i
    v = (L / T) * (q3 * kap * i + q3 * s * j)
    return r, v


def dt_dsigma(sigma: float, z, T: float) -> float:
    """dt/dsigma = T r^2/h = T / (q3^3 s^2) (s), the Newton derivative of the time search."""
    s = 1.0 + z[1] * math.cos(sigma) + z[2] * math.sin(sigma)
    return T / (z[3] ** 3 * s * s)


def predicted_sigma(elements, sigma0: float, t_s: float, T: float) -> float:
    """Ideal anomaly at time ``t_s`` (from t = 0) on the unperturbed osculating ellipse (Kepler's
    equation).  Only sizes the first integration pass; never used as a result."""
    q1, q2, q3 = elements[:3]
    e = math.hypot(q1, q2)
    if not e < 1.0:
        raise ValueError(
            f"the sigma form of DROMO needs an elliptic orbit to schedule its output (e = {e:.6g}); "
            "use formulation 'dromo-time'"
        )
    beta = math.atan2(q2, q1)  # f = sigma - beta (sheet s7)
    f0 = sigma0 - beta
    n = q3**3 * (1 - e * e) ** 1.5 / T  # mean motion, rad/s (sheet s6, n = q3^3 w^3 per T)
    E0 = 2 * math.atan2(math.sqrt(1 - e) * math.sin(f0 / 2), math.sqrt(1 + e) * math.cos(f0 / 2))
    M = E0 - e * math.sin(E0) + n * t_s
    revs = math.floor((M + math.pi) / TWO_PI)
    Mw = M - TWO_PI * revs  # in [-pi, pi)
    E = Mw + e * math.sin(Mw) if e < 0.8 else math.copysign(math.pi, Mw)  # Newton converges from pi
    for _ in range(60):
        dE = (E - e * math.sin(E) - Mw) / (1 - e * math.cos(E))
        E -= dE
        if abs(dE) < 1e-15:
            break
    f = 2 * math.atan2(math.sqrt(1 + e) * math.sin(E / 2), math.sqrt(1 - e) * math.cos(E / 2))
    f0w = f0 - TWO_PI * math.floor((f0 + math.pi) / TWO_PI)
    return sigma0 + (f + TWO_PI * revs) - f0w


# ------------------------------------------------------------------------------------------------
# parameter block
# ------------------------------------------------------------------------------------------------
def attach(p: np.ndarray, form: int, mu_m3_s2: float, length_m: float, n_cowell: int) -> np.ndarray:
    """A copy of the model's parameter block with the DROMO block appended (header H_OFF_FORM)."""
    if form not in (FORM_DROMO_SIGMA, FORM_DROMO_TIME):
        raise ValueError(f"form: expected FORM_DROMO_SIGMA or FORM_DROMO_TIME; got {form!r}")
    L, T = units(mu_m3_s2, length_m)
    h = n_cowell // 2
    n_state = 8 if form == FORM_DROMO_SIGMA else 8 + 2 * (h - 3)
    off = p.size
    block = np.zeros(FP_BUF + 3 * h)
    block[FP_MU] = mu_m3_s2
    block[FP_L] = L
    block[FP_T] = T
    block[FP_NCOW] = n_cowell
    block[FP_NSTATE] = n_state
    out = np.concatenate([p, block])
    out[H_LEN] = out.size
    out[H_OFF_FORM] = off
    out[H_FORM] = form
    return out


def time_state(y_cowell: np.ndarray, mu_m3_s2: float, length_m: float, sigma0: float = 0.0) -> np.ndarray:
    """Time-form state [sigma, elements, d, d'] from a Cowell state [r0, d, v0, d']."""
    h = y_cowell.size // 2
    el = cartesian_to_dromo(y_cowell[:3], y_cowell[h : h + 3], mu_m3_s2, length_m, sigma0)
    return np.concatenate([[sigma0], el, y_cowell[3:h], y_cowell[h + 3 :]])


def cowell_state(y_time: np.ndarray, mu_m3_s2: float, length_m: float) -> np.ndarray:
    """Cowell state [r0, d, v0, d'] from a time-form state [sigma, elements, d, d']."""
    nd = (y_time.size - 8) // 2
    r, v = dromo_to_cartesian(y_time[0], y_time[1:8], mu_m3_s2, length_m)
    return np.concatenate([r, y_time[8 : 8 + nd], v, y_time[8 + nd :]])


# ------------------------------------------------------------------------------------------------
# integration
# ------------------------------------------------------------------------------------------------
_STAT_KEYS = ("n_accepted", "n_rejected", "n_rhs", "n_jac", "n_lu")


def _add_stats(total: dict, part: dict) -> None:
    for k in _STAT_KEYS:
        total[k] = total.get(k, 0) + int(part.get(k, 0))


def integrate_time(method, p_ext, y0_cowell, t_out, rtol, atol_cowell, mu, length_m, h_max=0.0,
                   max_steps=10**7, progress=None):  # fmt: skip
    """Time form: integrate and return an IntegrationResult whose ``y`` rows are Cowell states."""
    from ..integrators.driver import IntegrationResult, integrate

    z0 = time_state(np.asarray(y0_cowell, float), mu, length_m)
    h = y0_cowell.size // 2
    a = np.asarray(atol_cowell, float)
    # elements and sigma are O(1) non-dimensional: atol in their own units = the scene's atol,
    # which is atol_cowell[0]/L (the root position scale is the reference radius)
    a_el = a[0] / length_m
    atol = np.concatenate([np.full(8, a_el), a[3:h], a[h + 3 :]])
    res = integrate(method, dromo_time_rhs, 0.0, z0, t_out, p_ext, rtol, atol, h_max=h_max,
                    max_steps=max_steps, progress=progress)  # fmt: skip
    Y = np.array([cowell_state(z, mu, length_m) for z in res.y]).reshape(len(res.t), y0_cowell.size)
    return IntegrationResult(t=res.t, y=Y, status=res.status, message=res.message, t_end=res.t_end,
                             y_end=cowell_state(res.y_end, mu, length_m), stats=dict(res.stats))  # fmt: skip


def integrate_sigma(method, p_ext, r0_m, v0_m_s, t_out, rtol, atol, mu, length_m, sigma0=0.0,
                    max_steps=10**7, progress=None, grid_per_rev=GRID_PER_REV):  # fmt: skip
    """Sigma form for a point mass, with the state reported at the physical times ``t_out`` (s).

    Returns an IntegrationResult with Cartesian rows [r, v] (m, m/s) at ``t_out``.  ``atol`` is in
    the units of the non-dimensional state (a scalar).  DOP853 and Vern9 find the output sigmas in
    their compiled loop (:func:`_integrate_sigma_clock`); the other methods use the sigma grid and a
    Newton search (:func:`_integrate_sigma_grid`).  See the module docstring.
    """
    tt = np.asarray(t_out, float)
    if tt.ndim != 1 or tt.size == 0 or np.any(np.diff(tt) < 0) or tt[0] < 0:
        raise ValueError(f"t_out: expected non-decreasing times >= 0 s; got {tt!r}")
    if method in ERK_KINDS:
        return _integrate_sigma_clock(method, p_ext, r0_m, v0_m_s, tt, rtol, atol, mu, length_m,
                                      sigma0, max_steps, progress)  # fmt: skip
    return _integrate_sigma_grid(method, p_ext, r0_m, v0_m_s, tt, rtol, atol, mu, length_m, sigma0,
                                 max_steps, progress, grid_per_rev)  # fmt: skip


#: Accepted steps per call of the compiled clock loop: progress is reported between calls.
CLOCK_CHUNK_STEPS = 200_000


def _integrate_sigma_clock(method, p_ext, r0_m, v0_m_s, tt, rtol, atol, mu, length_m, sigma0,
                           max_steps, progress):  # fmt: skip
    """DOP853 or Vern9 in sigma with the output times found inside the compiled loop
    (:func:`_clock_run`).

    Each output row comes from one extra step of the method, from the start of the step in which tau
    crosses tau_k to the sigma located on that step's dense output; the main integration then
    goes on from that step's start, so the trajectory does not depend on the output times.  The
    small residual g = t_k - t(sigma_k) (the located sigma's bracket, and the interpolant's error
    in tau) is stepped over with the Kepler acceleration: r + v g + a g^2/2, v + a g.
    """
    import time

    from ..integrators.common import ST_ACCEPTED, ST_NJAC, ST_NLU, ST_NRHS, ST_REJECTED
    from ..integrators.common import IntegrationResult, status_message
    from ..integrators.driver import warm_up

    L, T = units(mu, length_m)
    el0 = cartesian_to_dromo(r0_m, v0_m_s, mu, length_m, sigma0)
    z = np.concatenate([[0.0], el0])
    atol_v = np.full(8, float(atol))
    targets = tt / T
    # a sigma bound past the last output (extended by a revolution whenever it is reached first)
    sig_max = predicted_sigma(el0, sigma0, float(tt[-1]), T) + 0.25 * TWO_PI
    m = tt.size
    out_sig = np.empty(m)
    out_z = np.empty((m, 8))
    stats = np.zeros(8, dtype=np.int64)
    compile_s = warm_up(method, dromo_sigma_rhs, 8, p_ext)
    kind = ERK_KINDS[method]
    t0 = time.perf_counter()
    sig, h, k, budget, status = float(sigma0), 0.0, 0, int(max_steps), OK_STATUS
    while k < m:
        acc = int(stats[ST_ACCEPTED])
        status, sig, h, k, sig_max = _clock_run(kind, dromo_sigma_rhs, dromo_clock_event, sig, z, h,
                                                targets, k, p_ext, float(rtol), atol_v, sig_max,
                                                min(CLOCK_CHUNK_STEPS, budget), out_sig, out_z,
                                                stats)  # fmt: skip
        budget -= int(stats[ST_ACCEPTED]) - acc
        if progress is not None:
            progress(float(z[0] * T))
        if status != OK_STATUS and (status != MAX_STEPS_STATUS or budget <= 0):
            break
    wall = time.perf_counter() - t0
    rows = []
    for j in range(k):
        r, v = dromo_to_cartesian(float(out_sig[j]), out_z[j, 1:8], mu, length_m)
        g = float(tt[j] - out_z[j, 0] * T)
        a = -mu * r / float(r @ r) ** 1.5
        rows.append(np.concatenate([r + v * g + 0.5 * a * g * g, v + a * g]))
    Y = np.array(rows).reshape(k, 6)
    st = {"n_accepted": int(stats[ST_ACCEPTED]), "n_rejected": int(stats[ST_REJECTED]),
          "n_rhs": int(stats[ST_NRHS]), "n_jac": int(stats[ST_NJAC]), "n_lu": int(stats[ST_NLU]),
          "wall_s": wall, "compile_s": compile_s, "sigma_end": float(sig),
          # the landing steps, one per output after the start (their rhs calls are in n_rhs)
          "search_n_accepted": int(np.count_nonzero(out_sig[:k] != sigma0)),
          "time_residual_max_s": float(np.max(np.abs(tt[:k] - out_z[:k, 0] * T))) if k else 0.0}  # fmt: skip
    if k == m:
        status, message = 0, f"reached t={tt[-1]!r} (sigma form, sigma={out_sig[-1]:.6f})"
    else:
        message = status_message(int(status), float(z[0] * T), h, int(stats[5]), 0, int(max_steps))
        message += f" (sigma form: sigma={sig!r}, t={z[0] * T!r} s)"
    r_end, v_end = dromo_to_cartesian(float(sig), z[1:8], mu, length_m)
    return IntegrationResult(t=tt[:k].copy(), y=Y, status=int(status), message=message,
                             t_end=float(tt[k - 1]) if k else 0.0,
                             y_end=np.concatenate([r_end, v_end]), stats=st)  # fmt: skip


def _integrate_sigma_grid(method, p_ext, r0_m, v0_m_s, tt, rtol, atol, mu, length_m, sigma0,
                          max_steps, progress, grid_per_rev):  # fmt: skip
    """Sigma form by a sigma grid and a Newton search on t(sigma) for each output time (any
    method; the module docstring)."""
    from ..integrators.driver import IntegrationResult, integrate

    L, T = units(mu, length_m)
    el0 = cartesian_to_dromo(r0_m, v0_m_s, mu, length_m, sigma0)
    z0 = np.concatenate([[0.0], el0])
    atol_v = np.full(8, float(atol))
    t_last = float(tt[-1])
    dsig = TWO_PI / grid_per_rev
    sig_end = predicted_sigma(el0, sigma0, t_last, T) + 0.25 * TWO_PI
    stats: dict = {}
    wall = 0.0

    # pass 1: sigma grid until it passes t_last (extended one revolution at a time if the
    # perturbation made the prediction short)
    sig_grid = [np.array([sigma0])]
    z_grid = [z0[None, :]]
    start_sig, start_z = sigma0, z0
    status, message, budget = 0, "", max_steps
    while True:
        n = max(1, int(math.ceil((sig_end - start_sig) / dsig)))
        grid = start_sig + dsig * np.arange(1, n + 1)
        res = integrate(method, dromo_sigma_rhs, start_sig, start_z, grid, p_ext, rtol, atol_v,
                        max_steps=budget, progress=None)  # fmt: skip
        _add_stats(stats, res.stats)
        wall += res.stats.get("wall_s", 0.0)
        budget -= res.stats.get("n_accepted", 0)
        sig_grid.append(res.t)
        z_grid.append(res.y)
        if progress is not None and len(res.t):
            progress(float(res.y[-1, 0] * T))
        if res.status != 0:
            status, message = res.status, res.message
            break
        if res.y[-1, 0] * T >= t_last or budget <= 0:
            break
        start_sig, start_z = float(res.t[-1]), res.y[-1].copy()
        sig_end = start_sig + TWO_PI
    S = np.concatenate(sig_grid)
    Z = np.concatenate(z_grid)
    tg = Z[:, 0] * T
    if not np.all(np.diff(tg) > 0):
        status = status or 4
        message = message or "time did not increase along sigma (h -> 0 or s <= 0: DROMO singular)"

    # pass 2: each requested time by Newton on t(sigma) from its bracketing grid state
    rows = []
    n_newton = 0
    search: dict = {}  # cost of the time searches, reported apart from the sigma pass
    for tk in tt:
        j = int(np.searchsorted(tg, tk, side="right")) - 1
        if j < 0 or j >= len(S) - 1 and tk > tg[-1]:
            break
        if tk == tg[j] or j == len(S) - 1:
            sig_k, z_k, g = float(S[j]), Z[j], tk - tg[j]
        else:
            sig_k, z_k, g, nn, st = _solve_time(method, p_ext, float(S[j]), Z[j], float(S[j + 1] - S[j]),
                                                tk, T, rtol, atol_v, search)  # fmt: skip
            n_newton += nn
            if st != 0:
                status, message = st, f"time search near t={tk!r} s failed (status {st})"
                break
        r, v = dromo_to_cartesian(sig_k, z_k[1:8], mu, length_m)
        rows.append(np.concatenate([r + v * g, v]))  # first-order step over the residual g (~ulp of t)
    Y = np.array(rows).reshape(len(rows), 6)
    t_done = tt[: len(rows)].copy()
    stats["wall_s"] = wall
    stats["newton_integrations"] = n_newton
    for k in _STAT_KEYS:
        stats["search_" + k] = search.get(k, 0)
    stats["sigma_end"] = float(S[-1])
    z_end = Z[-1]
    r_end, v_end = dromo_to_cartesian(float(S[-1]), z_end[1:8], mu, length_m)
    if status == 0:
        message = f"reached t={t_done[-1]!r} (sigma form, sigma_end={S[-1]:.6f})"
    return IntegrationResult(t=t_done, y=Y, status=int(status), message=message,
                             t_end=float(t_done[-1]) if len(t_done) else 0.0,
                             y_end=np.concatenate([r_end, v_end]), stats=stats)  # fmt: skip


def _solve_time(method, p_ext, sig_a, z_a, width, tk, T, rtol, atol_v, stats):
    """sigma in (sig_a, sig_a + width] with t(sigma) = tk: safeguarded Newton whose evaluations
    integrate from the grid state (sig_a, z_a).  Returns (sigma, z, tk - t(sigma), evals, status)."""
    from ..integrators.driver import integrate

    lo, hi = 0.0, width
    d = (tk - z_a[0] * T) / dt_dsigma(sig_a, z_a, T)
    if not lo < d < hi:
        d = 0.5 * (lo + hi)
    tol = 4.0 * np.finfo(float).eps * max(abs(tk), T)
    for it in range(1, 60):
        res = integrate(method, dromo_sigma_rhs, sig_a, z_a, np.array([sig_a + d]), p_ext, rtol,
                        atol_v)  # fmt: skip
        _add_stats(stats, res.stats)
        if res.status != 0:
            return sig_a + d, z_a, 0.0, it, res.status
        z = res.y[-1]
        sig = sig_a + d
        g = z[0] * T - tk
        if abs(g) <= tol:
            return sig, z, -g, it, 0
        if g < 0:
            lo = d
        else:
            hi = d
        dn = d - g / dt_dsigma(sig, z, T)
        if not lo < dn < hi:
            dn = 0.5 * (lo + hi)
        if hi - lo <= 4.0 * np.finfo(float).eps * max(abs(sig), 1.0):
            return sig, z, -g, it, 0
        d = dn
    return sig, z, -g, it, 0
