"""Reels: the rod at the reel, births and retirements, the exit (docs/deployment.md).

Each gate has its threshold from the error budget of docs/deployment.md 8 and a negative control
(a deliberate defect of kernel/layout.py it must fail):

* free space, paying out with a spin: linear momentum of bodies, stored tether and rods conserved
  across births to round-off; the peers' fixed-segment scaling l0 = L/N fails it;
* the same run's angular momentum to the integrator's error;
* a birth keeps mass, momentum, angular momentum and kinetic energy to round-off (no integration);
* the energy balance E + W_exit = const, the exit work integrated on the outputs, against the
  quadrature's own Richardson estimate;
* exponential deployment on a circular orbit (slow): the angle of sin 2 theta = -4c/3 and the
  tension m* Omega^2 l (3 cos^2 theta - c^2) within the budget of docs/deployment.md 7; the strain
  rate without its l' term fails it;
* every bad reel key is a SceneError naming it; a retrieval of the last rod stops with an event.
"""

from __future__ import annotations


import numpy as np
import pytest

from tetherlab.deployment import _rows, birth_state, simulate_reel
from tetherlab.errors import SceneError
from tetherlab.model.params import DEFECT_REEL_FROZEN, DEFECT_REEL_NO_LDOT, DEFECT_REEL_RESCALED
from tetherlab.pipeline import prepare
from tetherlab.scene import Scene

from .helpers import import_study

EPS = np.finfo(float).eps
MU = 3.986004418e14  # m^3/s^2, the scene preset "earth" (tetherlab/scene/data.py)


# the free-space scene and the invariant columns are the verify study's own (studies/deployment.py)
_STUDY = import_study("deployment")
_free_scene = _STUDY.free_scene
_vectors = _STUDY.vectors


def _momentum_budget(run) -> float:
    """Round-off of a linear invariant (docs/deployment.md 8): 10 eps per step of the sum of the
    momenta of the parts (the largest term, m |v| of the end mass and the line, bounds each)."""
    steps = sum(ph.stats["n_accepted"] for ph in run.phases)
    scale = 110.0 * 3.0 + 10.0 * 2.5  # every mass times the largest speed in the run (the line's 2 m/s + spin)
    return 10.0 * steps * EPS * scale


@pytest.fixture(scope="module")
def deployed():
    return simulate_reel(_free_scene())


def test_free_space_momentum_is_conserved_across_births(deployed):
    run = deployed
    assert [c["change"] for c in run.changes] == ["birth"] * 5  # 150 -> 390 m in rods of 50 m
    P = _vectors(run.invariants, "momentum")
    err = float(np.abs(P - P[0]).max())
    assert err <= _momentum_budget(run), (err, _momentum_budget(run))
    # the end mass's 10 kg x 0.5 m/s sideways and the line leaving at 2 m/s: nothing trivial
    assert abs(P[0, 0]) > 20.0 and abs(P[0, 1]) > 5.0


def test_peers_fixed_segment_scaling_fails_the_momentum_gate():
    # the same run with N = 3 rods of L/3 each, mass appearing in place (docs/deployment.md 1)
    run = simulate_reel(_free_scene(birth="10 km"), defect=DEFECT_REEL_RESCALED)
    P = _vectors(run.invariants, "momentum")
    err = float(np.abs(P - P[0]).max())
    assert err > 1e6 * _momentum_budget(run), err


def test_free_space_angular_momentum_spinning(deployed):
    H = _vectors(deployed.invariants, "angmom")
    h0 = float(np.linalg.norm(H[0]))
    assert h0 > 700.0  # 750 kg m^2/s of spin (the fixture's docstring) less the body's share
    rtol = 1e-11  # the scene's
    assert float(np.abs(H - H[0]).max()) <= 100.0 * rtol * h0


