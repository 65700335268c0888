"""Gravity effects (j2, zonal, moon_de421, sun_de421): orbits against the heyoka references, each
potential's gradient against its acceleration, and the DE421 Chebyshev fit against skyfield.

References: references/heyoka_orbits/references.json (binary128 heyoka, built by
references/heyoka_orbits/build_references.py; these tests never import heyoka).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from tetherlab import ephemeris
from tetherlab.errors import SceneError
from tetherlab.forces import EFFECTS, EffectSpec
from tetherlab.forces import third_body, zonal
from tetherlab.formulations.cowell import cowell_rhs
from tetherlab.integrators.driver import integrate
from tetherlab.kernel.effects import body_force, potential_per_mass
from tetherlab.model.params import ParamView
from tetherlab.pipeline import simulate
from tetherlab.scene import Scene
from tetherlab.system import build_model, tolerance_scales

REF = json.loads((Path(__file__).resolve().parent.parent / "references" / "heyoka_orbits" / "references.json").read_text())
CONST = REF["constants"]
EPOCH = "2026-01-01T00:00:00"
# Position bound against the binary128 references: dop853 at rtol = atol = 1e-13 (scale units) over
# ~15 LEO orbits or 5 days of a GEO-like orbit.  The heyoka double run at tol 1e-15 differs from
# binary128 by 2e-6 m (references.json), so the bound is tetherlab's own integration error,
# measured 5e-5 m (LEO, 1 day); bound 1 cm = 1.5e-9 of the LEO radius, 200x the measurement.
BOUND_M = 0.01


def _point_mass_scene(effects: dict, r0, v0, days: float, count: int, **top) -> Scene:
    return Scene.from_dict({
        "name": "point-mass",
        "duration": f"{days} d",
        "effects": effects,
        "bodies": {"sat": {
            "mass": "100 kg",
            "position": [f"{float(v)!r} m" for v in r0],
            "velocity": [f"{float(v)!r} m/s" for v in v0],
        }},
        "integrator": {"method": "dop853", "rtol": 1e-13, "atol": 1e-13},
        "output": {"count": count},
        **top,
    })


@pytest.mark.parametrize("case,effects", [
    ("leo_j2", {"central_gravity": {}, "j2": {}}),
    ("leo_zonal", {"central_gravity": {}, "zonal": {}}),
])
def test_zonal_orbit_matches_heyoka(case, effects):
    ref = REF["cases"][case]
    states = np.array(ref["states_float"])
    t = np.array(ref["t_s"])
    scene = _point_mass_scene(effects, states[0, :3], states[0, 3:], ref["duration_days"], len(t))
    res = simulate(scene, progress=False)
    ts = res.timeseries
    assert np.allclose(ts["t_s"].to_numpy(), t, rtol=0, atol=1e-6)
    pos = ts[["sat.x_m", "sat.y_m", "sat.z_m"]].to_numpy()
    err = np.linalg.norm(pos - states[:, :3], axis=1)
    assert err.max() < BOUND_M, f"{case}: max position error {err.max():.3e} m"


def test_the_zonal_references_test_each_term():
    # The J3 + J4 terms move the 1-day LEO orbit by far more than BOUND_M, so test_zonal_orbit...
    # checks them, not just J2 (both from references.json).
    a = np.array(REF["cases"]["leo_j2"]["states_float"])[:, :3]
    b = np.array(REF["cases"]["leo_zonal"]["states_float"])[:, :3]
    assert np.linalg.norm(a - b, axis=1).max() > 100 * BOUND_M


def _circular_moon(t_s):
    # The closed form of references.json "constants.moon_position".
    th = CONST["n_moon_rad_s"] * np.asarray(t_s, float)
    inc = CONST["inc_moon_rad"]
    return CONST["rho_moon_m"] * np.array([np.cos(th), np.sin(th) * math.cos(inc), np.sin(th) * math.sin(inc)])


def test_third_body_orbit_matches_heyoka():
    # The moon_de421 kernel (Chebyshev fit + Clenshaw + direct/indirect term) fed with the fit of
    # the reference's analytic circular Moon instead of DE421: same compiled path, known motion.
    ref = REF["cases"]["geo_moon_circular"]
    states = np.array(ref["states_float"])
    t = np.array(ref["t_s"])
    mu = CONST["mu_earth_m3_s2"]
    block, fit_err = ephemeris.fit_block(_circular_moon, t[-1])
    assert fit_err < 1e-3  # m: a smooth circle, 4-day segments, degree 14
    spec = EffectSpec("moon_circular", third_body.CODE_MOON, "test", pack=lambda p, c, x: [CONST["mu_moon_m3_s2"]] + block)
    model = build_model(root_mass_kg=100.0, tethers=[], effects=[(EFFECTS["central_gravity"], {}), (spec, {})],
                        central={"mu_m3_s2": mu, "radius_m": 6378137.0})
    r = float(np.linalg.norm(states[0, :3]))
    atol = 1e-13 * tolerance_scales(model, r, math.sqrt(r**3 / mu))
    res = integrate("dop853", cowell_rhs, 0.0, states[0].copy(), t, model.fresh_params(), 1e-13, atol)
    assert res.status == 0, res.message
    err = np.linalg.norm(res.y[:, :3] - states[:, :3], axis=1)
    assert err.max() < BOUND_M, f"max position error {err.max():.3e} m"
    # ... and the Moon matters here: the same orbit without it is kilometres away.
    no_moon = build_model(root_mass_kg=100.0, tethers=[], effects=[(EFFECTS["central_gravity"], {})],
                          central={"mu_m3_s2": mu, "radius_m": 6378137.0})
    kep = integrate("dop853", cowell_rhs, 0.0, states[0].copy(), t, no_moon.fresh_params(), 1e-13, atol)
    assert np.linalg.norm(kep.y[-1, :3] - states[-1, :3]) > 1e3


def _model(names, duration_s=30 * 86400.0):
    return build_model(
        root_mass_kg=1.0, tethers=[],
        effects=[(EFFECTS[n], _defaults(n)) for n in names],
        central={"mu_m3_s2": 3.986004418e14, "radius_m": 6378137.0},
        epoch=EPOCH, duration_s=duration_s,
    )


def _defaults(name):
    return {k: float(s.default) for k, s in EFFECTS[name].params.items() if s.default is not None}


def _fd_gradient(u, x, h):
    g = np.zeros(3)
    for k in range(3):
        e = np.zeros(3)
        e[k] = h
        g[k] = (u(*(x + e)) - u(*(x - e))) / (2 * h)
    return g


@pytest.mark.parametrize("name", ["j2", "zonal", "moon_de421", "sun_de421"])
def test_potential_gradient_is_minus_the_acceleration(name):
    # Central differences with h = 1 m at r ~ 7000-42000 km: truncation ~ (h/r)^2 ~ 1e-13 and
    # rounding ~ 1e-16 r/h ~ 1e-9 relative to the acceleration; bound 1e-7 of |a|.
    model = _model([name])
    p = model.fresh_params()
    par = ParamView(p).effect(0).par_offset  # parameters of the only effect
    rng = np.random.default_rng(3)
    for _ in range(20):
        x = rng.normal(size=3)
        x *= rng.uniform(6.6e6, 4.3e7) / np.linalg.norm(x)
        t = rng.uniform(0.0, 30 * 86400.0)
        if name in ("j2", "zonal"):
            u = lambda a, b, c: potential_per_mass(p, t, a, b, c)  # noqa: E731  (dispatch path)
        else:
            u = lambda a, b, c: third_body.potential(p, par, t, a, b, c)  # noqa: E731
        acc = np.array(body_force(p, t, 0, *x, 0.0, 0.0, 0.0, 1.0))
        g = _fd_gradient(u, x, 1.0)
        assert np.linalg.norm(acc + g) < 1e-7 * np.linalg.norm(acc)


def test_zonal_with_only_j2_equals_j2():
    # Two independent formulas (P'_{n+1} r_hat - P'_n z_hat form and Vallado's J2 form), docs/effects-gravity.md
    x, y, z = 4.1e6, -3.3e6, 4.4e6
    a = zonal.accel(3.986004418e14, 6378137.0, zonal.EGM2008_J2, 0.0, 0.0, x, y, z)
    b = zonal.accel_j2(3.986004418e14, 6378137.0, zonal.EGM2008_J2, x, y, z)
    assert np.allclose(a, b, rtol=1e-14, atol=0)


def test_egm2008_constants():
    # J_n = -sqrt(2n+1) C_n0bar (EGM2008 tide-free, Pavlis et al. 2012); 1.0826261738522e-3 is
    # the value printed in the space.stackexchange/NGA conversions of C20bar = -0.484165143790815e-3.
    assert zonal.EGM2008_J2 == pytest.approx(1.082626173852e-3, rel=1e-12)
    assert zonal.EGM2008_J3 == pytest.approx(-2.5324105185677e-6, rel=1e-12)
    assert zonal.EGM2008_J4 == pytest.approx(-1.619897599916973e-6, rel=1e-12)


def test_chebyshev_fit_matches_skyfield():
    # Compare the compiled Clenshaw evaluation with skyfield called here directly (not through
    # tetherlab.ephemeris), at times that are not fit nodes.  Bound: < 1 m (docs/effects-gravity.md 3).
    from astropy.time import Time
    from skyfield.api import Loader, load_file

    duration = 30 * 86400.0
    model = _model(["moon_de421", "sun_de421"], duration)
    p = model.fresh_params()
    path = ephemeris.de421_path()
    eph = load_file(str(path))
    try:
        ts = Loader(str(path.parent)).timescale(builtin=True)
        ep = Time(EPOCH, scale="tdb")
        t = np.random.default_rng(1).uniform(0.0, duration, 200)
        for e, body in enumerate(("moon", "sun")):
            par = ParamView(p).effect(e).par_offset  # parameters of effect e
            want = (eph[body] - eph["earth"]).at(ts.tdb_jd(ep.jd1, ep.jd2 + t / 86400.0)).position.m
            got = np.array([ephemeris.position(p, par + 1, tk) for tk in t]).T
            err = np.linalg.norm(got - want, axis=0).max()
            assert err < 1.0, f"{body}: {err:.3e} m"
            reported = model.effect_meta[f"{body}_de421"]["fit_error_m"]
            assert reported < 1.0 and err < 10 * reported + 1e-3  # the reported error is honest
    finally:
        eph.close()


def test_de421_effects_report_their_fit_error_in_the_result():
    scene = _point_mass_scene({"central_gravity": {}, "moon_de421": {}, "sun_de421": {}},
                              [7.0e6, 0.0, 0.0], [0.0, 6000.0, 4000.0], 0.02, 3, epoch=EPOCH)
    res = simulate(scene, progress=False)
    for name in ("moon_de421", "sun_de421"):
        meta = res.meta["effect_meta"][name]
        assert meta["time_scale"] == "TDB" and 0.0 <= meta["fit_error_m"] < 1.0


def test_de421_effect_without_epoch_is_refused_before_integration():
    # refused when the scene is made (scene/checks.py _check_epoch), long before integration
    with pytest.raises(SceneError, match="epoch"):
        _point_mass_scene({"central_gravity": {}, "moon_de421": {}}, [7.0e6, 0.0, 0.0], [0.0, 7500.0, 0.0], 0.01, 2)


def test_zonal_parameter_with_a_wrong_unit_is_refused():
    with pytest.raises(SceneError, match="effects.j2.radius"):
        _point_mass_scene({"central_gravity": {}, "j2": {"radius": "5 kg"}}, [7.0e6, 0.0, 0.0], [0.0, 7500.0, 0.0], 0.01, 2)
