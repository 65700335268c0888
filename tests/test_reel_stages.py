"""A tension law in stages (docs/deployment.md 10.6) and the retrieval of a 5 km line to 100 m
with and without it (docs/deployment.md 14).

* the `stages` key: bad input is a SceneError naming the key; the stages survive a round trip
  through the scene's dictionary;
* the staged command is the law's formula with the stage's l_c at every output (the switch ends a
  phase and writes l_c for the next one);
* the constant-speed retrieval's in-plane angle against the rigid-rod variable-length pendulum, and
  a kernel ignoring the law (DEFECT_REEL_FROZEN) failing the same budget
  (tetherlab/oracles/reeled_pendulum.py).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tetherlab.deployment import check_law, simulate_reel, stage_length
from tetherlab.errors import SceneError
from tetherlab.model.params import DEFECT_REEL_FROZEN
from tetherlab.scene import Scene

from .helpers import import_study

_STUDY = import_study("reel_retrieval")
KEY = "tethers.main.reel.stages"

BAD_STAGES = [
    ("2 h", KEY),  # not a list
    ([], KEY),  # empty
    ([{"start": "1 h"}], f"{KEY}[0].commanded_length"),  # missing
    ([{"commanded_length": "1 km"}], f"{KEY}[0].start"),  # missing
    ([{"start": "0 s", "commanded_length": "1 km"}], f"{KEY}[0].start"),  # not after t = 0
    ([{"start": "2 h", "commanded_length": "1 km"}, {"start": "1 h", "commanded_length": "2 km"}], f"{KEY}[1].start"),
    ([{"start": "1 h", "commanded_length": "-1 km"}], f"{KEY}[0].commanded_length"),
    ([{"start": "1 h", "commanded_length": "1 km", "k1": 5}], f"{KEY}[0].k1"),  # unknown key
]


@pytest.mark.parametrize("stages,key", BAD_STAGES)
def test_bad_stages_name_the_key(stages, key):
    data = _STUDY.retrieval_scene(controlled=True).to_dict()
    data["tethers"]["main"]["reel"]["stages"] = stages
    with pytest.raises(SceneError) as err:
        Scene.from_dict(data)
    assert err.value.key == key


def test_stages_only_with_the_tension_law():
    data = _STUDY.retrieval_scene().to_dict()  # the constant law
    data["tethers"]["main"]["reel"]["stages"] = [{"start": "1 h", "commanded_length": "1 km"}]
    with pytest.raises(SceneError) as err:
        Scene.from_dict(data)
    assert err.value.key == KEY


def test_a_stage_after_the_run_is_refused():
    data = _STUDY.retrieval_scene(controlled=True, orbits=1.0).to_dict()
    scene = Scene.from_dict(data)
    with pytest.raises(SceneError) as err:
        check_law(scene, 5000.0)  # the second stage starts at 1.5 orbits (8743 s)
    assert err.value.key == f"{KEY}[1].start"


def test_stages_round_trip_and_their_lengths():
    scene = _STUDY.retrieval_scene(controlled=True)
    again = Scene.from_dict(scene.to_dict())
    sp, sp2 = scene.tethers[0].reel.spool, again.tethers[0].reel.spool
    assert np.allclose(sp2.stages, sp.stages, rtol=1e-12, atol=0.0) and sp2.commanded_length_m == sp.commanded_length_m
    first = sp.stages[0][0]
    assert stage_length(sp, 0.0) == 2500.0  # the scene's commanded_length holds before the first stage
    assert stage_length(sp, first * (1.0 - 1e-6)) == 2500.0
    assert stage_length(sp, first) == 1250.0  # a stage holds from its start
    assert stage_length(sp, 1e9) == 100.0


@pytest.fixture(scope="module")
def staged():
    return simulate_reel(_STUDY.retrieval_scene(controlled=True), progress=False)


def test_staged_command_is_the_law_with_the_stage_length(staged):
    """command_N = m* Omega^2 [3 l_c + k1 (L - l_c) + k2 L'/Omega] with l_c the stage's at every
    output (no limits set), to round-off of the command."""
    c = _STUDY.RETRIEVAL
    om, mred = _STUDY.omega(), _STUDY.reduced_mass()
    sp = _STUDY.retrieval_scene(controlled=True).tethers[0].reel.spool
    r = staged.reel
    starts = {s for s, _ in sp.stages}
    worst = 0.0
    for t, L, v, cmd in zip(r["t_s"], r["deployed_length_m"], r["speed_m_s"], r["command_N"]):
        if any(abs(t - s) < 1e-6 for s in starts):
            continue  # the phase before ends at the start with the old command, the next begins with the new
        lc = stage_length(sp, float(t))
        want = mred * om**2 * (3.0 * lc + c["k1"] * (L - lc) + c["k2"] * v / om)
        worst = max(worst, abs(cmd - want) / abs(want))
    assert worst < 1e-12, worst
    phase_starts = [float(ph.timeseries["t_s"].iloc[0]) for ph in staged.phases]
    for s in starts:  # every stage start ends a phase
        assert min(abs(p - s) for p in phase_starts) < 1e-6 * s


def test_staged_retrieval_reaches_the_last_stage(staged):
    """The staged law hauls 5 km in to within 10 % of l_c = 100 m over 5 orbits, the angle within
    20 deg throughout (measured 103 m and 15.3 deg; the uncontrolled retrieval passes 170 deg)."""
    pr = _STUDY.profile(staged)
    assert abs(pr["L"][-1] - 100.0) < 10.0, pr["L"][-1]
    assert np.abs(pr["theta"]).max() < math.radians(20.0)


def test_uniform_retrieval_against_the_rigid_rod_pendulum():
    """The constant-speed retrieval (1 m/s, 5 km -> 100 m) against theta'' = -(I'/I)(theta' + Omega)
    - 3 Omega^2 sin theta cos theta, I = (m* + rho l/3) l^2, while l >= 500 m (the angle reaches
    87 deg there; below, it passes 100 deg and the line swings through: outside both models).  Budget, relative to the largest
    angle: the line's flexibility, of the order of its mass ratio rho l/m* (0.010 at 5 km; the
    rigid-rod term takes its mean effect), the field beyond the gravity gradient 4 l/a (0.003,
    docs/deployment.md 7), the strain eps (2e-4).  A stated estimate, not a derived bound.
    Measured: 0.44 deg against 1.15 deg (2 s once compiled)."""
    err, budget, oracle = _pendulum_error(simulate_reel(_STUDY.retrieval_scene(), progress=False))
    assert err <= budget, (math.degrees(err), math.degrees(budget))
    assert np.abs(oracle).max() > math.radians(80.0)  # the instability is in the window (87 deg at 500 m)


def test_frozen_law_fails_the_pendulum_comparison():
    """Negative control: a kernel that ignores the law (DEFECT_REEL_FROZEN) keeps the line at
    5 km, its angle near 0 against the pendulum's 87 deg: 87 deg off, 60 times its budget (1.44 deg: the frozen line's strain is larger)."""
    run = simulate_reel(_STUDY.retrieval_scene(), progress=False, defect=DEFECT_REEL_FROZEN, raise_on_failure=False)
    err, budget, _ = _pendulum_error(run)
    assert err > 10.0 * budget, (math.degrees(err), math.degrees(budget))


def _pendulum_error(run):
    """(max |theta - theta_pendulum| over l >= 500 m of the law's length, its budget, the oracle)."""
    c = _STUDY.RETRIEVAL
    pr = _STUDY.profile(run)
    pr["L"] = c["L0"] - c["v"] * pr["t"]  # the law's length: a frozen kernel's table says the same
    keep = pr["L"] >= 500.0
    theta = pr["theta"][keep]
    oracle = _STUDY.oracle_angle(pr["t"][keep])
    eps = float(np.abs(pr["T"][keep]).max()) / c["EA"]
    budget = (c["rho"] * c["L0"] / _STUDY.reduced_mass() + 4.0 * c["L0"] / c["a"] + eps) * float(np.abs(oracle).max())
    return float(np.abs(theta - oracle).max()), budget, oracle


@pytest.mark.slow
def test_yes2_like_runs_both_stages():
    """The YES2-like scene (studies/reel_yes2.py, ~9 s): the first stage holds below the line's
    end, the second starts at its scheduled time and pays the rest of the 31.7 km line out; the
    run stops with the located event reel.main.spent and keeps its outputs (docs/deployment.md 15)."""
    yes2 = import_study("reel_yes2")
    run = simulate_reel(yes2.yes2_scene(), progress=False, raise_on_failure=False)
    assert run.stopped_by == "reel.main.spent", run.message
    pr = yes2.yes2_profile(run)
    start2 = yes2.yes2_scene(count=3).tethers[0].reel.spool.stages[0][0]
    first = pr["t"] < start2
    assert pr["L"][first].max() < 10e3  # the first stage never runs away towards the line's end
    assert pr["t"][-1] > start2 and abs(pr["L"][-1] - yes2.YES2["line"]) < 1.0