def test_birth_keeps_mass_momentum_and_energy_to_round_off():
    scene = _free_scene()
    first = prepare(scene)
    y = first.y0.copy()
    lay = first.model.state
    y[lay.rod_rate(0)] += np.array([0.01, 0.03, -0.02])  # a first rod bending and stretching
    t = 25.0  # the first rod is at its birth bound 75 m (L = 150 + 2 t; two full rods of 50 m)
    old = prepare(scene, reel_phase={"first": first, "rods": {"main": (3, 200.0)}})
    new = prepare(scene, reel_phase={"first": first, "rods": {"main": (4, 200.0)}})
    z = birth_state(old.model.state, new.model.state, y, 0, 100.0, 50.0, 2.0)
    a, da, _ = _rows(old.model, np.array([t]), y[None, :])
    b, db, _ = _rows(new.model, np.array([t]), z[None, :])
    from tetherlab import diagnostics as D

    for cols, corr in ((slice(D.G_PX, D.G_PZ + 1), slice(9, 12)), (slice(D.G_HX, D.G_HZ + 1), slice(12, 15))):
        before = da["global"][0, cols] + a[0, 0, corr]
        after = db["global"][0, cols] + b[0, 0, corr]
        assert np.abs(after - before).max() <= 1e-12 * np.abs(before).max()
    ke_a = da["global"][0, D.G_KE] + a[0, 0, 15]
    ke_b = db["global"][0, D.G_KE] + b[0, 0, 15]
    assert abs(ke_b - ke_a) <= 1e-12 * ke_a
    assert abs(db["global"][0, D.G_VE] - da["global"][0, D.G_VE]) <= 1e-12 * da["global"][0, D.G_VE] + 1e-300
    assert new.model.rod_lengths().tolist() == [50.0, 50.0, 50.0, 50.0]


def test_the_cut_nominal_defect_cuts_against_the_nominal_rod_only_when_asked():
    # remap_defect "cut-nominal", the control of part G's gates (docs/deployment.md 8c): a first rod
    # of l = 120 m cut at la = 20 m from the reel (rods of 100 m) gets the chord la/(l - la) d = d/5
    # instead of la/l d = d/6; without the argument the cut is exact
    scene = _free_scene()
    first = prepare(scene)
    old = prepare(scene, reel_phase={"first": first, "rods": {"main": (3, 200.0)}})
    new = prepare(scene, reel_phase={"first": first, "rods": {"main": (4, 200.0)}})
    y = first.y0.copy()
    d = y[old.model.state.rod(0)].copy()
    z = birth_state(old.model.state, new.model.state, y, 0, 120.0, 20.0, 2.0, remap_defect="cut-nominal")
    assert np.allclose(z[new.model.state.rod(0)], d / 5.0, rtol=1e-15, atol=0.0)
    z = birth_state(old.model.state, new.model.state, y, 0, 120.0, 20.0, 2.0)
    assert np.allclose(z[new.model.state.rod(0)], d / 6.0, rtol=1e-15, atol=0.0)


def test_the_transport_dropped_defect_gives_the_new_rods_the_affine_field_only_when_asked():
    # remap_defect "transport-dropped", the control of part G's continuum gate (docs/deployment.md
    # 8h): the rates of the cut rod's parts are f dd and (1 - f) dd, the transport term
    # (1 - f) (L'/l) d of 6.1 dropped; without the argument it is there (f = la/l = 1/6 here)
    scene = _free_scene()
    first = prepare(scene)
    old = prepare(scene, reel_phase={"first": first, "rods": {"main": (3, 200.0)}})
    new = prepare(scene, reel_phase={"first": first, "rods": {"main": (4, 200.0)}})
    y = first.y0.copy()
    d, dd = y[old.model.state.rod(0)].copy(), y[old.model.state.rod_rate(0)].copy()
    f = 20.0 / 120.0
    z = birth_state(old.model.state, new.model.state, y, 0, 120.0, 20.0, 2.0, remap_defect="transport-dropped")
    assert np.allclose(z[new.model.state.rod_rate(0)], f * dd, rtol=1e-14, atol=0.0)
    z = birth_state(old.model.state, new.model.state, y, 0, 120.0, 20.0, 2.0)
    assert np.allclose(z[new.model.state.rod_rate(0)], f * dd + (1.0 - f) * (2.0 / 120.0) * d, rtol=1e-14, atol=0.0)


def test_the_cut_nominal_defect_reaches_the_births_of_a_run():
    # simulate_reel threads remap_defect down to the birth: the free scene's first birth (t = 12.5 s,
    # first rod l = 75 m cut at la = 25 m, rods of 50 m) leaves the new first rod at la/(l - la) = 1/2
    # of the chord instead of 1/3, so its strain is l/(l - la) - 1 = 0.5 instead of the line's ~1e-5;
    # the phase before the birth is the same bit for bit
    scene = _free_scene(duration="13 s", count=14)
    run = simulate_reel(scene)
    cut = simulate_reel(scene, remap_defect="cut-nominal")
    assert [c["t_s"] for c in cut.changes] == [c["t_s"] for c in run.changes] == [12.5]
    assert run.phases[0].timeseries.equals(cut.phases[0].timeseries)
    assert abs(float(run.phases[1].timeseries["main.rod1.strain"].iloc[0])) <= 1e-3
    assert abs(float(cut.phases[1].timeseries["main.rod1.strain"].iloc[0]) - 0.5) <= 1e-3


