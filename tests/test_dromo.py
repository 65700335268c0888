"""DROMO (tetherlab/formulations/dromo.py; derivation docs/dromo.md).

* Cartesian -> DROMO -> Cartesian round trip to round-off (shared/references/dromo.md s9 reports
  <= 4e-15 relative for the same kinds of orbits);
* on an unperturbed orbit the DROMO elements stay constant and the position at requested
  physical times matches Kepler's equation solved here independently;
* the time form on a tethered scene agrees with Cowell;
* the stiefel_moon effect against its definition (shared/references/stiefel-scheifele.md);
* scene validation of [integrator] formulation.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.helpers import SCENES
from tetherlab.errors import SceneError
from tetherlab.formulations import dromo
from tetherlab.propagation import dromo as drive
from tetherlab.pipeline import simulate
from tetherlab.scene import Scene, load_scene

MU = 3.986004418e14  # m^3/s^2, scene preset "earth" (WGS 84)


def _kepler_state(a, e, inc, raan, argp, nu):
    p = a * (1 - e * e)
    r_pf = np.array([math.cos(nu), math.sin(nu), 0.0]) * p / (1 + e * math.cos(nu))
    v_pf = np.array([-math.sin(nu), e + math.cos(nu), 0.0]) * math.sqrt(MU / p)
    cO, sO, ci, si, cw, sw = (math.cos(raan), math.sin(raan), math.cos(inc), math.sin(inc),
                              math.cos(argp), math.sin(argp))  # fmt: skip
    Q = np.array([
        [cO * cw - sO * sw * ci, -cO * sw - sO * cw * ci, sO * si],
        [sO * cw + cO * sw * ci, -sO * sw + cO * cw * ci, -cO * si],
        [sw * si, cw * si, ci],
    ])  # fmt: skip
    return Q @ r_pf, Q @ v_pf


ROUND_TRIP_CASES = {
    # Stiefel-Scheifele initial state, paper eqs. 50-51 (km, km/s -> m, m/s)
    "stiefel": (np.array([0.0, -5888.9727e3, -3400.0e3]), np.array([10691.338, 0.0, 0.0])),
    "circular-equatorial": _kepler_state(7000e3, 0.0, 0.0, 0.0, 0.0, 0.3),
    "retrograde-equatorial": _kepler_state(7000e3, 0.1, math.pi, 0.0, 0.4, 1.0),
    "hyperbolic": _kepler_state(-20000e3, 1.5, 0.5, 1.0, 2.0, 0.7),
    "polar-eccentric": _kepler_state(26000e3, 0.74, math.pi / 2, 2.0, 4.5, 3.0),
}


@pytest.mark.parametrize("case", sorted(ROUND_TRIP_CASES))
@pytest.mark.parametrize("sigma0", [0.0, 1.234, -2.5])
def test_round_trip_to_round_off(case, sigma0):
    r, v = ROUND_TRIP_CASES[case]
    L = float(np.linalg.norm(r))
    el = dromo.cartesian_to_dromo(r, v, MU, L, sigma0)
    assert abs(el[3:] @ el[3:] - 1.0) < 4e-16  # unit quaternion
    r2, v2 = dromo.dromo_to_cartesian(sigma0, el, MU, L)
    # round-off: a few ulp of |r| and |v| (dromo.md s9: <= 4e-15 over 2000 random orbits)
    assert np.linalg.norm(r2 - r) / np.linalg.norm(r) < 2e-15
    assert np.linalg.norm(v2 - v) / np.linalg.norm(v) < 2e-15


def test_round_trip_random_elliptic():
    rng = np.random.default_rng(7)
    worst = 0.0
    for _ in range(300):
        a = rng.uniform(6.6e6, 5e7)
        st = _kepler_state(a, rng.uniform(0, 0.95), rng.uniform(0, math.pi), *rng.uniform(0, 2 * math.pi, 3))
        sigma0 = rng.uniform(-10, 10)
        L = rng.uniform(0.5, 2.0) * a
        el = dromo.cartesian_to_dromo(*st, MU, L, sigma0)
        r2, v2 = dromo.dromo_to_cartesian(sigma0, el, MU, L)
        worst = max(worst, np.linalg.norm(r2 - st[0]) / np.linalg.norm(st[0]),
                    np.linalg.norm(v2 - st[1]) / np.linalg.norm(st[1]))  # fmt: skip
    assert worst < 1e-14  # dromo.md s9: 3.9e-15 worst over 2000 such orbits


def _point_mass_scene(formulation, duration="3 d", rtol=1e-12, effects=None, count=7):
    r, v = _kepler_state(20000e3, 0.6, 0.9, 0.4, 1.3, 0.25)
    return Scene.from_dict({
        "name": "kepler",
        "duration": duration,
        "effects": effects if effects is not None else {"central_gravity": {}},
        "bodies": {"sat": {"mass": "1 kg", "position": [f"{x} m" for x in r],
                           "velocity": [f"{x} m/s" for x in v]}},
        "integrator": {"method": "dop853", "rtol": rtol, "atol": rtol, "formulation": formulation},
        "output": {"count": count},
    }), (r, v)  # fmt: skip


def _kepler_position(r0, v0, t):
    """Two-body position at time t by Kepler's equation (independent of tetherlab)."""
    rr = np.linalg.norm(r0)
    a = 1.0 / (2.0 / rr - v0 @ v0 / MU)
    n = math.sqrt(MU / a**3)
    ecc = np.cross(v0, np.cross(r0, v0)) / MU - r0 / rr
    e = np.linalg.norm(ecc)
    P = ecc / e
    h = np.cross(r0, v0)
    Qv = np.cross(h / np.linalg.norm(h), P)
    E0 = math.atan2((r0 @ v0) / math.sqrt(MU * a), 1 - rr / a)
    M = E0 - e * math.sin(E0) + n * t
    E = M
    for _ in range(50):
        E -= (E - e * math.sin(E) - M) / (1 - e * math.cos(E))
    return a * (math.cos(E) - e) * P + a * math.sqrt(1 - e * e) * math.sin(E) * Qv


