"""A reaction-wheel scenario as a user writes it: a rigid body in free space, a wheel spun up in
rpm, its motor switched off at 5 s by a torque table with a jump.

What is checked, and the source of every expected value:

* angular rates in the field's units ("500 rpm", "500 rev/min", "2 rev/s", "3 deg/s", "1 rad/s")
  wherever one is read: 1 rev = 2 pi rad (the definition), so 500 rpm = 500 * 2 pi / 60 rad/s;
* free space: an empty [effects] table runs; a missing one says that an empty table means none;
  the default attitude and rate (both relative to an orbit frame free space lacks) are named
  together in one error;
* a torque table with a jump: the wheel speed against the closed form of docs/model.md 12.2
  (L = J_s,z w_z + h = h(0) about the axis; h' = tau(t)), within a budget in rad/s; the steps
  land on the jump (no rejected step), and without the breakpoint (the negative control) the
  same run rejects steps;
* the wheel limits as located events: entered and left at the times of the closed form;
* each rigid body's own rotational angular momentum R (J_s w + sum a h) as its own columns:
  constant in free space, and equal to the total angular momentum when the body is alone at rest
  at the origin (no orbital part).
"""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

from tetherlab.errors import SceneError
from tetherlab.pipeline import prepare, simulate
from tetherlab.scene import Scene

USER_SCENE = """
name = "wheel-off-at-5s"
duration = "10 s"

[effects]

[bodies.sat]
mass = "100 kg"
position = ["0 m", "0 m", "0 m"]
velocity = ["0 m/s", "0 m/s", "0 m/s"]

[bodies.sat.rigid]
inertia = { xx = "10 kg m2", yy = "12 kg m2", zz = "14 kg m2" }
attitude = { quaternion = [1.0, 0.0, 0.0, 0.0] }
angular_velocity = { vector = ["0 rad/s", "0 rad/s", "0 rad/s"], frame = "body" }

[bodies.sat.wheels.w1]
axis = [0.0, 0.0, 1.0]
inertia = "0.1 kg m2"
speed = "500 rpm"
torque = { times = ["0 s", "5 s", "5 s", "10 s"], values = ["0.1 N m", "0.1 N m", "0 N m", "0 N m"] }

[integrator]
method = "dop853"
rtol = 1e-10
atol = 1e-10

[output]
step = "0.5 s"
"""

I_W = 0.1  # kg m2, the wheel's axial inertia
J_SZ = 14.0 - I_W  # kg m2, J_s = J_B - I a a^T about z (docs/model.md 12.2)
OMEGA0 = 500.0 * 2.0 * math.pi / 60.0  # rad/s: 500 rpm, 1 rev = 2 pi rad
# Error budget of the wheel speed: the speed is h/I - w_z ~ 52 rad/s; the integrators keep the
# state to rtol ~ 1e-10 relative per unit time over 10 s of polynomial motion (exact for the
# methods' order, so only round-off remains: ~50 ulps of 52 rad/s = 3e-13 rad/s).  Taken: 1e-12.
SPEED_TOL_RAD_S = 1e-12


def user_dict() -> dict:
    return tomllib.loads(USER_SCENE)


def scene_of(d: dict) -> Scene:
    return Scene.from_dict(d)


def closed_form_speed(t: np.ndarray, torque) -> np.ndarray:
    """Wheel speed relative to the body about z: h(t) = h0 + int tau, w_z = (h0 - h)/J_s,z
    (angular momentum about z conserved, the body at rest at t = 0), Omega = h/I - w_z."""
    h0 = I_W * OMEGA0
    h = h0 + torque(t)
    return h / I_W - (h0 - h) / J_SZ


@pytest.mark.parametrize("text", ["500 rpm", "500 rev/min", "8.333333333333334 rev/s", "3000 deg/s"])
def test_wheel_speed_in_the_fields_units(text):
    d = user_dict()
    d["bodies"]["sat"]["wheels"]["w1"]["speed"] = text
    w = scene_of(d).body("sat").rigid.wheels[0]
    # 500 rpm = 500 rev/min = 500/60 rev/s = 3000 deg/s (1 rev = 360 deg = 2 pi rad)
    assert w.speed_rad_s == pytest.approx(OMEGA0, rel=4 * np.finfo(float).eps)