def test_energy_balance_of_the_canister():
    """E + W_exit = const (docs/deployment.md 5.2): the only error is the trapezoid rule of W_exit on
    the outputs, second order in the output step; its Richardson estimate between two spacings is
    the budget (x2), and the finer run must shrink the drift about fourfold."""
    runs = [simulate_reel(_free_scene(count=c)) for c in (241, 481)]
    drift = [float(np.abs(r.invariants["energy_plus_exit_work_J"] - r.invariants["energy_plus_exit_work_J"][0]).max())
             for r in runs]  # fmt: skip
    coarse, fine = (r.invariants.drop_duplicates("t_s").set_index("t_s")["exit_work_J"] for r in runs)
    common = coarse.index.intersection(fine.index)
    assert len(common) >= 240
    # the coarse run's quadrature error at every common time (order 2: (W_h - W_h/2) 4/3), at its largest
    est = float((coarse[common] - fine[common]).abs().max()) * 4.0 / 3.0
    w = [float(r.invariants["exit_work_J"].iloc[-1]) for r in runs]
    assert abs(w[0]) > 1.0  # the exit takes joules out: the balance is not trivially zero
    assert drift[0] <= 2.0 * est + 1e-9 * abs(w[0]), (drift, est)
    assert drift[1] <= drift[0] / 3.0, drift
    # the Carnot loss of the canister is part of it: (1/2) rho L'^3 (1 + eps)^2 ~ 0.04 W over 120 s
    carnot = float(runs[0].reel["carnot_J"].iloc[-1])
    assert 0.04 * 120 * 0.99 < carnot < 0.04 * 120 * 1.01


def test_peers_scaling_fails_the_energy_balance():
    run = simulate_reel(_free_scene(birth="10 km"), defect=DEFECT_REEL_RESCALED)
    inv = run.invariants
    drift = float(np.abs(inv["energy_plus_exit_work_J"] - inv["energy_plus_exit_work_J"][0]).max())
    assert drift > 0.1  # J; the balance above holds to about 1e-3 J on these outputs


def test_drum_and_canister_move_alike_on_a_point_body(deployed):
    drum = simulate_reel(_free_scene(exit_="drum"))
    assert np.array_equal(drum.invariants["momentum_x_N_s"].to_numpy(), deployed.invariants["momentum_x_N_s"].to_numpy())
    assert float(drum.reel["carnot_J"].abs().max()) == 0.0


def test_outputs_of_the_reel(deployed):
    r = deployed.reel
    last = r.iloc[-1]
    assert last["deployed_length_m"] == pytest.approx(150.0 + 2.0 * 120.0, rel=1e-12)
    assert last["stored_length_m"] == pytest.approx(2000.0 - 240.0, rel=1e-12)
    assert int(last["rods"]) == 8
    assert 0.5 * 50.0 <= float(r["rod_length_m"].min()) and float(r["rod_length_m"].max()) <= 1.5 * 50.0 * (1 + 1e-12)
    # the jump rho L'^2 (1 + eps) at 2 m/s and 10 g/m
    assert float(r["exit_jump_N"].iloc[-1]) == pytest.approx(0.04, rel=1e-2)


def test_retrieval_of_the_last_rod_stops_with_an_event():
    scene = _free_scene(speed="-2 m/s", length="100 m", duration="48 s", count=49)  # L(48 s) = 4 m
    run = simulate_reel(scene, raise_on_failure=False)
    assert run.stopped_by == "reel.main.retrieved"
    assert [c["change"] for c in run.changes] == ["retire", "retrieved"]
    # 100 m: a first rod of 50 and one of 50; merged at 12.5 m (t = 18.75 s), last at 12.5 m (t = 43.75 s)
    assert run.changes[0]["t_s"] == pytest.approx(18.75)
    assert run.changes[1]["t_s"] == pytest.approx(43.75)
    assert float(run.reel["t_s"].iloc[-1]) == pytest.approx(43.75)  # every output up to it kept
    assert "retrieved" in run.message


@pytest.fixture(scope="module")
def hauled_in():
    return simulate_reel(_free_scene(speed="-2 m/s", length="300 m", duration="140 s", count=141))


