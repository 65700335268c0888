"""DROMO: the orbit in ideal-frame elements (Pelaez, Hedo & Rodriguez de Andres, CMDA 97, 2007).

Equations, conventions, derivation and checks: ``docs/dromo.md`` (built on the checked sheet
``shared/references/dromo.md``; its section numbers are cited as "sheet s5" etc.).

Non-dimensional units: length L = |r0| (the initial radius of the root body), time
T = sqrt(L^3/mu), so mu = 1.  Elements (sheet s1): q1, q2 = components of the eccentricity vector
on the ideal axes x, y; q3 = 1/h; eta1..eta4 = Euler parameters of the ideal frame (eta4 scalar).
Central gravity -mu r/r^3 is handled analytically; everything else the scene names (effects, and
for a tether the joint reactions) enters as the perturbing acceleration a_p.

This module is the formulation only: right-hand sides, event functions and conversions.  The
integration drivers (output times in the sigma form, the time form's driver call) are in
:mod:`tetherlab.propagation.dromo`.

Two forms, both compiled cfuncs with the integrators' RHS_SIG:

* :func:`dromo_sigma_rhs` -- a point mass, independent variable the ideal anomaly sigma,
  state z = [tau, q1, q2, q3, eta1, eta2, eta3, eta4] with tau = t/T (sheet s5, s6(a));
* :func:`dromo_time_rhs` -- any scene, independent variable t (s): the root body's orbit in DROMO
  elements with sigma as a state, every other block of the Cowell state (the rods' d_i, d_i',
  the other roots, the rigid bodies' attitudes and the wheels) passed through unchanged,
  state y = [sigma, q1, q2, q3, eta1..eta4, q[3:], q'[3:], attitude, wheels]
  (model/state.py: ``StateLayout.orbit_split``);
  :func:`dromo_time_events` -- the scene's event components (kernel/events.py) on that state.
"""

from __future__ import annotations

import math

import numpy as np
from numba import carray

from .._jit import njit, rhs_cfunc
from ..kernel import effects as _effects
from ..kernel.effects import perturbing_body_force
from ..kernel.layout import (
    FORM_DROMO_SIGMA,
    FORM_DROMO_TIME,
    H_DEFECT,
    H_FORM,
    H_LEN,
    H_NQT,
    H_OFF_FORM,
    H_ROOT_M,
    MUT_TE_SECULAR,
)
from ..kernel.events import event_values
from ..tether.solve import system_accelerations

# Formulation block (at p[H_OFF_FORM]): mu, L, T, Cowell state length, DROMO state length;
# a scratch buffer (q, q', acc of the Cowell coordinates) starts at FP_BUF.
FP_MU, FP_L, FP_T, FP_NCOW, FP_NSTATE = 0, 1, 2, 3, 4
FP_CLOCK = 5  # sigma form: the output time tau_k = t_k/T the clock event looks for
FP_TIME = 6  # sigma form: what state component 0 is (TIME_PHYSICAL or TIME_LINEAR)
FP_BUF = 8
#: sigma form, state component 0: the physical time tau = t/T (sheet s6(a)), or the linear time
#: element tau_l = tau + Phi/n (sheet s6(b), docs/dromo.md section 11), elliptic orbits only
TIME_PHYSICAL, TIME_LINEAR = 0, 1
#: scene names of the two (``integrator.time_element``)
TIME_ELEMENTS = {"none": TIME_PHYSICAL, "linear": TIME_LINEAR}
N_EL = 7  # q1 q2 q3 eta1 eta2 eta3 eta4
TWO_PI = 2.0 * math.pi


# ------------------------------------------------------------------------------------------------
# compiled kernels
# ------------------------------------------------------------------------------------------------
#: The effect sum of :func:`tetherlab.kernel.effects.perturbing_body_force` (the same Python
#: function, not a copy) compiled to be inlined into the sigma-form rhs at numba-IR level: as a
#: separate compiled function it is a call with eleven arguments and a tuple returned through
#: memory, on the rhs's critical path (docs/integrators.md section 8, constant factors).
#: Without cache=True: this instance never runs on its own, it is compiled into the cached cfunc.
_body_force_inlined = njit(inline="always")(_effects._body_force.py_func)