@pytest.mark.parametrize("formulation", ["dromo", "dromo-time"])
def test_unperturbed_orbit_matches_keplers_equation(formulation):
    scene, (r0, v0) = _point_mass_scene(formulation, duration="3 d", rtol=1e-13)
    res = simulate(scene, progress=False)
    t = res.timeseries["t_s"].to_numpy()
    pos = res.timeseries[["sat.x_m", "sat.y_m", "sat.z_m"]].to_numpy()
    assert len(t) == 7 and t[-1] == pytest.approx(3 * 86400.0, rel=0, abs=1e-9)
    err = max(np.linalg.norm(pos[k] - _kepler_position(r0, v0, t[k])) for k in range(len(t)))
    # a 20000 km, e = 0.6 orbit for ~4.6 revolutions at tolerance 1e-13: measured 0.74 mm (sigma
    # form) and 0.31 mm (time form), Cowell 3.0 mm on the same scene; bound 5 mm (2.5e-10 of a)
    assert err < 5e-3, err


def test_sigma_form_elements_are_constant_without_perturbation():
    r, v = _kepler_state(20000e3, 0.6, 0.9, 0.4, 1.3, 0.25)
    L = float(np.linalg.norm(r))
    from tetherlab.integrators.driver import integrate
    from tetherlab.model.params import FORM_DROMO_SIGMA

    scene, _ = _point_mass_scene("dromo")
    from tetherlab.pipeline import prepare

    prep = prepare(scene)
    pe = dromo.attach(prep.model.fresh_params(), FORM_DROMO_SIGMA, MU, L, prep.y0.size)
    z0 = np.concatenate([[0.0], dromo.cartesian_to_dromo(r, v, MU, L)])
    res = integrate("dop853", dromo.dromo_sigma_rhs, 0.0, z0, [0.0, 20.0], pe, 1e-12, 1e-12)
    # central gravity is not evaluated in the sigma form (perturbing_body_force skips it), so the
    # perturbation is exactly zero and the seven elements do not move at all
    assert np.array_equal(res.y[-1, 1:], z0[1:])
    # tau advanced by the integral of 1/(q3^3 s^2) = Kepler time over ~3.2 revolutions
    assert res.y[-1, 0] > 0