def test_angular_rates_everywhere_they_are_read():
    d = user_dict()
    d["bodies"]["sat"]["rigid"]["angular_velocity"]["vector"] = ["1 rpm", "2 rev/s", "3 deg/s"]
    d["bodies"]["sat"]["wheels"]["w1"]["max_speed"] = "6000 rpm"
    rig = scene_of(d).body("sat").rigid
    assert rig.angular_velocity_rad_s == pytest.approx((2 * math.pi / 60, 4 * math.pi, math.radians(3)), rel=1e-15)
    assert rig.wheels[0].max_speed_rad_s == pytest.approx(6000 * 2 * math.pi / 60, rel=1e-15)
    # round trip through the scene's SI form
    again = Scene.from_dict(scene_of(d).to_dict())
    assert again.body("sat").rigid == rig


@pytest.mark.parametrize("bad,why", [("500 Hz", "dimension frequency"), ("500", "missing unit"), ("5 m/s", "speed")])
def test_angular_rate_errors_list_the_accepted_units(bad, why):
    d = user_dict()
    d["bodies"]["sat"]["wheels"]["w1"]["speed"] = bad
    with pytest.raises(SceneError) as e:
        scene_of(d)
    assert e.value.key == "bodies.sat.wheels.w1.speed"
    assert "rpm" in str(e.value) and "rev/s" in str(e.value) and why in str(e.value)


def test_free_space_missing_effects_says_empty_means_none():
    d = user_dict()
    del d["effects"]
    with pytest.raises(SceneError) as e:
        scene_of(d)
    assert e.value.key == "effects" and "empty table" in str(e.value) and "free space" in str(e.value)


def test_free_space_default_attitude_and_rate_in_one_error():
    d = user_dict()
    del d["bodies"]["sat"]["rigid"]["attitude"]
    del d["bodies"]["sat"]["rigid"]["angular_velocity"]
    with pytest.raises(SceneError) as e:
        prepare(scene_of(d))
    text = str(e.value)
    assert "bodies.sat.rigid.attitude" in text and "bodies.sat.rigid.angular_velocity" in text
    # one key alone is named alone
    d = user_dict()
    del d["bodies"]["sat"]["rigid"]["attitude"]
    with pytest.raises(SceneError) as e:
        prepare(scene_of(d))
    assert "bodies.sat.rigid.attitude" in str(e.value) and "angular_velocity" not in str(e.value)


@pytest.mark.parametrize(
    "times,msg",
    [(["0 s", "5 s", "4 s"], "non-decreasing"), (["0 s", "5 s", "5 s", "5 s"], "at most twice"),
     (["0 s", "0 s", "5 s"], "first time")],
)
def test_table_times_bad(times, msg):
    d = user_dict()
    d["bodies"]["sat"]["wheels"]["w1"]["torque"] = {"times": times, "values": ["0.1 N m"] * len(times)}
    with pytest.raises(SceneError) as e:
        scene_of(d)
    assert e.value.key == "bodies.sat.wheels.w1.torque.times" and msg in str(e.value)


def _off_at_5(t):
    return np.where(t <= 5.0, 0.1 * t, 0.5)  # int_0^t tau: 0.1 N m for 5 s, then 0


@pytest.mark.parametrize("method", ["dop853", "vern9", "radau5"])
def test_motor_switched_off_at_5s(method):
    d = user_dict()
    d["integrator"]["method"] = method
    r = simulate(scene_of(d), progress=False)
    t = r.timeseries["t_s"].to_numpy()
    err = np.abs(r.timeseries["sat.w1.speed_rad_s"].to_numpy() - closed_form_speed(t, _off_at_5))
    assert err.max() <= SPEED_TOL_RAD_S, err.max()
    # the steps land on the jump: nothing to reject (a ramp cost 24-39 rejected steps)
    assert r.stats["n_rejected"] == 0