@njit(cache=True, inline="always")
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


@njit(cache=True, inline="always")
def kepler_phase(c, sn, q1, q2, q3):
    """(Phi/n, Phi, n, w, s, kappa) of the linear time element (sheet s6(b); docs/dromo.md 11):
    w = sqrt(1 - q1^2 - q2^2), n = q3^3 w^3 the mean motion, Phi = 2 atan2(kappa, s + w) +
    w kappa/s (= f - E + e sin E, the Kepler part of t measured from the ideal axis), so that
    tau = tau_l - Phi/n.  c, sn = cos sigma, sin sigma.  NaN for e >= 1 (w undefined)."""
    s = 1.0 + q1 * c + q2 * sn
    kap = q1 * sn - q2 * c
    w = math.sqrt(1.0 - q1 * q1 - q2 * q2)
    n = q3 * q3 * q3 * w * w * w
    phi = 2.0 * math.atan2(kap, s + w) + w * kap / s
    return phi / n, phi, n, w, s, kap


@njit(cache=True)
def physical_tau(sigma, y, mode):
    """The non-dimensional physical time tau = t/T of a sigma-form state y (component 0: tau
    itself, or the linear time element, ``mode`` TIME_PHYSICAL / TIME_LINEAR)."""
    if mode == TIME_PHYSICAL:
        return y[0]
    return y[0] - kepler_phase(math.cos(sigma), math.sin(sigma), y[1], y[2], y[3])[0]


@njit(cache=True, inline="always")
def _linear_element_rate(c, sn, y, dy, pn, n, w, s, kap, secular):
    """d tau_l / d sigma = 1/n + grad_q(Phi/n) . q' (sheet s6(b)), from the element rates already
    in dy[1:4], and :func:`kepler_phase`'s Phi/n, n, w, s, kappa.  The Kepler part of dtau/dsigma
    = 1/(q3^3 s^2), sharply peaked at apocentre (1/s^2), cancels analytically into 1/n; what is
    left is proportional to the perturbation.  ``secular`` multiplies the terms Phi d(1/n)/dsigma
    (the mean motion's drift): 1 in every run, 0 only as tetherlab.mutants' deliberate defect."""
    q1 = y[1]
    q2 = y[2]
    q3 = y[3]
    sw = s + w
    den = sw * sw + kap * kap
    w1 = -q1 / w
    w2 = -q2 / w
    # kappa_1 = sin, kappa_2 = -cos, s_1 = cos, s_2 = sin (derivatives with respect to q1, q2)
    ks = w * kap / (s * s)
    f1 = 2.0 * (sw * sn - kap * (c + w1)) / den + (w1 * kap + w * sn) / s - ks * c
    f2 = 2.0 * (-sw * c - kap * (sn + w2)) / den + (w2 * kap - w * c) / s - ks * sn
    iw2 = 3.0 * pn / (w * w) * secular
    g1 = f1 / n + iw2 * q1
    g2 = f2 / n + iw2 * q2
    g3 = -3.0 * pn / q3 * secular
    dy[0] = 1.0 / n + g1 * dy[1] + g2 * dy[2] + g3 * dy[3]


@njit(cache=True)
def sigma_rates(c, sn, y, fr, ft, fn, dy):
    """d/dsigma of [tau, q1, q2, q3, eta1..eta4] into dy[0:8], for the non-dimensional
    perturbation (fr, ft, fn) in the orbital frame (sheet s5; docs/dromo.md section 3);
    c, sn = cos sigma, sin sigma."""
    q3 = y[3]
    s = 1.0 + y[1] * c + y[2] * sn
    den = q3 * q3 * q3 * s * s * q3 * s  # q3^4 s^3
    _scaled_rates(c, sn, y, fr / den, ft / den, fn / den, dy)