def test_time_form_tethered_scene_agrees_with_cowell():
    scene = load_scene(SCENES / "vertical-equilibrium.toml").replace(**{"duration": "1 orbits"})
    a = simulate(scene.replace(**{"integrator.rtol": 1e-11, "integrator.atol": 1e-11}), progress=False)
    b = simulate(scene.replace(**{"integrator.formulation": "dromo-time", "integrator.rtol": 1e-11,
                                  "integrator.atol": 1e-11}), progress=False)  # fmt: skip
    cols = [c for c in a.timeseries.columns if c.endswith("_m") and ".v" not in c]
    dx = np.max(np.abs(a.timeseries[cols].to_numpy() - b.timeseries[cols].to_numpy()))
    # two formulations of the same dynamics at 1e-11: agreement far below a metre on a 7400 km
    # orbit (a 5 km tether's node positions included); bound 1 cm
    assert dx < 1e-2, dx
    assert b.stats["formulation"] == "dromo-time"


def test_stiefel_moon_matches_definition():
    from tetherlab.forces import stiefel_moon as sm

    mu, rho, w = sm.MU_MOON_M3_S2, sm.RHO_MOON_M, sm.RATE_MOON_RAD_S
    # a(0) = rho [0, -sqrt3/2, -1/2] (stiefel-scheifele.md); |a(t)| = rho; orbit normal 30 deg off z
    a0 = np.array(sm.moon_position(rho, w, 0.0))
    assert np.allclose(a0, rho * np.array([0.0, -math.sqrt(3) / 2, -0.5]), rtol=0, atol=1e-6)
    a1 = np.array(sm.moon_position(rho, w, 0.5 * math.pi / w))
    nrm = np.cross(a0, a1)
    assert math.degrees(math.acos(nrm[2] / np.linalg.norm(nrm))) == pytest.approx(30.0, abs=1e-12)
    assert np.linalg.norm(a1) == pytest.approx(rho, rel=1e-15)
    # direct + indirect term at a point, written out from the definition
    r = np.array([7.0e6, -3.0e6, 2.0e6])
    t = 12345.0
    am = np.array(sm.moon_position(rho, w, t))
    want = -mu * ((r - am) / np.linalg.norm(r - am) ** 3 + am / rho**3)
    got = np.array(sm.accel(mu, rho, w, t, *r))
    assert np.allclose(got, want, rtol=1e-14, atol=0)
    # minus the gradient of the potential is the acceleration (central differences, 10 m steps)
    grad = np.array([(sm.potential(mu, rho, w, t, *(r + 10 * e)) - sm.potential(mu, rho, w, t, *(r - 10 * e))) / 20
                     for e in np.eye(3)])  # fmt: skip
    assert np.allclose(-grad, got, rtol=1e-6, atol=0)


def test_formulation_validation():
    scene, _ = _point_mass_scene("dromo")
    with pytest.raises(SceneError) as exc:
        scene.replace(**{"integrator.formulation": "encke"})
    assert "integrator.formulation" in str(exc.value)
    bad, _ = _point_mass_scene("dromo", effects={"j2": {}})
    with pytest.raises(SceneError) as exc:
        simulate(bad, progress=False)
    assert "central_gravity" in str(exc.value)
    with pytest.raises(SceneError) as exc:
        simulate(scene.replace(**{"integrator.max_step": "60 s"}), progress=False)
    assert "integrator.max_step" in str(exc.value)