def test_without_the_breakpoint_the_jump_is_straddled():
    """Negative control: the same scene integrated with no breakpoint rejects steps at the jump
    and misses the closed form by far more than the budget."""
    from tetherlab.integrators.driver import integrate
    from tetherlab.pipeline import cowell_rhs

    prep = prepare(scene_of(user_dict()))
    p = prep.model.fresh_params()
    res = integrate("dop853", cowell_rhs, 0.0, prep.y0, prep.t_out, p, prep.rtol, prep.atol, second_order=prep.model.state.n_qt)
    ix = prep.model.wheel_index[(0, "w1")]
    speed = res.y[:, ix] / I_W - res.y[:, prep.model.rigid_index[0] + 6]
    err = np.abs(speed - closed_form_speed(res.t, _off_at_5))
    assert res.stats["n_rejected"] > 0
    assert err.max() > 10 * SPEED_TOL_RAD_S


def test_scipy_backend_lands_on_the_jump():
    d = user_dict()
    d["integrator"]["method"] = "scipy:DOP853"
    r = simulate(scene_of(d), progress=False)
    t = r.timeseries["t_s"].to_numpy()
    err = np.abs(r.timeseries["sat.w1.speed_rad_s"].to_numpy() - closed_form_speed(t, _off_at_5))
    # scipy's DOP853 at rtol 1e-10: the same round-off level as the native one (budget above)
    assert err.max() <= SPEED_TOL_RAD_S, err.max()


# ---- limits as located events ----------------------------------------------------------------
#: max_torque 0.1 N m, max_speed 5 rad/s, command 0.02 t N m up to 10 s then falling 0.04 N m/s
MAXT = 0.1
MAXW = 5.0
K_OMEGA = 1.0 / I_W + 1.0 / J_SZ  # Omega = h (1/I + 1/J_s,z) with h(0) = 0, body at rest
H_MAXW = MAXW / K_OMEGA  # the momentum at which the speed limit is reached
# closed form of the event times (command tau_c(t) = 0.02 t to 10 s, 0.2 - 0.04 (t - 10) after):
T_ENTER_TORQUE = MAXT / 0.02  # 5 s: |tau_c| = max_torque
T_ENTER_SPEED = 5.0 + (H_MAXW - 0.01 * 25.0) / MAXT  # h = 0.01 t^2 to 5 s (0.25), then 0.1 N m
T_LEAVE_TORQUE = 10.0 + (0.2 - MAXT) / 0.04  # 12.5 s
T_LEAVE_SPEED = 10.0 + 0.2 / 0.04  # 15 s: the command turns negative, the cut-off releases
T_ENTER_TORQUE_2 = 10.0 + (0.2 + MAXT) / 0.04  # 17.5 s
# Budget of an event time: the bisection brackets to 64 eps max(t, h) ~ 3e-13 s; the state's error
# (rtol 1e-10 on h ~ 0.5 N m s: 5e-11) over the switching function's slope (>= 0.02 N m/s, or
# dOmega/dt = 0.1 K / s for the speed) moves the root by < 3e-9 s.  Taken: 1e-8 s.
EVENT_TOL_S = 1e-8


def _limits_dict():
    d = user_dict()
    d["duration"] = "20 s"
    # a step never spans two switches of one limit (12.5 s and 17.5 s) while nothing moves: at
    # most 1 s (docs/integrators.md section 14)
    d["integrator"]["max_step"] = "1 s"
    w = d["bodies"]["sat"]["wheels"]["w1"]
    w["speed"] = "0 rad/s"
    w["max_torque"] = f"{MAXT} N m"
    w["max_speed"] = f"{MAXW} rad/s"
    w["torque"] = {"times": ["0 s", "10 s", "20 s"], "values": ["0 N m", "0.2 N m", "-0.2 N m"]}
    return d