@njit(cache=True, inline="always")
def _scaled_rates(c, sn, y, ax, ay, az, dy):
    """:func:`sigma_rates` from the perturbation already divided by q3^4 s^3 (ax = fr / (q3^4
    s^3), ...): the sigma form folds that factor into one multiplier computed from the
    elements alone, off the path from the force to the rates (:func:`dromo_sigma_rhs`)."""
    q1 = y[1]
    q2 = y[2]
    q3 = y[3]
    e1 = y[4]
    e2 = y[5]
    e3 = y[6]
    e4 = y[7]
    s = 1.0 + q1 * c + q2 * sn
    q3s = q3 * q3 * q3 * s * s
    dy[0] = 1.0 / q3s
    dy[1] = s * sn * ax + (q1 + (1.0 + s) * c) * ay
    dy[2] = -s * c * ax + (q2 + (1.0 + s) * sn) * ay
    dy[3] = -q3 * ay
    h = 0.5 * az
    dy[4] = h * (e4 * c - e3 * sn)
    dy[5] = h * (e3 * c + e4 * sn)
    dy[6] = h * (-e2 * c + e1 * sn)
    dy[7] = h * (-e1 * c - e2 * sn)


@njit(cache=True, inline="always")
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
    # One multiplier k = (L^2/mu) / (m0 q3^4 s^3) takes the force (N) to the scaled rates'
    # inputs fr/(q3^4 s^3), ...: it depends on the elements only, so its division runs beside the
    # force evaluation instead of two divisions (by m0, by q3^4 s^3) after it on the rhs's
    # critical path (docs/integrators.md section 8: ~10 % of the rhs latency; the rates change
    # by rounding only).
    q3 = y[3]
    s = 1.0 + y[1] * c + y[2] * sn
    k = (L * L / mu) / (m0 * (q3 * q3 * q3 * s * s * q3 * s))
    linear = p[off + FP_TIME] == TIME_LINEAR
    tau = y[0]
    pn = n = w = s_ = kap = 1.0
    if linear:  # tau = tau_l - Phi/n: off the force's path unless an effect depends on time
        pn, phi, n, w, s_, kap = kepler_phase(c, sn, y[1], y[2], q3)
        tau -= pn
    # central gravity is the Kepler part DROMO integrates analytically: only the rest is evaluated
    fx, fy, fz = _body_force_inlined(p, T * tau, 0, rx, ry, rz, vx, vy, vz, m0, False)
    _scaled_rates(c, sn, y, (fx * ix + fy * iy + fz * iz) * k, (fx * jx + fy * jy + fz * jz) * k,
                  (fx * kx + fy * ky + fz * kz) * k, dy)  # fmt: skip
    if linear:
        secular = 0.0 if p[H_DEFECT] == MUT_TE_SECULAR else 1.0
        _linear_element_rate(c, sn, y, dy, pn, n, w, s_, kap, secular)
    return 0


@rhs_cfunc
def dromo_time_rhs(t, y_ptr, dy_ptr, p_ptr):
    p = carray(p_ptr, (int(p_ptr[H_LEN]),))
    off = int(p[H_OFF_FORM])
    mu = p[off + FP_MU]
    L = p[off + FP_L]
    T = p[off + FP_T]
    h = int(p[H_NQT])  # q_trans of the Cowell state
    n = int(p[off + FP_NSTATE])  # 8 + 2 (h - 3) + the attitude and wheel blocks
    y = carray(y_ptr, (n,))
    dy = carray(dy_ptr, (n,))
    nd = h - 3
    a0 = 8 + 2 * nd  # the first-order blocks pass through: the Cowell kernel's own derivatives
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
    status = system_accelerations(t, q, qd, y[a0:n], p, acc, dy[a0:n])
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


@rhs_cfunc
def dromo_time_events(t, y_ptr, g_ptr, p_ptr):
    """The scene's event components (kernel/events.py: ``[stop] altitude``, tension-only rods) on
    the time-form state: the Cowell state [r0, d, v0, d'] is rebuilt in the formulation block's
    buffer (docs/dromo.md section 7) and the Cowell event values are computed on it, so both
    formulations locate the same functions of the same physical state."""
    p = carray(p_ptr, (int(p_ptr[H_LEN]),))
    off = int(p[H_OFF_FORM])
    L = p[off + FP_L]
    T = p[off + FP_T]
    h = int(p[H_NQT])
    n = int(p[off + FP_NSTATE])
    y = carray(y_ptr, (n,))
    nd = h - 3
    b = off + FP_BUF
    yc = p[b : b + 2 * h]  # [q, q'] of the Cowell coordinates (the rhs's q and qd buffers)
    rx, ry, rz, vx, vy, vz = root_state(y[0], y, L, T)[:6]
    yc[0] = rx
    yc[1] = ry
    yc[2] = rz
    yc[h] = vx
    yc[h + 1] = vy
    yc[h + 2] = vz
    for i in range(nd):
        yc[3 + i] = y[8 + i]
        yc[h + 3 + i] = y[8 + nd + i]
    event_values(t, yc, g_ptr, p)
    return 0