def _stiefel_sigma_run(t_out, method="dop853", tol=1e-11, te=dromo.TIME_PHYSICAL):
    from tetherlab.model.params import FORM_DROMO_SIGMA
    from tetherlab.pipeline import prepare

    scene = load_scene(SCENES / "stiefel-scheifele.toml")
    prep = prepare(scene)
    mu = prep.mu_m3_s2
    L = float(np.linalg.norm(prep.y0[:3]))
    pe = dromo.attach(prep.model.fresh_params(), FORM_DROMO_SIGMA, mu, L, prep.y0.size, te)
    return drive.integrate_sigma(method, pe, prep.y0[:3], prep.y0[3:6], t_out, tol, tol, mu, L), prep


#: the sigma form's two time variables: tau itself, and the linear time element (docs/dromo.md 11)
TIME_VARIABLES = pytest.mark.parametrize("te", [dromo.TIME_PHYSICAL, dromo.TIME_LINEAR], ids=["tau", "linear-te"])


@TIME_VARIABLES
@pytest.mark.parametrize("method", ["dop853", "vern9", "abm"])
def test_sigma_clock_outputs_do_not_alter_the_trajectory(method, te):
    """The compiled clock loop restarts from the start of the crossing step after each output,
    so the outputs do not move the integration's path: the only difference is that a restart
    forgets the step controller's last rejection (which caps the next step)."""
    t_f = 20 * 86400.0
    few, _ = _stiefel_sigma_run(np.array([0.0, t_f]), method, te=te)
    many, _ = _stiefel_sigma_run(np.linspace(0.0, t_f, 37), method, te=te)
    assert few.status == 0 and many.status == 0, (few.message, many.message)
    # measured 0.5 mm (DOP853) and 0.12 mm (Vern9) after 20 days at tol 1e-11 with tau, 3.3 mm
    # (DOP853) with the time element, with the same step count (ABM: outputs are landed from saved
    # states, its path does not depend on them); the integration's own error there is ~6 cm
    # (0.87 m over 50 revolutions, Figure-3 table): bound a tenth of it, 6 mm
    assert np.linalg.norm(few.y[-1, :3] - many.y[-1, :3]) < 6e-3
    # the path is the same but for the controller's memory of its last rejection, which a restart
    # forgets: measured equal step counts with tau, one step more in 102 with the time element
    assert abs(few.stats["n_accepted"] - many.stats["n_accepted"]) <= 0.01 * few.stats["n_accepted"]
    assert many.t.size == 37 and np.array_equal(many.t, np.linspace(0.0, t_f, 37))
    # the located sigma leaves t_k - t(sigma_k) at the level of the dense output's error in tau;
    # it is stepped over with the Kepler acceleration (its neglected g^3 term is < 1e-12 m here)
    assert many.stats["time_residual_max_s"] < 1e-3


@TIME_VARIABLES
@pytest.mark.parametrize("method", ["dop853", "vern9", "abm"])
def test_sigma_clock_agrees_with_the_grid_search(method, te):
    """The compiled clock (DOP853 or Vern9) and the sigma grid + Newton search (the other
    methods' path, here run with DOP853) give the same states at the same output times, to the
    integration's own accuracy."""
    t_out = np.linspace(0.0, 20 * 86400.0, 5)
    clock, prep = _stiefel_sigma_run(t_out, method, tol=1e-12, te=te)
    mu = prep.mu_m3_s2
    L = float(np.linalg.norm(prep.y0[:3]))
    from tetherlab.model.params import FORM_DROMO_SIGMA

    pe = dromo.attach(prep.model.fresh_params(), FORM_DROMO_SIGMA, mu, L, prep.y0.size, te)
    grid = drive._integrate_sigma_grid("dop853", pe, prep.y0[:3], prep.y0[3:6], t_out, 1e-12, 1e-12,
                                       mu, L, 0.0, 10**7, None, drive.GRID_PER_REV)  # fmt: skip
    assert clock.status == 0 and grid.status == 0
    # both at 1e-12 over 3.5 revolutions of the Stiefel orbit (about 4 cm/revolution at 1e-11 in
    # the Figure-3 table): they differ by the outputs' path (and the method) only; bound 1 cm
    dr = np.max(np.linalg.norm(clock.y[:, :3] - grid.y[:, :3], axis=1))
    assert dr < 1e-2, dr