def test_retirements_keep_momentum_and_angular_momentum_to_round_off(hauled_in):
    """Hauling in 300 m at 2 m/s with the spin: five retirements.  Each merge is followed by the
    rigid velocity increment that restores P and H (docs/deployment.md 6.3): their jumps across
    the merges are round-off of one remap (the verify study's bounds), linear momentum over the run
    the round-off budget of the free-space gate, angular momentum the integrator's error."""
    run = hauled_in
    assert [c["change"] for c in run.changes] == ["retire"] * 5
    P = _vectors(run.invariants, "momentum")
    assert float(np.abs(P - P[0]).max()) <= _momentum_budget(run)
    jp_bound, jh_bound = _STUDY.remap_bounds(run, _STUDY.total_mass_kg(300.0))
    assert _STUDY.remap_jumps(run.invariants, "momentum") <= jp_bound
    assert _STUDY.remap_jumps(run.invariants, "angmom") <= jh_bound
    H = _vectors(run.invariants, "angmom")
    h0 = float(np.linalg.norm(H[0]))
    assert h0 > 1000.0  # 10 kg x 300 m x 0.5 m/s of spin, less the body's share: nothing trivial
    assert float(np.abs(H - H[0]).max()) <= 100.0 * _STUDY.FREE_RTOL * h0


def test_retirement_restoring_momentum_alone_fails_the_angular_momentum_gate(hauled_in):
    """The negative control: the merge of docs/deployment.md 6.2 alone (B's velocity changed so
    that P is kept) changes H at every merge, far beyond the round-off bound."""
    scene = _free_scene(speed="-2 m/s", length="300 m", duration="140 s", count=141)
    lin = simulate_reel(scene, remap_defect="linear-only")
    assert [c["change"] for c in lin.changes] == ["retire"] * 5
    _, jh_bound = _STUDY.remap_bounds(lin, _STUDY.total_mass_kg(300.0))
    assert _STUDY.remap_jumps(lin.invariants, "angmom") > 1e6 * jh_bound


def test_restore_gives_momenta_back_with_a_rigid_increment(hauled_in):
    """momentum_remap.restore on a state whose velocities were disturbed: P and H come back to
    round-off, and the change is rigid (every rod's rate changes by omega x d)."""
    from tetherlab.momentum_remap import centre_of_mass, momenta, restore

    scene = _free_scene(speed="-2 m/s", length="300 m", duration="140 s", count=141)
    first = prepare(scene)
    y = first.y0.copy()
    lay = first.model.state
    target = momenta(first.model, 0.0, y[None, :])[0]
    c0, _ = centre_of_mass(first.model, 0.0, y)
    z = y.copy()
    z[lay.rod_rate(0)] += np.array([0.02, -0.05, 0.01])  # one rod's rate off: P and H both change
    assert np.abs(momenta(first.model, 0.0, z[None, :])[0] - target).max() > 1e-3
    w, info = restore(first.model, 0.0, z, target, c0)
    got = momenta(first.model, 0.0, w[None, :])[0]
    scale = float(np.abs(target).max())
    assert np.abs(got - target).max() <= 100 * EPS * scale
    for g in range(lay.n_rods):
        assert np.allclose(w[lay.rod_rate(g)] - z[lay.rod_rate(g)], np.cross(info["omega"], z[lay.rod(g)]),
                           rtol=0, atol=1e-15 * 300)  # fmt: skip


def test_restore_refuses_a_non_finite_state():
    from tetherlab.momentum_remap import restore

    first = prepare(_free_scene())
    y = first.y0.copy()
    y[first.model.state.rod_rate(0)] = np.nan
    with pytest.raises(ValueError, match="non-finite"):
        restore(first.model, 0.0, y, np.zeros(6), np.zeros(3))


def test_remap_defect_is_checked():
    with pytest.raises(ValueError, match="remap_defect: expected None or one of 'linear-only', 'cut-nominal', 'transport-dropped'; "
                                         "got 'nonsense'"):
        simulate_reel(_free_scene(), remap_defect="nonsense")


def _table_scene(times, lengths, duration="120 s"):
    data = _free_scene(duration=duration).to_dict()
    reel = data["tethers"]["main"]["reel"]
    reel.pop("speed")
    reel.update(law="table", times=times, lengths=lengths)
    return Scene.from_dict(data)