# ------------------------------------------------------------------------------------------------
# conversions (set-up and output; NumPy)
# ------------------------------------------------------------------------------------------------
def units(mu_m3_s2: float, length_m: float) -> tuple[float, float]:
    """(L, T): the length unit and T = sqrt(L^3/mu) (sheet s3)."""
    if not (mu_m3_s2 > 0 and length_m > 0):
        raise ValueError(f"DROMO units: expected mu > 0 and L > 0; got mu={mu_m3_s2!r}, L={length_m!r}")
    return float(length_m), math.sqrt(length_m**3 / mu_m3_s2)


def quaternion_from_frame(R) -> np.ndarray:
    """Euler parameters (eta1, eta2, eta3, eta4) of the rotation whose columns are x, y, k
    (the convention of sheet s1), by Shepperd's method: divide by the largest component, so no
    geometry (retrograde equatorial included) divides by zero (sheet s4 step 4).  ``R`` is a 3x3
    array or nested sequence; its entries are read once as floats (plain-float arithmetic: this
    runs once per integration, and NumPy calls on 3-vectors cost microseconds each)."""
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = ((float(v) for v in row) for row in R)
    tr = r00 + r11 + r22
    cand = (tr, r00, r11, r22)
    k = max(range(4), key=cand.__getitem__)  # the first largest, as np.argmax
    if k == 0:
        w = 0.5 * math.sqrt(1.0 + tr)
        f = 0.25 / w
        e = (f * (r21 - r12), f * (r02 - r20), f * (r10 - r01), w)
    elif k == 1:
        x = 0.5 * math.sqrt(1.0 + r00 - r11 - r22)
        f = 0.25 / x
        e = (x, f * (r01 + r10), f * (r02 + r20), f * (r21 - r12))
    elif k == 2:
        y = 0.5 * math.sqrt(1.0 - r00 + r11 - r22)
        f = 0.25 / y
        e = (f * (r01 + r10), y, f * (r12 + r21), f * (r02 - r20))
    else:
        z = 0.5 * math.sqrt(1.0 - r00 - r11 + r22)
        f = 0.25 / z
        e = (f * (r02 + r20), f * (r12 + r21), z, f * (r10 - r01))
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
    R = [[x[a], y[a], k[a]] for a in range(3)]
    q1 = e[0] * x[0] + e[1] * x[1] + e[2] * x[2]
    q2 = e[0] * y[0] + e[1] * y[1] + e[2] * y[2]
    return np.concatenate([[q1, q2, 1.0 / h], quaternion_from_frame(R)])


def _cross(ax, ay, az, bx, by, bz):
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


def dromo_to_cartesian(sigma: float, elements, mu_m3_s2: float, length_m: float) -> tuple[np.ndarray, np.ndarray]:
    """(r in m, v in m/s) from the ideal anomaly and the DROMO elements (sheet s7).

    Plain floats, the same operations as the vector form r = (L/(q3^2 s)) i,
    v = (L/T)(q3 kappa i + q3 s j) with i = cos(sigma) x + sin(sigma) y, j = -sin(sigma) x +
    cos(sigma) y and x, y the first two columns of :func:`frame_from_quaternion` (bit-for-bit:
    tests/test_dromo.py); NumPy on 3-vectors cost ~15 us a call here, three calls a run."""
    L, T = units(mu_m3_s2, length_m)
    q1, q2, q3, e1, e2, e3, e4 = (float(v) for v in elements[:7])
    # columns x, y of R = [x y k] (frame_from_quaternion)
    x = (1 - 2 * (e2 * e2 + e3 * e3), 2 * (e1 * e2 + e3 * e4), 2 * (e1 * e3 - e2 * e4))
    y = (2 * (e1 * e2 - e3 * e4), 1 - 2 * (e1 * e1 + e3 * e3), 2 * (e2 * e3 + e1 * e4))
    c, sn = math.cos(sigma), math.sin(sigma)
    s = 1.0 + q1 * c + q2 * sn
    kap = q1 * sn - q2 * c
    rn = L / (q3 * q3 * s)
    vs = L / T
    a = q3 * kap
    b = q3 * s
    r = np.empty(3)
    v = np.empty(3)
    for n in range(3):
        i = c * x[n] + sn * y[n]
        j = -sn * x[n] + c * y[n]
        r[n] = rn * i
        v[n] = vs * (a * i + b * j)
    return r, v


