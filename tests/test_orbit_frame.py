"""The formulation "cowell-orbit" (Cowell in a frame turning with the orbit) and the start
``orbit.motion = "quasi-static"`` (docs/integrators.md section 9, docs/model.md section 8.1)."""

from __future__ import annotations

import numpy as np
import pytest

import tetherlab
from tetherlab.errors import SceneError
from tetherlab.formulations import cowell_orbit as co
from tetherlab.formulations.cowell import cowell_rhs_py
from tetherlab.model.state import StateLayout
from tetherlab.pipeline import integrate_prepared, prepare

from .helpers import SCENES, call_cfunc

DEORBIT = SCENES / "deorbit-ed.toml"
R_EARTH_M = 6378.137e3  # the scene preset "earth" (tetherlab/scene/data.py)


def _deorbit(**kv):
    base = {"tethers.main.rods": 4, "orbit.motion": "quasi-static", "output.step": "1080 s"}
    return tetherlab.load_scene(DEORBIT).replace(**{**base, **kv})


def _run(scene):
    prep = prepare(scene)
    res, _ = integrate_prepared(prep, prep.model.fresh_params())
    return prep, res


def test_frame_conversions_round_trip():
    rng = np.random.default_rng(3)
    omega = np.array([0.0, -5.7e-4, 8.2e-4])  # the de-orbit orbit's rate, rad/s
    nqt = 15
    lay = StateLayout(rods=(4,))  # q of 15: the root and four rods
    y = rng.normal(size=2 * nqt) * np.r_[np.full(nqt, 7e6), np.full(nqt, 7e3)]
    for t in (0.0, 1234.5, 3.3e6):
        back = co.to_inertial([t], co.to_frame(t, y, omega, lay), omega, lay)[0]
        # round-off of two rotations of 7e6 m vectors: a few ulp of 7e6 m (1e-9 m each)
        np.testing.assert_allclose(back[:nqt], y[:nqt], rtol=0, atol=1e-7)
        np.testing.assert_allclose(back[nqt:], y[nqt:], rtol=0, atol=1e-10)
    # at t = 0 the frame coincides with the inertial one; rates differ by omega x q
    f0 = co.to_frame(0.0, y, omega, lay)
    np.testing.assert_array_equal(f0[:nqt], y[:nqt])
    np.testing.assert_allclose(f0[nqt : nqt + 3], y[nqt : nqt + 3] - np.cross(omega, y[:3]), rtol=1e-15, atol=1e-9)


def test_frame_rhs_is_the_inertial_rhs_in_turning_components():
    """q'' = R^T a - 2 w x v - w x (w x q) (formulations/cowell_orbit.py): turned back with the
    frame kinematics, the acceleration is the inertial Cowell one at the same physical state."""
    prep = prepare(_deorbit())
    nqt = prep.model.n_qt
    omega = co.frame_rate(prep.y0, prep.model.state)
    pe = co.attach(prep.model.fresh_params(), omega)
    t = 2000.0
    y_in = prep.y0.copy()
    y_f = co.to_frame(t, y_in, omega, prep.model.state)
    st, dy = call_cfunc(co.cowell_orbit_rhs, t, y_f, pe)
    assert st == 0
    a_in = cowell_rhs_py(prep.model, y_in, t)[nqt:].reshape(-1, 3)
    q = y_f[:nqt].reshape(-1, 3)
    v = y_f[nqt:].reshape(-1, 3)
    a_f = dy[nqt:].reshape(-1, 3) + 2 * np.cross(omega, v) + np.cross(omega, np.cross(omega, q))
    R = co._rotation_matrices([t], omega)[0]
    # round-off of the turned states (an ulp of a 90 m rod vector is 1.4e-14 m) through the
    # rod's axial stiffness per mass (EA/l/m = 17 s^-2) and of 7.3 m/s^2 gravity: ~1e-12 m/s^2
    # (4e-12 measured); a wrong Coriolis or centrifugal term is 1e-2 m/s^2 here
    np.testing.assert_allclose(a_f @ R.T, a_in, rtol=0, atol=1e-10)