def test_table_law_out_and_back_keeps_momentum():
    """A table out to 270 m and back to 200 m (a natural cubic spline through the points): births
    then a retirement, linear momentum to round-off across all of them, L on the spline."""
    from scipy.interpolate import CubicSpline

    times, lengths = [0.0, 60.0, 120.0], [150.0, 270.0, 200.0]
    scene = _table_scene([f"{x} s" for x in times], [f"{x} m" for x in lengths])
    run = simulate_reel(scene)
    kinds = [c["change"] for c in run.changes]
    assert "birth" in kinds and "retire" in kinds, kinds
    P = _vectors(run.invariants, "momentum")
    assert float(np.abs(P - P[0]).max()) <= _momentum_budget(run)
    spline = CubicSpline(times, lengths, bc_type="natural")  # the law's definition (docs/scenes.md)
    r = run.reel
    assert np.abs(r["deployed_length_m"] - spline(r["t_s"])).max() <= 1e-9 * 300.0
    assert np.abs(r["speed_m_s"] - spline(r["t_s"], 1)).max() <= 1e-9 * 3.0


BAD_REELS = [
    ({"rod_length": "0 m"}, "tethers.main.reel.rod_length"),
    ({"rod_length": "-5 m"}, "tethers.main.reel.rod_length"),
    ({"retire_length": "0 m"}, "tethers.main.reel.retire_length"),
    ({"retire_length": "-1 m"}, "tethers.main.reel.retire_length"),
    ({"birth_length": "-10 m"}, "tethers.main.reel.birth_length"),
    ({"birth_length": "0 m"}, "tethers.main.reel.birth_length"),
    ({"birth_length": "60 m"}, "tethers.main.reel.birth_length"),  # 60 < 12.5 + 50: no hysteresis
    ({"retire_length": "200 m", "birth_length": "400 m"}, "tethers.main.reel.retire_length"),  # below one rod
    ({"law": "spiral"}, "tethers.main.reel.law"),
    ({"exit": "bucket"}, "tethers.main.reel.exit"),
    ({"at": "to"}, "tethers.main.reel.at"),
    ({"speed": "2 kg"}, "tethers.main.reel.speed"),
    ({"stored_length": "-1 m"}, "tethers.main.reel.stored_length"),
    ({"law": "exponential"}, "tethers.main.reel.rate"),  # the exponential law without its rate
    ({"spool": "1 kg m2"}, "tethers.main.reel.spool"),
    ({"law": "table", "times": ["0 s", "0 s"], "lengths": ["150 m", "200 m"]}, "tethers.main.reel.times"),
    ({"law": "table", "times": ["0 s", "60 s"], "lengths": ["100 m", "200 m"]}, "tethers.main.reel.lengths"),
    ({"law": "table", "times": ["0 s", "60 s"], "lengths": ["150 m"]}, "tethers.main.reel.lengths"),
    ({"law": "table", "lengths": ["150 m", "200 m"]}, "tethers.main.reel.times"),
]


@pytest.mark.parametrize("change,key", BAD_REELS)
def test_bad_reel_keys_name_the_key(change, key):
    data = _free_scene().to_dict()
    data["tethers"]["main"]["reel"].update(change)
    if change.get("law") in ("exponential", "table"):
        data["tethers"]["main"]["reel"].pop("speed")
    with pytest.raises(SceneError) as err:
        Scene.from_dict(data)
    assert err.value.key == key


def test_speed_law_that_makes_the_length_negative_is_refused():
    with pytest.raises(SceneError) as err:
        simulate_reel(_free_scene(speed="-3 m/s", duration="60 s"))  # L = 150 - 3 t < 0 from 50 s
    assert err.value.key == "tethers.main.reel.speed"


def test_table_that_ends_before_the_run_is_refused():
    with pytest.raises(SceneError) as err:
        simulate_reel(_table_scene(["0 s", "60 s"], ["150 m", "200 m"]))  # the run lasts 120 s
    assert err.value.key == "tethers.main.reel.times"


def test_law_beyond_the_stored_tether_is_refused():
    with pytest.raises(SceneError) as err:
        simulate_reel(_free_scene(speed="20 m/s", duration="120 s"))  # 2.4 km out of 2 km stored
    assert err.value.key == "tethers.main.reel.stored_length"


def test_reel_at_the_end_that_is_not_the_attachment():
    data = _free_scene().to_dict()
    data["tethers"]["main"]["from"], data["tethers"]["main"]["to"] = "mf", "m0"
    data["bodies"]["m0"]["fixed"] = True  # m0 is the root, so the tether written from mf hangs mf from m0
    data["bodies"]["m0"].pop("velocity")
    with pytest.raises(SceneError) as err:
        Scene.from_dict(data)
    assert err.value.key == "tethers.main.reel"