def test_wheel_limits_are_located_events():
    r = simulate(scene_of(_limits_dict()), progress=False)
    ev = r.events
    got = list(zip(ev["event"], ev["side"]))
    assert got == [
        ("wheel.sat.w1.max_torque", "entered"),
        ("wheel.sat.w1.max_speed", "entered"),
        ("wheel.sat.w1.max_torque", "left"),
        ("wheel.sat.w1.max_speed", "left"),
        ("wheel.sat.w1.max_torque", "entered"),
    ], got
    expected = [T_ENTER_TORQUE, T_ENTER_SPEED, T_LEAVE_TORQUE, T_LEAVE_SPEED, T_ENTER_TORQUE_2]
    assert np.max(np.abs(ev["t_s"].to_numpy() - expected)) <= EVENT_TOL_S
    # between the speed limit's entry and release the wheel holds its speed (the motor is cut)
    ts = r.timeseries
    held = (ts["t_s"] > T_ENTER_SPEED + 0.1) & (ts["t_s"] < T_LEAVE_SPEED - 0.1)
    assert held.sum() > 5
    assert np.max(np.abs(ts.loc[held, "sat.w1.speed_rad_s"] - MAXW)) <= 1e-9
    assert r.stats["n_rejected"] <= 2


def test_wheel_limits_unlocated_are_not_reported():
    """Negative control: with the limit events off (H_EV_WHEELS = 0) nothing is reported, so the
    check above would fail on a run that does not locate them."""
    from tetherlab.integrators.driver import integrate
    from tetherlab.model.params import ParamView
    from tetherlab.pipeline import cowell_rhs

    prep = prepare(scene_of(_limits_dict()))
    p = prep.model.fresh_params()
    ParamView(p).wheel_limit_events = 0
    res = integrate("dop853", cowell_rhs, 0.0, prep.y0, prep.t_out, p, prep.rtol, prep.atol,
                    second_order=prep.model.state.n_qt, breaks=prep.breaks_s)  # fmt: skip
    assert res.events == ()
    assert len(prep.event_names) == 2  # the scene's own components: located in simulate()


def test_rotational_angular_momentum_columns():
    r = simulate(scene_of(user_dict()), progress=False)
    dg = r.diagnostics
    L = dg[[f"sat.angmom_rot_{a}_kg_m2_s" for a in "xyz"]].to_numpy()
    # about z: J_s w_z + h = h(0) = I * 500 rpm (docs/model.md 12.2); no torque from outside
    # Budget: h' = tau and J_s w_z' = -tau are integrated as one linear combination; what remains is
    # the rounding of J_s w + h (a few ulps of h0 = 5.2 N m s per step, 20 steps): 1e-12 N m s.
    h0 = I_W * OMEGA0
    assert np.max(np.abs(L[:, 2] - h0)) <= 1e-12
    assert np.max(np.abs(L[:, :2])) == 0.0
    # alone at rest at the origin, the body's own angular momentum is the total (no m r x v)
    H = dg[[f"angmom_{a}_kg_m2_s" for a in "xyz"]].to_numpy()
    assert np.max(np.abs(H - L)) <= 1e-12


def test_controller_torque_limit_events_agree_with_the_applied_torque():
    """Under the PD controller the command depends on the whole state: the events (located on
    the dense output, the branch held between them) must bracket exactly the output rows where
    the applied torque sits at its limit (the diagnostics evaluate the limit afresh at each row)."""
    from tetherlab.scene import load_scene

    from .helpers import SCENES

    scene = load_scene(SCENES / "rigid-wheels-control.toml").replace(
        **{"bodies.sat.wheels.wy.max_torque": "0.02 N m", "duration": "200 s", "output.step": "0.5 s"})  # fmt: skip
    r = simulate(scene, progress=False)
    ev = r.events[r.events["event"] == "wheel.sat.wy.max_torque"]
    assert len(ev) >= 4
    tq = r.diagnostics["sat.wy.torque_N_m"].to_numpy()
    t = r.diagnostics["t_s"].to_numpy()
    at_limit = np.abs(tq) == 0.02
    inside = np.full(t.size, bool(at_limit[0]))  # saturated from the start or not
    for te, side in zip(ev["t_s"], ev["side"]):
        inside[t > te] = side == "entered"
    near = np.min(np.abs(t[:, None] - ev["t_s"].to_numpy()[None, :]), axis=1) < 1e-6
    assert np.array_equal(at_limit[~near], inside[~near])