def test_turning_frame_agrees_with_the_inertial_run():
    """Same scene, both formulations, rtol = atol = 1e-10 (atol in units of the orbit radius
    7.4e6 m and the orbital speed 7.4e3 m/s: tetherlab.pipeline.tolerance_scales).  Budget: each
    run's global error within 10 x its per-step tolerance, 10 x 1e-10 x 7.4e6 m = 7.4 mm and
    7.4e-6 m/s, rounded up to 1 cm and 1e-5 m/s for the difference of the two."""
    kv = {"duration": "0.05 d", "integrator.rtol": 1e-10, "integrator.atol": 1e-10}
    _, a = _run(_deorbit(**kv, **{"integrator.formulation": "cowell"}))
    _, b = _run(_deorbit(**kv, **{"integrator.formulation": "cowell-orbit"}))
    assert a.success and b.success and a.t[-1] == b.t[-1] == 4320.0
    ya, yb = a.y[-1], b.y[-1]
    h = ya.size // 2
    assert np.max(np.abs(ya[:h] - yb[:h])) < 1e-2
    assert np.max(np.abs(ya[h:] - yb[h:])) < 1e-5
    # negative control: outputs turned back with a frame rate 1e-6 off (a wrong frame kinematics
    # far smaller than a wrong Coriolis term) move the root by r w 1e-6 t = 3 cm: the bound fails
    (t_a, *omega), = b.stats["frame_anchors"]  # one frame: the run is shorter than its re-anchoring
    omega = np.asarray(omega)
    lay = StateLayout(rods=(h // 3 - 1,))  # one tether: q = (r0, its rods)
    yf = co.to_frame(b.t[-1] - t_a, yb, omega, lay)
    wrong = co.to_inertial([b.t[-1] - t_a], yf, omega * (1 + 1e-6), lay)[0]
    assert np.max(np.abs(ya[:3] - wrong[:3])) > 1e-2


def test_stop_event_located_in_the_turning_frame():
    """The event functions are frame invariant (|r0|, rod tensions): the [stop] crossing of both
    formulations agrees to the located-event tolerance and the global error (1e-10, budget 0.01 s
    at the measured 0.2 m/s descent: 2 mm)."""
    alt0 = float(np.linalg.norm(prepare(_deorbit()).y0[:3])) - R_EARTH_M
    kv = {"duration": "0.3 d", "stop.altitude": f"{alt0 - 3000.0} m", "integrator.rtol": 1e-10, "integrator.atol": 1e-10}
    _, a = _run(_deorbit(**kv, **{"integrator.formulation": "cowell"}))
    _, b = _run(_deorbit(**kv, **{"integrator.formulation": "cowell-orbit"}))
    assert a.stopped_by == b.stopped_by == 0
    assert abs(a.t[-1] - b.t[-1]) < 0.01
    # the stop state is in inertial components: its radius is the threshold
    assert abs(np.linalg.norm(b.y[-1][:3]) - R_EARTH_M - (alt0 - 3000.0)) < 1e-3


@pytest.mark.parametrize(
    "scene, kv, fragment",
    [
        ("catenary.toml", {}, "fixed"),
    ],
)
def test_cowell_orbit_refused_where_there_is_no_frame(scene, kv, fragment):
    sc = tetherlab.load_scene(SCENES / scene).replace(**{"integrator.formulation": "cowell-orbit", **kv})
    with pytest.raises(SceneError, match="integrator.formulation") as exc:
        prepare(sc)
    assert fragment in str(exc.value)


def _relative_accelerations(prep):
    """d''_g - W x (W x d_g) of every rod at the start (W: the start's rigid rotation)."""
    y = prep.y0
    h = y.size // 2
    W = np.cross(y[:3], y[h : h + 3]) / float(y[:3] @ y[:3])
    d = y[3:h].reshape(-1, 3)
    acc = cowell_rhs_py(prep.model, y)[h + 3 :].reshape(-1, 3)
    return acc - np.cross(W, np.cross(W, d))


def test_quasi_static_start_is_at_rest_in_the_turning_frame():
    """Every rod's relative acceleration vanishes under every effect (the electrodynamic force
    too).  Scale: the electrodynamic acceleration of a rod, I B L_rod / m_rod = 2 A x 3e-5 T x
    1250 m / 3.8 kg = 2e-2 m/s^2, and the tidal one 3 W^2 L = 1.5e-2 m/s^2; the solve's floor is
    round-off of 8 m/s^2 gravity (1e-15 relative) through the reaction solve: bound 1e-8 m/s^2."""
    qs = prepare(_deorbit())
    assert np.max(np.abs(_relative_accelerations(qs))) < 1e-8
    # negative control: the straight relative equilibrium of the conservative effects is not at
    # rest under the current (the transient that rang the lateral modes: docs/integrators.md 9)
    eq = prepare(_deorbit(**{"orbit.motion": "equilibrium"}))
    assert np.max(np.abs(_relative_accelerations(eq))) > 1e-4


def test_quasi_static_bows_the_tether_along_the_electrodynamic_force():
    """The current flows up the tether and I L x B points against the velocity on this prograde
    orbit (the scene's comment, docs/effects-electrodynamic.md section 2): the tether, which alone
    carries the force, bows backwards from the chord between its end masses."""
    prep = prepare(_deorbit(**{"tethers.main.rods": 8}))
    y = prep.y0
    h = y.size // 2
    d = y[3:h].reshape(-1, 3)
    joints = np.cumsum(2 * np.sqrt(3) * d, axis=0)  # joint positions from the root body
    chord = joints[-1] / np.linalg.norm(joints[-1])
    mid = joints[3]  # the joint at the middle (after 4 of 8 rods)
    off = mid - (mid @ chord) * chord
    vhat = y[h : h + 3] / np.linalg.norm(y[h : h + 3])
    assert off @ vhat < -1.0  # metres: the bow is several metres (8.6 m measured at n = 16)


def test_quasi_static_equals_equilibrium_without_nonconservative_forces():
    """With no current the quasi-static solve has nothing to add to the relative equilibrium of a
    vertical tether (paper section 4.3): the same rods to the solve's 1e-10 of their length."""
    kv = {"effects.electrodynamic.current": "0 A"}
    a = prepare(_deorbit(**kv))
    b = prepare(_deorbit(**kv, **{"orbit.motion": "equilibrium"}))
    h = a.y0.size // 2
    np.testing.assert_allclose(a.y0[3:h], b.y0[3:h], rtol=0, atol=1e-10 * 400)


def test_reanchored_frame_agrees_with_the_inertial_run_and_keeps_every_output():
    """Re-anchoring (pipeline.ANCHOR_ORBITS) restarts the run in a new frame every few orbits:
    with anchors every 0.2 orbits the outputs are the same times and states as the inertial run's
    (budget as in the test above, over 0.15 d)."""
    import tetherlab.pipeline as pl

    kv = {"duration": "0.15 d", "output.step": "600 s", "integrator.rtol": 1e-10, "integrator.atol": 1e-10}
    _, a = _run(_deorbit(**kv, **{"integrator.formulation": "cowell"}))
    old = pl.ANCHOR_ORBITS
    pl.ANCHOR_ORBITS = 0.2
    try:
        _, b = _run(_deorbit(**kv, **{"integrator.formulation": "cowell-orbit"}))
    finally:
        pl.ANCHOR_ORBITS = old
    assert len(b.stats["frame_anchors"]) >= 10
    np.testing.assert_array_equal(a.t, b.t)
    h = a.y.shape[1] // 2
    assert np.max(np.abs(a.y[:, :h] - b.y[:, :h])) < 1e-2
    assert np.max(np.abs(a.y[:, h:] - b.y[:, h:])) < 1e-5