@TIME_VARIABLES
@pytest.mark.parametrize("method", ["dop853", "vern9", "abm"])
def test_sigma_clock_reports_a_failure_with_the_rows_before_it(method, te):
    """A step budget that runs out mid-way returns the rows computed so far and says why."""
    res, _ = _stiefel_sigma_run(np.linspace(0.0, 20 * 86400.0, 11), method, te=te)
    full = res.stats["n_accepted"]
    from tetherlab.model.params import FORM_DROMO_SIGMA
    from tetherlab.pipeline import prepare

    prep = prepare(load_scene(SCENES / "stiefel-scheifele.toml"))
    mu = prep.mu_m3_s2
    L = float(np.linalg.norm(prep.y0[:3]))
    pe = dromo.attach(prep.model.fresh_params(), FORM_DROMO_SIGMA, mu, L, prep.y0.size, te)
    cut = drive.integrate_sigma(method, pe, prep.y0[:3], prep.y0[3:6], res.t, 1e-11, 1e-11, mu, L,
                                max_steps=full // 2)  # fmt: skip
    assert cut.status == 1 and "step" in cut.message.lower()
    assert 1 <= cut.t.size < res.t.size
    assert np.array_equal(cut.y, res.y[: cut.t.size])


def test_perturbing_body_force_is_body_force_without_central_gravity():
    from tetherlab.forces import central_gravity
    from tetherlab.kernel.effects import body_force, perturbing_body_force
    from tetherlab.pipeline import prepare

    prep = prepare(load_scene(SCENES / "stiefel-scheifele.toml"))
    p = prep.model.fresh_params()
    x = (7.1e6, -1.2e6, 2.3e6, 10.0, 7000.0, 5.0)
    total = np.array(body_force(p, 1234.5, 0, *x, 2.0))
    pert = np.array(perturbing_body_force(p, 1234.5, 0, *x, 2.0))
    kepler = 2.0 * np.array(central_gravity.accel(prep.mu_m3_s2, *x[:3]))
    assert np.allclose(pert + kepler, total, rtol=1e-15, atol=0.0)
    assert np.linalg.norm(pert) < 1e-2 * np.linalg.norm(kepler)  # J2 + Moon: a perturbation


@pytest.mark.parametrize("mass_kg", [1.0, 7.3])
def test_sigma_rhs_equals_the_sheet_rates_of_the_projected_perturbation(mass_kg):
    """dromo_sigma_rhs folds 1/m0 and 1/(q3^4 s^3) into one multiplier (an operation-order
    change): its rates must equal sheet s5's, evaluated here in NumPy from the Cartesian
    perturbing force (perturbing_body_force) projected on the orbital frame [i, j, k] of sheet
    s2, to rounding (relative 1e-13 of each rate's largest term)."""
    from numba import njit

    from tetherlab._jit import ptr
    from tetherlab.kernel.effects import perturbing_body_force
    from tetherlab.model.params import FORM_DROMO_SIGMA, ParamView
    from tetherlab.pipeline import prepare

    prep = prepare(load_scene(SCENES / "stiefel-scheifele.toml"))
    mu = prep.mu_m3_s2
    L = float(np.linalg.norm(prep.y0[:3]))
    T = math.sqrt(L**3 / mu)
    p = dromo.attach(prep.model.fresh_params(), FORM_DROMO_SIGMA, mu, L, prep.y0.size)
    ParamView(p).root_mass_kg = mass_kg

    @njit
    def call(z, sig, p):
        dz = np.empty(8)
        dromo.dromo_sigma_rhs(sig, ptr(z), ptr(dz), ptr(p))
        return dz

    rng = np.random.default_rng(12)
    for _ in range(20):
        sig = rng.uniform(0.0, 300.0)
        el = dromo.cartesian_to_dromo(prep.y0[:3] * rng.uniform(0.9, 1.1), prep.y0[3:6] * rng.uniform(0.95, 1.0),
                                      mu, L, rng.uniform(-3, 3))  # fmt: skip
        z = np.concatenate([[rng.uniform(0.0, 3e4)], el])
        got = call(z, sig, p)
        # sheet s7 / s2: position, velocity and the orbital frame
        r, v = dromo.dromo_to_cartesian(sig, el, mu, L)
        i_hat = r / np.linalg.norm(r)
        k_hat = np.cross(r, v) / np.linalg.norm(np.cross(r, v))
        j_hat = np.cross(k_hat, i_hat)
        f = np.array(perturbing_body_force(p, T * z[0], 0, *r, *v, mass_kg)) / mass_kg * (L * L / mu)
        fr, ft, fn = f @ i_hat, f @ j_hat, f @ k_hat
        q1, q2, q3, e1, e2, e3, e4 = el
        c, sn = math.cos(sig), math.sin(sig)
        s = 1 + q1 * c + q2 * sn
        den = q3**4 * s**3
        want = np.array([1 / (q3**3 * s * s), (s * sn * fr + (q1 + (1 + s) * c) * ft) / den,
                         (-s * c * fr + (q2 + (1 + s) * sn) * ft) / den, -q3 * ft / den,
                         0.5 * fn / den * (e4 * c - e3 * sn), 0.5 * fn / den * (e3 * c + e4 * sn),
                         0.5 * fn / den * (-e2 * c + e1 * sn), 0.5 * fn / den * (-e1 * c - e2 * sn)])  # fmt: skip
        scale = np.array([want[0], *(np.abs([fr, ft, fn]).max() * (2 + abs(q1) + abs(q2)) / den * np.ones(7))])
        assert np.all(np.abs(got - want) <= 1e-13 * np.abs(scale)), (got - want) / scale


def test_dromo_to_cartesian_is_the_vector_form_bit_for_bit():
    """The plain-float dromo_to_cartesian does sheet s7's vector form operation for operation:
    r = (L/(q3^2 s)) i, v = (L/T)(q3 kappa i + q3 s j), i = c x + s y, j = -s x + c y with x, y
    the first two columns of frame_from_quaternion (sheet s1) -- so the result is bit-for-bit
    the vector form's, evaluated here with NumPy."""
    rng = np.random.default_rng(7)
    mu, L = 398600.4418e9, 6.9e6
    T = math.sqrt(L**3 / mu)
    for _ in range(300):
        el = dromo.cartesian_to_dromo(rng.normal(size=3) * L, rng.normal(size=3) * 7e3, mu, L,
                                      rng.uniform(-3.0, 3.0))  # fmt: skip
        sig = rng.uniform(-10.0, 400.0)
        R = dromo.frame_from_quaternion(el[3:7])
        c, sn = math.cos(sig), math.sin(sig)
        i = c * R[:, 0] + sn * R[:, 1]
        j = -sn * R[:, 0] + c * R[:, 1]
        q1, q2, q3 = el[:3]
        s = 1.0 + q1 * c + q2 * sn
        kap = q1 * sn - q2 * c
        r_want = (L / (q3 * q3 * s)) * i
        v_want = (L / T) * (q3 * kap * i + q3 * s * j)
        r, v = dromo.dromo_to_cartesian(sig, el, mu, L)
        assert np.array_equal(r, r_want) and np.array_equal(v, v_want)