# -- exponential deployment and slow retrieval (docs/deployment.md 7): the scenes and the error
# measures are the verify study's own (studies/deployment.py), so the tests and the report check
# the same runs ------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def study():
    return _STUDY


@pytest.mark.slow
def test_exponential_deployment_angle_and_tension(study):
    scene, om, theta, m_red = study.exponential_scene()
    run = simulate_reel(scene)
    th_ratio, t_ratio, _curves = study.exponential_errors(run, om, theta, m_red)
    assert len(run.changes) == 6  # 2 km -> 12.4 km in rods of 2 km
    assert th_ratio <= 1.0, th_ratio
    assert t_ratio <= 1.0, t_ratio


@pytest.mark.slow
def test_strain_rate_without_its_ldot_term_fails_the_deployment_gate(study):
    scene, om, theta, m_red = study.exponential_scene()
    run = simulate_reel(scene, defect=DEFECT_REEL_NO_LDOT, raise_on_failure=False)
    if run.ok:  # the damping brakes the line with D c Omega ~ 0.4 N against a tension of 3 to 19 mN
        _th_ratio, t_ratio, _curves = study.exponential_errors(run, om, theta, m_red)
        assert t_ratio > 10.0


@pytest.mark.slow
def test_slow_retrieval_amplitude_grows_as_one_over_length(study):
    """Retrieval at l'/l = -0.02 Omega: the libration's action ~ m* l^2 A^2 sqrt3 Omega is an
    adiabatic invariant, so A l stays A0 l0.  Budget: the adiabatic parameter |c|/sqrt3 = 0.012
    (the invariant's oscillating error is of that order), the amplitude's nonlinearity A^2/8 =
    0.003 at 9 deg, the field beyond the gravity gradient 4 l/a = 0.006 (section 7): 0.021."""
    ratio, L, run = study.retrieval_run()
    assert run.ok, run.message
    assert [c["change"] for c in run.changes] == ["retire", "retire"]
    assert len(ratio) >= 15 and L[-1] < 0.6e4  # every half libration from 10 km down to 5.6 km
    assert np.abs(ratio - 1.0).max() <= 0.021, ratio


@pytest.mark.slow
def test_a_reel_whose_law_the_kernel_ignores_fails_the_retrieval_gate(study):
    ratio, _, _ = study.retrieval_run(defect=DEFECT_REEL_FROZEN)
    assert np.abs(ratio - 1.0).max() > 0.1


def test_structured_newton_matrix_takes_the_reel_rod_at_its_own_time():
    """RADAU5 forms the structured matrix at a state and time of its own (mid-step), not at the
    last rhs call; the rod at the reel must then have its length at that time (newton.form_blocks)
    or its strain, and the geometric stiffness made of it, are off by l' dt/l.  A_q of the
    structured matrix against central differences of the rhs at that time: they agree to what the
    matrix leaves out by design (the apparent load's kappa m and the exit's flux, ~rho l'^2/l
    against EA/l: below 1e-4 of the largest entry here); the blocks formed with the length of the
    last rhs call (5 s earlier, 10 m of 50 m) miss by tens of per cent."""
    from tetherlab.formulations.cowell import cowell_rhs
    from tetherlab.tether import newton as nw

    from .helpers import call_cfunc, dense_newton_A

    first = prepare(_free_scene())
    model, y = first.model, first.y0.copy()
    p = model.fresh_params()
    m1 = y.size // 2
    t1, t2 = 0.0, 5.0

    def rhs(t, yy):
        st, out = call_cfunc(cowell_rhs, t, yy, p)
        assert st == 0
        return out

    J = np.empty((m1, m1))
    for j in range(m1):
        d = 1e-6 * max(1.0, abs(y[j]))
        yp, ym = y.copy(), y.copy()
        yp[j] += d
        ym[j] -= d
        J[:, j] = (rhs(t2, yp)[m1:] - rhs(t2, ym)[m1:]) / (2 * d)
    blk, _, _ = nw.workspace(p)
    rhs(t1, y)  # the last rhs call at another time, as in a step
    assert nw.form_blocks(t2, y, p, m1, blk) == 0
    aq, _ = dense_newton_A(p, blk, m1)
    scale = float(np.abs(J).max())
    assert float(np.abs(aq - J).max()) <= 1e-4 * scale
    rhs(t1, y)
    assert nw.rod_blocks(y, p, m1, blk) == 0  # the negative control: the reel rod of t1
    stale, _ = dense_newton_A(p, blk, m1)
    assert float(np.abs(stale - J).max()) > 0.05 * scale