def test_speed_limit_under_the_controller_holds_without_chattering():
    """A controlled wheel driven into its speed limit: once cut, the wheel keeps its momentum and
    its speed relative to the body follows the body's rate, dipping below the limit while the
    controller still pushes; the cut holds until the command turns round (bodies/wheels.py::
    limit_events), so the run neither chatters nor stalls, and the diagnostics, evaluated with the
    branches the run held, show the torque that was integrated: zero while cut."""
    from tetherlab.scene import load_scene

    from .helpers import SCENES

    scene = load_scene(SCENES / "rigid-wheels-control.toml").replace(
        **{"bodies.sat.wheels.wy.max_speed": "2 rad/s", "duration": "400 s", "output.step": "0.5 s"})  # fmt: skip
    r = simulate(scene, progress=False)
    # Work bound: deciding the cut at every evaluation took 527 accepted (and 705 rejected) steps
    # per simulated second on this scene (main at cf292e0, 3000 s); the tether's own dynamics need
    # about 5 (the scene without limits: 28 798 steps over 6000 s).  20 per second leaves room.
    assert r.stats["n_accepted"] < 20 * 400
    ev = r.events[r.events["event"] == "wheel.sat.wy.max_speed"]
    assert list(ev["side"][:3]) == ["entered", "left", "entered"]
    t = r.diagnostics["t_s"].to_numpy()
    cut = np.zeros(t.size, bool)
    for te, side in zip(ev["t_s"], ev["side"]):
        cut[t > te] = side == "entered"
    near = np.min(np.abs(t[:, None] - ev["t_s"].to_numpy()[None, :]), axis=1) < 1e-6
    sat = r.diagnostics["sat.wy.saturated"].to_numpy()
    tq = r.diagnostics["sat.wy.torque_N_m"].to_numpy()
    assert np.all(sat[cut & ~near] == 2.0) and np.all(tq[cut & ~near] == 0.0)
    assert np.all(sat[~cut & ~near] != 2.0)
    # while cut the wheel's momentum is frozen (h' = tau = 0, docs/model.md 12.2): constant over
    # each cut span to round-off (a few ulps of h = I (Omega + a.w) ~ 0.6 N m s: 1e-14 N m s)
    h = r.timeseries["sat.wy.momentum_N_m_s"].to_numpy()
    starts = np.flatnonzero(np.diff(cut.astype(int)) == 1) + 1
    for a in starts:
        b = a
        while b < t.size and cut[b]:
            b += 1
        span = h[a:b][~near[a:b]]
        assert span.size > 0 and np.max(np.abs(span - span[0])) <= 1e-14


def test_diagnostics_without_the_held_branches_disagree():
    """Negative control of the check above: deciding the cut afresh at each output row (no spans)
    misreads the rows where the held wheel's speed has dipped below its limit."""
    from tetherlab import diagnostics as diag
    from tetherlab.pipeline import branch_spans, integrate_prepared
    from tetherlab.scene import load_scene

    from .helpers import SCENES

    scene = load_scene(SCENES / "rigid-wheels-control.toml").replace(
        **{"bodies.sat.wheels.wy.max_speed": "2 rad/s", "duration": "400 s", "output.step": "0.5 s"})  # fmt: skip
    prep = prepare(scene)
    res, _ = integrate_prepared(prep, prep.model.fresh_params())
    held = diag.compute(prep.model, res.t, res.y, branch_spans(prep, res.events))["wheels"][:, 1, 1]
    fresh = diag.compute(prep.model, res.t, res.y)["wheels"][:, 1, 1]
    assert np.sum(held != fresh) > 10