def sigma_state(r_m, v_m_s, mu_m3_s2: float, length_m: float, sigma0: float = 0.0, tau0: float = 0.0,
                time_element: int = TIME_PHYSICAL) -> np.ndarray:  # fmt: skip
    """The sigma form's initial state [tau or tau_l, q1, q2, q3, eta1..eta4] at time tau0 = t0/T."""
    el = cartesian_to_dromo(r_m, v_m_s, mu_m3_s2, length_m, sigma0)
    z = np.concatenate([[tau0], el])
    if time_element == TIME_LINEAR:
        e2 = float(el[0] * el[0] + el[1] * el[1])
        if not e2 < 1.0:
            raise ValueError(f"the linear time element needs an elliptic orbit; got e = {math.sqrt(e2):.6g}")
        z[0] = tau0 + kepler_phase(math.cos(sigma0), math.sin(sigma0), float(el[0]), float(el[1]), float(el[2]))[0]
    return z


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
def attach(p: np.ndarray, form: int, mu_m3_s2: float, length_m: float, n_cowell: int,
           time_element: int = TIME_PHYSICAL) -> np.ndarray:  # fmt: skip
    """A copy of the model's parameter block with the DROMO block appended (header H_OFF_FORM).
    ``time_element``: what the sigma form's state component 0 is (TIME_PHYSICAL or TIME_LINEAR)."""
    if form not in (FORM_DROMO_SIGMA, FORM_DROMO_TIME):
        raise ValueError(f"form: expected FORM_DROMO_SIGMA or FORM_DROMO_TIME; got {form!r}")
    if time_element not in (TIME_PHYSICAL, TIME_LINEAR) or (form == FORM_DROMO_TIME and time_element != TIME_PHYSICAL):
        raise ValueError(f"time_element: expected TIME_PHYSICAL, or TIME_LINEAR with the sigma form; got {time_element!r}")
    L, T = units(mu_m3_s2, length_m)
    h = int(p[H_NQT])
    # the time form: the root orbit's 6 Cowell components become sigma and the 7 elements
    n_state = 8 if form == FORM_DROMO_SIGMA else n_cowell + 2
    off = p.size
    block = np.zeros(FP_BUF + 3 * h)
    block[FP_MU] = mu_m3_s2
    block[FP_L] = L
    block[FP_T] = T
    block[FP_NCOW] = n_cowell
    block[FP_NSTATE] = n_state
    block[FP_TIME] = time_element
    out = np.concatenate([p, block])
    out[H_LEN] = out.size
    out[H_OFF_FORM] = off
    out[H_FORM] = form
    return out


def time_state(y_cowell: np.ndarray, layout, mu_m3_s2: float, length_m: float, sigma0: float = 0.0) -> np.ndarray:
    """Time-form state [sigma, elements, pass-through] from a Cowell state (``layout``: its
    :class:`~tetherlab.model.state.StateLayout`; only the root orbit is mapped)."""
    r, v, rest = layout.orbit_split(y_cowell)
    el = cartesian_to_dromo(r, v, mu_m3_s2, length_m, sigma0)
    return np.concatenate([[sigma0], el, rest])


def cowell_state(y_time: np.ndarray, layout, mu_m3_s2: float, length_m: float) -> np.ndarray:
    """Cowell state from a time-form state [sigma, elements, pass-through] (:func:`time_state`)."""
    r, v = dromo_to_cartesian(y_time[0], y_time[1:8], mu_m3_s2, length_m)
    return layout.orbit_join(r, v, y_time[8:])
