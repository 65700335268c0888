"""Environment fidelity levels: Earth rotation angle, IGRF-14, OML current, NRLMSIS 2.1
table, eclipse.  Every expected value has its source in a comment; derivations in
docs/environment.md and docs/effects-oml.md."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from tetherlab.errors import SceneError
from tetherlab.model.params import ParamView

ROOT = Path(__file__).resolve().parent.parent
MU_EARTH = 3.986004418e14
R_EARTH = 6378137.0
EPOCH = "2026-03-01T00:00:00"


# -- Earth rotation angle ---------------------------------------------------------------------------


def test_era_at_j2000_against_iers_conventions_formula():
    from tetherlab.environment.earth_orientation import earth_rotation_angle

    # IERS Conventions 2010 eq. 5.15: ERA = 2 pi (0.7790572732640 + 1.00273781191135448 Du),
    # Du = JD(UT1) - 2451545.0.  At 2000-01-01T12:00:00 TDB, UT1 = TDB - 64.184 s (TT - UTC in
    # 2000: 32 leap seconds + 32.184 s) + (UT1 - UTC) - (TDB - TT, 0.1 ms there).
    era = earth_rotation_angle("2000-01-01T12:00:00")
    du = (-64.184 + era["ut1_minus_utc_s"]) / 86400.0
    expected = (2.0 * math.pi * (0.7790572732640 + 1.00273781191135448 * du)) % (2.0 * math.pi)
    # 1e-8 rad: the 0.1 ms TDB - TT term is 7e-9 rad
    assert era["era_rad"] == pytest.approx(expected, abs=1e-8)
    # UT1 - UTC in January 2000 was +0.355 s (IERS Bulletin B); it must come from the bundled table
    assert era["ut1_minus_utc_s"] == pytest.approx(0.355, abs=0.005)


def test_explicit_greenwich_angle_wins_over_the_epoch():
    from tetherlab.environment.earth_orientation import earth_rotation_angle, rotation_angle_at_start

    angle, how = rotation_angle_at_start({"greenwich_angle": 0.3}, {"epoch": EPOCH}, "electrodynamic")
    assert angle == 0.3 and "override" in how
    angle, how = rotation_angle_at_start({}, {"epoch": EPOCH}, "electrodynamic")
    assert angle == earth_rotation_angle(EPOCH)["era_rad"] and "ERA" in how
    assert rotation_angle_at_start({}, {}, "electrodynamic")[0] == 0.0  # no epoch: the old default


# -- IGRF-14 ---------------------------------------------------------------------------------------


def test_igrf_kernel_matches_ppigrf_reference_to_0p1_nT():
    """references/igrf/reference.json: ppigrf's own IGRF-14 evaluation at 1200 random points and
    dates (build_reference.py); tolerance 0.1 nT (reference.json "tolerance_nT")."""
    import datetime as dt

    from tetherlab.environment import igrf

    ref = json.loads((ROOT / "references" / "igrf" / "reference.json").read_text())
    assert ref["provenance"]["coefficient_file"] == "IGRF14.shc"
    tol = ref["provenance"]["tolerance_nT"]
    worst = 0.0
    blocks = {}
    for pt in ref["points"]:
        date = dt.datetime.fromisoformat(pt["date"])
        start = date - dt.timedelta(seconds=pt["t_offset_s"])
        if start not in blocks:
            blocks[start] = np.array(igrf.pack(start))
        blk = blocks[start]
        r = pt["r_km"] * 1e3
        th = math.radians(pt["theta_deg"])
        ph = math.radians(pt["phi_deg"])
        rh = np.array([math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)])
        thh = np.array([math.cos(th) * math.cos(ph), math.cos(th) * math.sin(ph), -math.sin(th)])
        phh = np.array([-math.sin(ph), math.cos(ph), 0.0])
        b = np.array(igrf.field_ecef(blk, 0, pt["t_offset_s"], *(r * rh))) * 1e9
        err = max(abs(b @ rh - pt["Br_nT"]), abs(b @ thh - pt["Btheta_nT"]), abs(b @ phh - pt["Bphi_nT"]))
        worst = max(worst, err)
    assert len(ref["points"]) >= 1000
    assert worst <= tol, f"worst component difference {worst:.3g} nT > {tol} nT"


def test_igrf_degree_one_is_the_dipole_of_the_same_coefficients():
    """Degree 1 of the spherical-harmonic sum is the centred dipole K = a^3 (g11, h11, g10)
    (docs/effects-electrodynamic.md eq. 1): the IGRF kernel cut at degree 1 equals magnetic.dipole."""
    import datetime as dt

    from tetherlab.environment import igrf, magnetic

    date = dt.datetime(2020, 1, 1)
    blk = np.array(igrf.pack(date, nmax=1))
    g, h, _, _ = igrf.coefficients_at(date, 1)
    a = igrf.IGRF_REFERENCE_RADIUS_M
    k = a**3 * np.array([g[1, 1], h[1, 1], g[1, 0]])
    for r in ([7.0e6, 1.0e6, -2.0e6], [-3e6, 5e6, 4e6], [0.0, 0.0, 7.2e6]):
        np.testing.assert_allclose(igrf.field_ecef(blk, 0, 0.0, *r), magnetic.dipole(*k, *r), rtol=1e-12, atol=1e-18)


def _ed_scene(**changes):
    from tetherlab.scene import load_scene

    sc = load_scene(ROOT / "studies" / "scenes" / "fidelity-paper.toml")
    return sc.replace(**changes) if changes else sc


@pytest.mark.parametrize("epoch", ["1899-06-01T00:00:00", "2030-06-01T00:00:00"])
def test_igrf_epoch_outside_the_coefficients_is_a_scene_error(epoch):
    from tetherlab.pipeline import prepare

    sc = _ed_scene(**{"epoch": epoch, "effects.electrodynamic.field": "igrf14", "duration": "1 d"})
    with pytest.raises(SceneError) as err:
        prepare(sc)
    assert err.value.key == "epoch"


def test_igrf_without_epoch_is_a_scene_error():
    # refused when the scene is made (scene/checks.py _check_epoch), not when the run is prepared
    with pytest.raises(SceneError) as err:
        _ed_scene(**{"epoch": None, "effects.electrodynamic.field": "igrf14", "duration": "1 d"})
    assert err.value.key == "epoch"


# -- OML bare-tether current ---------------------------------------------------------------------


def _closed_form(ell):
    """Closed-form OML solution, ideal cathode (docs/effects-oml.md sec. 2): from the first
    integral (1 - i)^2 = 1 - phi_A^(3/2) + phi^(3/2),
    l = int_0^phi_A dphi / sqrt(1 - phi_A^1.5 + phi^1.5), i_C = 1 - sqrt(1 - phi_A^1.5),
    l i_av = int_0^phi_A i/(1 - i) dphi; for l >= 4: phi_A = 1, i_C = 1, i_av = 1 - 1/l."""
    from scipy.integrate import quad
    from scipy.optimize import brentq

    if ell >= 4.0:
        return 1.0, 1.0, 1.0 - 1.0 / ell

    def length(pa):
        return quad(lambda f: 1.0 / math.sqrt(1.0 - pa**1.5 + f**1.5), 0.0, pa, limit=200, epsabs=0, epsrel=1e-12)[0]

    pa = brentq(lambda a: length(a) - ell, 1e-14, 1.0, xtol=1e-15, rtol=1e-14)
    c = 1.0 - pa**1.5
    ic = 1.0 - math.sqrt(c)
    iav = quad(lambda f: 1.0 / math.sqrt(c + f**1.5) - 1.0, 0.0, pa, limit=200, epsabs=0, epsrel=1e-12)[0] / ell
    return pa, ic, iav


@pytest.mark.parametrize("ell", [0.02, 0.3, 1.0, 2.0, 3.0, 3.5, 4.0, 6.0, 20.0])
def test_oml_profile_against_closed_form(ell):
    from tetherlab.forces import oml

    pa, ic, iav = _closed_form(ell)
    s = oml.solution(ell)
    # RK4 with 1680 steps across a sqrt(phi) end singularity: 1e-6 on i_C, better on the rest
    assert s["phi_A"] == pytest.approx(pa, abs=1e-7)
    assert s["i_C"] == pytest.approx(ic, abs=2e-6)
    assert s["i_av"] == pytest.approx(iav, rel=1e-6, abs=1e-9)
    # zero-bias point: the cathode end (ideal contactor) for l <= 4, xi = 4 beyond (docs sec. 2)
    assert s["xi_B"] == pytest.approx(min(ell, 4.0))


def test_oml_small_l_limit():
    # l -> 0: phi ~ l - xi, i = ((l^1.5 - (l - xi)^1.5))/2, i_av = 0.3 l^1.5 (docs/effects-oml.md sec. 2)
    from tetherlab.forces import oml

    for ell in (1e-3, 1e-2):
        assert oml.solution(ell)["i_av"] == pytest.approx(0.3 * ell**1.5, rel=2 * ell)


def test_oml_table_lookup_error():
    """The kernel's interpolated G(f, l) against the profile solved at that l: linear interpolation
    on the 201-point l grid of G/l^1.5, a smooth function (docs/effects-oml.md sec. 3): budget
    Delta l^2/8 max|h''| with Delta l = 0.02, about 1e-4 of i_av."""
    from tetherlab.forces import oml

    fracs = (0.0, 0.25, 0.5, 0.75, 1.0)
    tab = oml.table(fracs)
    p = tab.ravel()
    worst = 0.0
    for ell in np.linspace(0.011, 3.99, 37):
        s = oml.solution(float(ell))
        for row, f in enumerate(fracs[1:], start=1):
            k = int(round(f * (s["xi"].size - 1)))
            expected = s["C"][k] / ell
            got = oml.cumulative(p, 0, tab.shape[1], row, f, float(ell))
            worst = max(worst, abs(got - expected) / max(s["i_av"], 1e-12))
    assert worst < 1e-3


def _oml_model(rods, ne=2e11, cathode="from", field="aligned"):
    from tetherlab.forces import EFFECTS
    from tetherlab.system import TetherSpec, build_model

    params = {"conductivity": 3.5e7, "cathode": cathode, "ionosphere": "uniform", "electron_density": ne,
              "peak_altitude": 350e3, "scale_height": 100e3, "field": field, "dipole_strength": 8e15,
              "eclipse": "none"}
    tet = TetherSpec("main", rods, 5000.0, 7.9e4, 15.0, 0.0, "paper", 392.2, "end_mass", diameter_m=1.2e-3)
    return build_model(root_mass_kg=1063.0, tethers=[tet], effects=[(EFFECTS["oml"], params)],
                       central={"mu_m3_s2": MU_EARTH, "radius_m": R_EARTH})


@pytest.mark.parametrize("rods", [1, 4])
def test_oml_force_on_a_vertical_tether_is_the_average_current_times_L_cross_B(rods):
    """Vertical tether over the equator, prograde circular velocity, aligned dipole: E_m = (v - w x r)
    x B is along +r (up), E_t = |v_rel| B; the closed form gives I_av for l = L/L*; the total
    Lorentz force is I_av L u x B (u up), along -y (drag).  Field and E_t vary by 2e-3 over 5 km:
    tolerance 1e-2 relative."""
    from tetherlab.forces import oml
    from tetherlab.kernel.effects import rod_force_density

    model = _oml_model(rods)
    r = R_EARTH + 1000e3
    v = math.sqrt(MU_EARTH / r)
    p = model.fresh_params()
    # integrate the density over every rod with Gauss-Legendre in xi (nodes at the rods' own points)
    xg, wg = np.polynomial.legendre.leggauss(6)
    total = np.zeros(3)
    rm = r + 2500.0
    for g in range(rods):
        a = r + g * 5000.0 / rods
        half = 0.5 * 5000.0 / rods
        for xi, w in zip(xg, wg):
            x = a + half * (1.0 + xi)
            vx = v * x / r  # rigid rotation with the orbit rate
            f = rod_force_density(p, 0.0, g, x, 0.0, 0.0, 0.0, vx, 0.0, half, 0.0, 0.0, 0.0)
            total += w * np.array(f)
    b = 8e15 / rm**3
    vrel = v * rm / r - 7.292115e-5 * rm
    et = vrel * b
    prof = oml.profile(3.5e7, 1.2e-3, 5000.0, et, 2e11)
    expected = prof["average_current_a"] * 5000.0 * b
    assert total[1] == pytest.approx(-expected, rel=1e-2)
    assert abs(total[0]) < 1e-6 * expected and abs(total[2]) < 1e-6 * expected
    # Joule dissipation is below the power drawn from the orbit (the rest goes to the plasma)
    assert 0.0 < prof["joule_w"] < prof["motional_power_w"]


def test_oml_no_current_when_the_field_pushes_towards_the_cathode():
    # cathode at the upper ("to") end: E_t = E_m . u(cathode -> anode) < 0, no current (docs sec. 1)
    from tetherlab.kernel.effects import rod_force_density

    model = _oml_model(1, cathode="to")
    p = model.fresh_params()
    r = R_EARTH + 1000e3
    v = math.sqrt(MU_EARTH / r)
    assert rod_force_density(p, 0.0, 0, r + 2500.0, 0.0, 0.0, 0.0, v, 0.0, 2500.0, 0.0, 0.0, 0.0) == (0.0, 0.0, 0.0)


def test_oml_bad_input_names_the_key():
    from tetherlab.pipeline import prepare

    base = {"effects.electrodynamic": None}
    with pytest.raises(SceneError) as err:
        _ed_scene(**base, **{"effects.oml": {"tether_diameter": "1 mm"}})
    assert err.value.key == "effects.oml.conductivity"
    with pytest.raises(SceneError) as err:
        prepare(_ed_scene(**base, **{"effects.oml": {"conductivity": "3.5e7 S/m"}, "tethers.main.diameter": None,
                                     "duration": "1 d"}))
    assert err.value.key == "tethers.main.diameter"
    with pytest.raises(SceneError) as err:
        prepare(_ed_scene(**base, **{"effects.oml": {"conductivity": "3.5e7 S/m", "electron_density": "-1 m-3"},
                                     "duration": "1 d"}))
    assert err.value.key == "effects.oml.electron_density"


# -- NRLMSIS 2.1 -------------------------------------------------------------------------------------


def test_nrlmsis_table_lookup_against_direct_pymsis():
    """Interpolated ln(rho) against pymsis at 600 random points and times over 6 days.  Budget
    (docs/environment.md sec. 4): linear interpolation of ln rho on the grid (20 km, 2 h of LST,
    20 deg of latitude, 4 h of UT, 5-day slices) costs up to a few % in each of the diurnal,
    UT (longitude) and latitude directions: at most 15 %, rms 4 %."""
    from tetherlab.environment import nrlmsis

    blk, info = nrlmsis.table(EPOCH, 6 * 86400.0, 150.0, 150.0, 15.0, 5 * 86400.0)
    p = np.array(blk)
    rng = np.random.default_rng(7)
    n = 600
    r = R_EARTH + rng.uniform(200e3, 1100e3, n)
    lat = np.arcsin(rng.uniform(-1.0, 1.0, n))
    lon = rng.uniform(-math.pi, math.pi, n)
    pos = np.c_[r * np.cos(lat) * np.cos(lon), r * np.cos(lat) * np.sin(lon), r * np.sin(lat)]
    ts = rng.uniform(0.0, 6 * 86400.0, n)
    direct = nrlmsis.density_direct(EPOCH, ts, pos, 150.0, 150.0, 15.0)
    look = np.array([nrlmsis.density(p, 0, t, *x) for t, x in zip(ts, pos)])
    rel = look / direct - 1.0
    assert np.max(np.abs(rel)) < 0.15
    assert np.sqrt(np.mean(rel**2)) < 0.04


@pytest.mark.parametrize("missing", ["f107", "f107a", "ap"])
def test_nrlmsis_missing_index_is_a_scene_error(missing):
    from tetherlab.pipeline import prepare

    drag = {"area": "1 m2", "atmosphere": "nrlmsis21", "f107": 150, "f107a": 150, "ap": 15}
    del drag[missing]
    with pytest.raises(SceneError) as err:
        prepare(_ed_scene(**{"effects.drag": drag, "duration": "1 d"}))
    assert err.value.key == f"effects.drag.{missing}"


def test_nrlmsis_negative_index_is_a_scene_error():
    from tetherlab.pipeline import prepare

    drag = {"area": "1 m2", "atmosphere": "nrlmsis21", "f107": -5, "f107a": 150, "ap": 15}
    with pytest.raises(SceneError) as err:
        prepare(_ed_scene(**{"effects.drag": drag, "duration": "1 d"}))
    assert err.value.key == "effects.drag.f107"


# -- eclipse ---------------------------------------------------------------------------------------


def test_shadow_functions_on_the_sun_line():
    from tetherlab.environment import eclipse

    s = np.array([1.496e11, 0.0, 0.0])
    rs = eclipse.SUN_RADIUS_M
    for code in (eclipse.ECLIPSE_CYLINDRICAL, eclipse.ECLIPSE_CONICAL):
        assert eclipse.fraction_at(code, R_EARTH, rs, *s, -7.0e6, 0.0, 0.0) == 0.0  # behind the Earth
        assert eclipse.fraction_at(code, R_EARTH, rs, *s, 7.0e6, 0.0, 0.0) == 1.0  # sunward
        assert eclipse.fraction_at(code, R_EARTH, rs, *s, -7.0e6, 7.0e6, 0.0) == 1.0  # beside
    # conical: at the geometric shadow edge (|r_perp| = R_E behind the Earth) the Earth's limb
    # crosses the Sun's centre (to first order in R_E/|s|): half the disc, nu ~ 0.5 (M&G sec. 3.4.2)
    d = 7.0e6
    nu = eclipse.fraction_at(eclipse.ECLIPSE_CONICAL, R_EARTH, rs, *s, -math.sqrt(d * d - R_EARTH**2), R_EARTH, 0.0)
    assert nu == pytest.approx(0.5, abs=0.03)


def test_cylindrical_eclipse_duration_of_an_orbit_containing_the_sun_line():
    """A circular orbit whose plane contains the Sun direction crosses a cylinder of radius R_E:
    shadow duration 2 asin(R_E/a)/n (geometry).  The Sun moves 0.07 deg during one orbit: the
    tolerance of 2 s covers it."""
    from tetherlab import ephemeris
    from tetherlab.environment import eclipse

    a = R_EARTH + 1000e3
    n = math.sqrt(MU_EARTH / a**3)
    blk = np.array(eclipse.pack("cylindrical", {"epoch": EPOCH, "duration_s": 86400.0}, R_EARTH, "test"))
    s = np.array(ephemeris.position(blk, 3, 0.0))
    u = s / np.linalg.norm(s)
    w = np.cross(u, [0.0, 0.0, 1.0])
    w /= np.linalg.norm(w)
    e2 = np.cross(w, u)  # orbit plane spanned by u and e2
    period = 2 * math.pi / n
    ts = np.arange(0.0, period + 1.0, 60.0)
    ang = n * ts
    y = np.array([np.r_[a * (math.cos(q) * u + math.sin(q) * e2), a * n * (-math.sin(q) * u + math.cos(q) * e2)]
                  for q in ang])
    ev = eclipse.eclipse_events("cylindrical", ts, y, EPOCH, R_EARTH, MU_EARTH)
    kinds = [e["kind"] for e in ev]
    assert kinds == ["entry", "exit"]
    duration = ev[1]["t_s"] - ev[0]["t_s"]
    assert duration == pytest.approx(2.0 * math.asin(R_EARTH / a) / n, abs=2.0)
    # entry at the angle pi - asin(R_E/a) from the Sun direction
    assert ev[0]["t_s"] == pytest.approx((math.pi - math.asin(R_EARTH / a)) / n, abs=2.0)


def test_eclipse_switches_the_constant_current_off():
    from tetherlab import ephemeris
    from tetherlab.forces import EFFECTS
    from tetherlab.forces import electrodynamic
    from tetherlab.system import TetherSpec, build_model

    params = {"current": 2.0, "field": "aligned", "dipole_strength": 8e15, "eclipse": "cylindrical"}
    tet = TetherSpec("main", 1, 5000.0, 7.9e4, 15.0, 0.0, "paper", 392.2, "end_mass")
    model = build_model(root_mass_kg=1063.0, tethers=[tet], effects=[(EFFECTS["electrodynamic"], params)],
                        central={"mu_m3_s2": MU_EARTH, "radius_m": R_EARTH}, epoch=EPOCH, duration_s=86400.0)
    p = model.fresh_params()
    par = ParamView(p).effect(0).par_offset
    off = par + int(p[par + 1])
    s = np.array(ephemeris.position(p, off + 3, 0.0))
    u = s / np.linalg.norm(s)
    lit = electrodynamic.rod_density(p, par, 0.0, *(7.4e6 * u), 2500.0, 0.0, 0.0)
    dark = electrodynamic.rod_density(p, par, 0.0, *(-7.4e6 * u), 2500.0, 0.0, 0.0)
    assert dark == (0.0, 0.0, 0.0)
    assert max(abs(c) for c in lit) > 0.0


def test_eclipse_epoch_outside_de421_is_a_scene_error():
    # DE421 covers 1899-07-29 to 2053-10-09 TDB (tetherlab/ephemeris.py); the Sun of the shadow
    # function comes from it
    from tetherlab.pipeline import prepare

    sc = _ed_scene(**{"epoch": "1850-01-01T00:00:00", "effects.electrodynamic.eclipse": "conical", "duration": "1 d"})
    with pytest.raises(SceneError) as err:
        prepare(sc)
    assert err.value.key == "epoch"


def test_full_environment_scene_loads_with_every_level_named():
    # studies/scenes/deorbit-ed-fullenv.toml: the top of the fidelity ladder as a scene file
    from tetherlab.scene import load_scene

    sc = load_scene(ROOT / "studies" / "scenes" / "deorbit-ed-fullenv.toml")
    eff = {e.name: e.params_si for e in sc.effects}
    assert set(eff) == {"central_gravity", "j2", "sun_de421", "moon_de421", "oml", "drag"}
    assert eff["oml"]["field"] == "igrf14" and eff["oml"]["eclipse"] == "conical"
    assert eff["oml"]["conductivity"] == pytest.approx(3.5e7)  # S/m, as written
    assert eff["drag"]["atmosphere"] == "nrlmsis21" and eff["drag"]["refresh"] == pytest.approx(10 * 86400.0)
    # round trip through the scene dictionary keeps the choices
    again = type(sc).from_dict(sc.to_dict())
    assert {e.name: e.params_si for e in again.effects}["oml"]["cathode"] == "from"


@pytest.mark.parametrize("degree", [0, 14, 2.5])
def test_igrf_degree_outside_1_to_13_is_a_scene_error(degree):
    from tetherlab.pipeline import prepare

    sc = _ed_scene(**{"effects.electrodynamic.field": "igrf14", "effects.electrodynamic.igrf_degree": degree,
                      "duration": "1 d"})
    with pytest.raises(SceneError) as err:
        prepare(sc)
    assert err.value.key == "effects.electrodynamic.igrf_degree"


def test_igrf_degree_one_equals_the_dipole_of_the_epoch_in_the_effect():
    # igrf_degree = 1: the field of the effect is the centred dipole K = a^3 (g11, h11, g10) of the
    # epoch's coefficients (docs/effects-electrodynamic.md eq. 1), in inertial axes rotated by theta_0
    from tetherlab.environment import igrf, magnetic
    from tetherlab.forces import EFFECTS
    from tetherlab.system import TetherSpec, build_model

    params = {"current": 2.0, "field": "igrf14", "igrf_degree": 1.0, "dipole_strength": 8e15,
              "greenwich_angle": 0.7, "eclipse": "none"}
    tet = TetherSpec("main", 1, 5000.0, 7.9e4, 15.0, 0.0, "paper", 392.2, "end_mass")
    model = build_model(root_mass_kg=1063.0, tethers=[tet], effects=[(EFFECTS["electrodynamic"], params)],
                        central={"mu_m3_s2": MU_EARTH, "radius_m": R_EARTH}, epoch=EPOCH, duration_s=86400.0)
    p = model.fresh_params()
    par = ParamView(p).effect(0).par_offset
    g, h, _, _ = igrf.coefficients_at(igrf.epoch_datetime(EPOCH), 1)
    a = igrf.IGRF_REFERENCE_RADIUS_M
    k = a**3 * np.array([g[1, 1], h[1, 1], g[1, 0]])
    c, s = math.cos(0.7), math.sin(0.7)
    k_in = np.array([c * k[0] - s * k[1], s * k[0] + c * k[1], k[2]])
    r = np.array([5.0e6, -4.0e6, 3.0e6])
    np.testing.assert_allclose(magnetic.field(p, par + 2, 0.0, *r), magnetic.dipole(*k_in, *r), rtol=1e-12, atol=1e-18)
