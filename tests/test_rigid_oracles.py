"""Self-checks of the rigid-body oracles (docs/rigid-oracles.md), without the simulator.

Each oracle (tetherlab/oracles/{torque_free, gg_attitude, spinning_spokes, wheel_exchange}.py,
derivations in docs/rigid-oracles.md) is checked against a second, independent method: the
differential equations it claims to solve (residuals by analytic or finite-difference
derivatives) and a scipy integration or collocation at tight tolerance.  The stored data
(references/rigid_bodies/reference.json) is checked to be what the oracles give today.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from tests.helpers import ROOT
from tetherlab.oracles import gg_attitude as gg
from tetherlab.oracles import spinning_spokes as ss
from tetherlab.oracles import torque_free as tf
from tetherlab.oracles import wheel_exchange as we
from tetherlab.oracles.continuum import fit_frequencies

REF = json.loads((ROOT / "references" / "rigid_bodies" / "reference.json").read_text())
I_TOP = (200.0, 300.0, 450.0)  # kg m^2, the reference cases' body
C0 = tf.quat_to_matrix([math.cos(0.3), *(math.sin(0.3) * np.array([1.0, 2.0, 2.0]) / 3.0)])


# -- 1. torque-free rigid body ----------------------------------------------------------------------
# rates chosen to cover both regimes, every sign pattern of the non-sign-changing component, and a
# case close to the separatrix (m near 1)
CASES = [
    ((0.02, 0.04, 0.2), tf.MAJOR),
    ((-0.05, 0.03, -0.1), tf.MAJOR),
    ((0.2, 0.06, -0.04), tf.MINOR),
    ((-0.1, -0.08, 0.03), tf.MINOR),
    ((0.1, 0.001, 0.0815), None),  # near the separatrix: either regime, m close to 1
]


@pytest.mark.parametrize("w0, regime", CASES)
def test_closed_form_rates_satisfy_euler_equations(w0, regime):
    top = tf.euler_top(I_TOP, w0, C0)
    if regime is not None:
        assert top.regime == regime
    t = np.linspace(0.0, 3.0 * top.period_s, 997)
    w = tf.rates(top, t)
    # initial condition reproduced to round-off
    assert np.max(np.abs(w[0] - w0)) < 1e-15 * 8
    # Euler's equations I w' + w x I w = 0 with the analytic derivatives of sn, cn, dn: the
    # residual is round-off of |H| |w| ~ 1e2 * 0.2 (N m)
    scale = top.h_N_m_s * float(np.max(np.abs(w)))
    assert np.max(np.abs(tf.euler_residual(top, t))) < 1e-13 * scale
    # the analytic derivative itself against a central difference (error ~ h^2 w''' / 6)
    h = 1e-4 * top.period_s
    fd = (tf.rates(top, t + h) - tf.rates(top, t - h)) / (2 * h)
    assert np.max(np.abs(fd - tf.rate_derivatives(top, t))) < 1e-6 * float(np.max(np.abs(tf.rate_derivatives(top, t))))
    # invariants 2T and H^2 of Euler's equations are constant along the closed form
    I = np.array(I_TOP)
    assert np.ptp(np.sum(I * w * w, axis=1)) < 1e-14 * top.energy2_J * 10
    assert np.ptp(np.linalg.norm(I * w, axis=1)) < 1e-14 * top.h_N_m_s * 10


@pytest.mark.parametrize("w0, regime", CASES[:4])
def test_closed_form_against_dop853_and_period(w0, regime):
    top = tf.euler_top(I_TOP, w0, C0)
    t = np.linspace(0.0, 4.0 * top.period_s, 201)
    wr, Cr = tf.integrate_reference(I_TOP, w0, C0, t)  # scipy DOP853 at rtol 1e-13
    w = tf.rates(top, t)
    # 4 periods at rtol 1e-13: the reference's own error is ~1e-13 relative (measured 1e-14)
    assert np.max(np.abs(w - wr)) < 1e-11 * np.max(np.abs(w))
    # the rates repeat after the period 4 K / lam (L&L section 37)
    assert np.max(np.abs(tf.rates(top, t + top.period_s) - w)) < 1e-13
    # the attitude: 3-1-3 angles about the fixed H, psi by quadrature, against the quaternion
    # kinematics integrated by DOP853
    C = tf.attitude(top, t)
    assert np.max(tf.rotation_angle(C, Cr)) < 1e-10  # rad
    assert np.max(np.abs(C[0] - C0)) < 1e-14
    # H in the inertial frame is fixed
    H = np.einsum("nij,nj->ni", C, np.array(I_TOP) * w)
    assert np.max(np.abs(H - top.h_inertial)) < 1e-13 * top.h_N_m_s


@pytest.mark.parametrize("w0, regime", CASES)
def test_psi_closed_form_against_quadrature(w0, regime):
    # psi by the elliptic integral of the third kind (Carlson R_F, R_J) against Gauss-Kronrod
    # quadrature of psi' = H (I1 w1^2 + I2 w2^2)/(I1^2 w1^2 + I2^2 w2^2) (L&L section 37)
    top = tf.euler_top(I_TOP, w0, C0)
    t = np.linspace(0.0, 5.0 * top.period_s, 23)
    a = tf.euler_angles_313(top, t, psi_method="closed")[:, 0]
    b = tf.euler_angles_313(top, t, psi_method="quad")[:, 0]
    assert np.max(np.abs(a - b)) < 1e-11  # rad, over psi growing to ~100 rad


def test_torque_free_input_errors():
    with pytest.raises(ValueError, match="I1 < I2 < I3"):
        tf.euler_top((300.0, 200.0, 450.0), (0.1, 0.1, 0.1))
    with pytest.raises(ValueError, match="I1 \\+ I2 >= I3"):
        tf.euler_top((100.0, 200.0, 450.0), (0.1, 0.1, 0.1))
    with pytest.raises(ValueError, match="steady"):
        tf.euler_top(I_TOP, (0.0, 0.0, 0.3))
    # on the separatrix H^2 = 2T I2: I3 w3^2 (I3 - I2) = I1 w1^2 (I2 - I1)
    w1 = 0.1
    w3 = w1 * math.sqrt(I_TOP[0] * (I_TOP[1] - I_TOP[0]) / (I_TOP[2] * (I_TOP[2] - I_TOP[1])))
    with pytest.raises(ValueError, match="separatrix"):
        tf.euler_top(I_TOP, (w1, 0.05, w3))


def test_torque_free_reference_data():
    # reference.json holds what the oracle gives (rebuild with the builder if this fails)
    for name, c in REF["torque_free"].items():
        top = tf.euler_top(c["inertia_kg_m2"], c["w0_rad_s"], tf.quat_to_matrix(c["q0"]))
        assert top.regime == c["regime"] == name
        assert math.isclose(top.period_s, c["period_s"], rel_tol=1e-14)
        t = np.asarray(c["samples"]["t_s"])[::50]
        assert np.max(np.abs(tf.rates(top, t) - np.asarray(c["samples"]["w_rad_s"])[::50])) < 1e-15 * 10
        assert c["second_method"]["max_rate_difference_rad_s"] < 1e-12
        assert c["second_method"]["max_attitude_difference_rad"] < 1e-10


# -- 2. gravity-gradient libration ----------------------------------------------------------------
def test_gg_linear_frequencies_are_the_eigenvalues_of_the_linearised_equations():
    n = 1.1e-3
    for I in [(150.0, 200.0, 100.0), (300.0, 320.0, 100.0), (90.0, 200.0, 120.0)]:
        lo, hi = gg.roll_yaw_frequencies(n, *I)
        ev = np.sort(np.abs(np.linalg.eigvals(gg.roll_yaw_matrix(n, *I)).imag))
        assert np.allclose(ev, [lo, lo, hi, hi], rtol=1e-12, atol=0)
        # the quartic's roots: W^4 - (1 + 3 k1 + k1 k3) W^2 + 4 k1 k3 = 0 (Hughes ch. 9)
        k1, k3 = gg.k_ratios(*I)
        for w in (lo / n, hi / n):
            assert abs(w**4 - (1 + 3 * k1 + k1 * k3) * w**2 + 4 * k1 * k3) < 1e-13
    # pitch: n sqrt(3 (Ix - Iz)/Iy)
    assert math.isclose(gg.pitch_frequency(n, 150.0, 200.0, 100.0), n * math.sqrt(0.75), rel_tol=1e-15)


def test_gg_stability_conditions():
    assert gg.stability(150.0, 200.0, 100.0).all  # Lagrange region Iy > Ix > Iz
    assert not gg.stability(100.0, 200.0, 150.0).pitch  # Iz > Ix: pitch unstable
    with pytest.raises(ValueError, match="pitch is unstable"):
        gg.pitch_frequency(1e-3, 100.0, 200.0, 150.0)
    # Ix > Iy > Iz: k1 > 0, k3 < 0, roll-yaw unstable (Hughes' region "unstable yaw")
    st = gg.stability(200.0, 150.0, 100.0)
    assert st.pitch and not st.roll_yaw
    with pytest.raises(ValueError, match="roll-yaw"):
        gg.roll_yaw_frequencies(1e-3, 200.0, 150.0, 100.0)


def test_gg_nonlinear_run_recovers_the_linear_frequencies():
    # independent scipy integration of the full attitude equations (quaternion, exact torque),
    # amplitude 1e-3 rad: the frequencies move by ~A^2/4 = 2.5e-7 (the pendulum's amplitude
    # correction for pitch, 2 theta as its angle); 8 orbits, least-squares fit
    I = (150.0, 200.0, 100.0)
    R, mu = 7.0e6, 3.986004418e14
    n = math.sqrt(mu / R**3)
    t = np.linspace(0.0, 8 * 2 * math.pi / n, 2001)
    wp = gg.pitch_frequency(n, *I)
    lo, hi = gg.roll_yaw_frequencies(n, *I)
    a = gg.integrate_nonlinear(I, R, mu, (0.0, 1e-3, 0.0), (0.0, 0.0, 0.0), t)
    assert np.max(np.abs(a[:, [0, 2]])) < 1e-13  # planar pitch stays planar
    assert abs(fit_frequencies(t, a[:, 1], [wp])[0][0] / wp - 1) < 1e-6
    a = gg.integrate_nonlinear(I, R, mu, (1e-3, 0.0, 1e-3), (0.0, 0.0, 0.0), t)
    f = np.sort(fit_frequencies(t, a[:, 0], [lo, hi])[0])
    assert np.max(np.abs(f / np.array([lo, hi]) - 1)) < 1e-6
    assert np.max(np.abs(a[:, 1])) < 10 * 1e-3**2  # roll-yaw excites pitch at second order only (A^2)


def test_gg_angles_round_trip():
    c = gg.matrix_from_rpy(0.1, -0.2, 0.3)
    assert np.allclose(gg.rpy_from_matrix(c), [0.1, -0.2, 0.3], rtol=0, atol=1e-15)
    o = gg.orbit_frame([7e6, 0.0, 0.0], [0.0, 7.5e3, 0.0])
    # x along-track, y minus the orbit normal, z nadir (docs/scenes.md "Orbit frame")
    assert np.allclose(o, [[0, 1, 0], [0, 0, -1], [-1, 0, 0]], atol=1e-15)


def test_gg_reference_data():
    g = REF["gravity_gradient"]
    Ix, Iy, Iz = g["inertia_roll_pitch_yaw_kg_m2"]
    n = math.sqrt(g["mu_m3_s2"] / g["radius_m"] ** 3)
    assert math.isclose(g["pitch_rad_s"], gg.pitch_frequency(n, Ix, Iy, Iz), rel_tol=1e-15)
    assert np.allclose([g["roll_yaw_low_rad_s"], g["roll_yaw_high_rad_s"]], gg.roll_yaw_frequencies(n, Ix, Iy, Iz), rtol=1e-15)
    assert max(g["second_method"]["relative_frequency_errors"].values()) < 1e-6


# -- 3. hub and spoke -------------------------------------------------------------------------------
SPOKE = dict(length_m=100.0, EA_N=2.0e4, rho_kg_m=0.02, tip_mass_kg=5.0)


@pytest.mark.parametrize("r_h", [0.0, 2.0])
@pytest.mark.parametrize("omega", [0.1, 0.5, 1.5])
def test_spoke_closed_form_solves_the_bvp(omega, r_h):
    sp = ss.spoke_profile(omega, hub_radius_m=r_h, **SPOKE)
    s = np.linspace(0.0, SPOKE["length_m"], 201)
    # boundary conditions: x(0) = r_h, T(L) = m_f Omega^2 x(L)
    assert abs(sp.x(0.0) - r_h) < 1e-15
    assert abs(sp.tip_tension_N - SPOKE["tip_mass_kg"] * omega**2 * sp.tip_radius_m) < 1e-12 * sp.hub_tension_N
    # the ODEs x' = 1 + T/EA, T' = -rho Omega^2 x by central differences (error ~ h^2 x'''/6)
    h = 1e-3
    xp = (sp.x(s + h) - sp.x(s - h)) / (2 * h)
    Tp = (sp.tension(s + h) - sp.tension(s - h)) / (2 * h)
    assert np.max(np.abs(xp - 1.0 - sp.tension(s) / SPOKE["EA_N"])) < 1e-9
    assert np.max(np.abs(Tp + SPOKE["rho_kg_m"] * omega**2 * sp.x(s))) < 1e-7 * sp.hub_tension_N
    # independent: scipy's collocation solver
    sol = ss.spoke_profile_bvp(omega, hub_radius_m=r_h, **SPOKE)
    xb, Tb = sol.sol(s)
    assert np.max(np.abs(xb - sp.x(s))) < 1e-8  # m
    assert np.max(np.abs(Tb - sp.tension(s))) < 1e-8 * sp.hub_tension_N


@pytest.mark.parametrize("r_h", [0.0, 2.0])
def test_spoke_inextensible_limit(r_h):
    # as EA grows the extensible profile tends to Omega^2 [m_f (r_h + L) + rho (L - s)(r_h + (L + s)/2)]
    # with a strain ~ T/EA, so the relative difference falls like 1/EA
    s = np.linspace(0.0, 100.0, 51)
    inx = ss.spoke_profile_inextensible(0.5, 100.0, 0.02, 5.0, r_h)
    prev = None
    for EA in (1e5, 1e6, 1e7):
        sp = ss.spoke_profile(0.5, 100.0, EA, 0.02, 5.0, r_h)
        d = np.max(np.abs(sp.tension(s) - inx.tension(s))) / inx.tension(0.0)
        eps = inx.tension(0.0) / EA
        assert d < 2 * eps
        if prev is not None:
            assert 8 < prev / d < 12  # first order in 1/EA
        prev = d


def test_spoke_angular_momentum_and_spin_inverse():
    for r_h, J_hub in ((0.0, 0.0), (2.0, 50.0)):
        H = ss.angular_momentum(0.5, 4, J_hub, 100.0, hub_radius_m=r_h, **SPOKE)
        # quadrature check of the closed-form moment of inertia int rho x^2 ds + m_f x(L)^2
        sp = ss.spoke_profile(0.5, hub_radius_m=r_h, **SPOKE)
        s = np.linspace(0.0, 100.0, 20001)
        Ixx = np.trapezoid(SPOKE["rho_kg_m"] * sp.x(s) ** 2, s) + SPOKE["tip_mass_kg"] * sp.tip_radius_m**2
        assert math.isclose(sp.moment_of_inertia_kg_m2(), Ixx, rel_tol=1e-8)
        assert math.isclose(H, 0.5 * (J_hub + 4 * Ixx), rel_tol=1e-8)
        w = ss.spin_for_angular_momentum(H, 4, J_hub, hub_radius_m=r_h, **SPOKE)
        assert abs(w - 0.5) < 1e-14


def test_spoke_input_errors():
    with pytest.raises(ValueError, match="steady state exists"):
        ss.spoke_profile(40.0, **SPOKE)
    with pytest.raises(ValueError, match="EA_N"):
        ss.spoke_profile(0.5, 100.0, -1.0, 0.02, 5.0)


def test_spoke_reference_data():
    h = REF["hub_spoke"]
    tt = h["tether"]
    for name in ("centre", "radius"):
        c = h[name]
        sp = ss.spoke_profile(h["omega0_rad_s"], tt["length_m"], tt["EA_N"], tt["rho_kg_m"], tt["tip_mass_kg"], c["hub_radius_m"])
        assert math.isclose(sp.hub_tension_N, c["hub_tension_N"], rel_tol=1e-14)
        assert c["second_method"]["max_tension_difference_N"] < 1e-6
        # the inextensible limit is within the strain (~1 %) of the extensible tension
        assert abs(c["inextensible"]["hub_tension_N"] / c["hub_tension_N"] - 1) < 2 * c["hub_tension_N"] / tt["EA_N"]


# -- 4. momentum exchange ---------------------------------------------------------------------------
def test_single_axis_exchange_closed_form():
    sa = we.SingleAxis(10.0, 0.5, 0.2, 30.0, (0.0, 5.0, 12.0), (0.3, -0.1, 0.0))
    t = np.linspace(0.0, 20.0, 401)
    w, Om = sa.state(t)
    # total angular momentum J w + Iw Omega is constant (no external torque)
    H = sa.angular_momentum(t)
    assert np.ptp(H) < 4e-16 * abs(H[0]) * 10
    # the body loses exactly what the wheel gains: (J - Iw) dw = -d[Iw (w + Omega)] = -int M dt
    dh = sa.wheel_absolute_momentum(t) - sa.wheel_absolute_momentum(0.0)
    assert np.max(np.abs((10.0 - 0.5) * (w - w[0]) + dh)) < 1e-14
    imp, _ = sa.impulse(t)
    assert np.max(np.abs(dh - imp)) < 1e-14
    # energy change equals the motor work int M Omega dt (closed form) ...
    assert np.max(np.abs(sa.energy(t) - sa.energy(0.0) - sa.motor_work(t))) < 1e-12 * sa.energy(0.0)
    # ... and the work by trapezoidal quadrature of M Omega (exact for a linear Omega between
    # switches; the switches 5 and 12 s are sample points)
    M = np.select([t < 5.0, t < 12.0], [0.3, -0.1], 0.0)  # constant on [t_i, t_i+1): its left value
    work_q = np.concatenate([[0.0], np.cumsum(M[:-1] * 0.5 * (Om[1:] + Om[:-1]) * np.diff(t))])
    assert np.max(np.abs(work_q - sa.motor_work(t))) < 1e-11


def test_single_axis_against_gyrostat_integration():
    # the 3-axis gyrostat equations by DOP853, body spinning about its z axis, torque constant
    sa = we.SingleAxis(10.0, 0.5, 0.2, 30.0, (0.0,), (0.3,))
    t = np.linspace(0.0, 8.0, 33)
    r = we.integrate_gyrostat(np.diag([6.0, 8.0, 10.0]), [[0, 0, 1]], [0.5], [0, 0, 0.2], [30.0], np.eye(3), t,
                              lambda *_: [0.3])  # fmt: skip
    w, Om = sa.state(t)
    assert np.max(np.abs(r["w"][:, 2] - w)) < 1e-12
    assert np.max(np.abs(r["Omega"][:, 0] - Om)) < 1e-10
    assert np.max(np.abs(r["energy"] - sa.energy(t))) < 1e-10


def test_gyrostat_conservation_three_wheels():
    # tumbling body, three wheels with motor torques: |H| and H inertial fixed, E - work fixed
    r = we.integrate_gyrostat(np.diag([6.0, 8.0, 10.0]), np.eye(3), [0.1, 0.1, 0.1], [0.1, -0.2, 0.3],
                              [10.0, -20.0, 30.0], C0, np.linspace(0.0, 20.0, 41),
                              lambda t, w, O: [0.01, -0.02, 0.03 * math.sin(t)])  # fmt: skip
    H = r["H_inertial"]
    assert np.max(np.abs(H - H[0])) < 1e-11 * np.linalg.norm(H[0])
    assert np.max(np.abs(r["energy"] - r["energy"][0] - r["work"])) < 1e-11 * r["energy"][0]


def test_wheel_reference_data():
    c = REF["wheel_single_axis"]
    sa = we.SingleAxis(c["J_kg_m2"], c["Iw_kg_m2"], c["w0_rad_s"], c["Omega0_rad_s"], tuple(c["switch_times_s"]),
                       tuple(c["torques_N_m"]))  # fmt: skip
    t = np.asarray(c["samples"]["t_s"])
    assert np.max(np.abs(sa.state(t)[1] - np.asarray(c["samples"]["Omega_rad_s"]))) < 1e-12
    assert c["second_method"]["max_work_difference_J"] < 1e-10
