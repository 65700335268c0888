"""RADAU5's Newton iteration at its round-off floor (docs/integrators.md section 12).

A tether of many short stiff rods at a tight tolerance: the simplified Newton increments of the
rod velocities cannot fall below the rounding of the elastic forces (EA eps / m_rod per rod,
~1e-9 m/s^2 at n = 256), which in tolerance units grows like n^2 / rtol^(2/3).  Before the fix the
iteration stalled there (rate ~0.7-0.99), every stall counted as a Newton failure and halved the
step, and a smaller step does not lower the floor: the run was trapped in steps of milliseconds
(libration, n = 64, rtol 1e-13: 23,478 steps and 23,159 Newton failures over 63.4 s, against 83
steps and none with the fix).  An increment within FLOOR_GAIN of the measured floor is now taken
as converged.

Negative control: the same run with the floor test switched off (workspace slot _F_FLOOR = 0)
must be trapped again.  Accuracy: the floor-accepted run agrees with the trapped one (which took
steps 300 times shorter, every Newton iteration run to its floor) within an error budget of
10 rtol times the tether length.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tetherlab import pipeline
from tetherlab.formulations.cowell import cowell_rhs
from tetherlab.integrators import driver, radau5
from tetherlab.scene import load_scene
from tetherlab.tether.newton_solver import choose

SCENE = Path(__file__).resolve().parents[1] / "studies" / "scenes" / "libration-inplane.toml"
RODS = 64
RTOL = 1e-13
T_END_S = 63.4


@pytest.fixture(scope="module")
def prepared():
    scene = load_scene(SCENE).replace(**{
        "orbit.motion": "equilibrium", "duration": "0.1 orbits", "output.count": 3,
        "integrator.method": "radau5", "integrator.rtol": RTOL, "integrator.atol": RTOL,
        "tethers.main.rods": RODS,
    })  # fmt: skip
    return pipeline.prepare(scene)


def _run(prep, gain, monkeypatch, max_steps=10**6):
    def workspace(*args, **kw):
        ws = radau5.radau5_workspace(*args, **kw)
        ws[radau5.WS_FLOATS][radau5._F_FLOOR] = gain
        return ws

    monkeypatch.setattr(driver, "radau5_workspace", workspace)
    p = prep.model.fresh_params()
    return driver.integrate("radau5", cowell_rhs, 0.0, prep.y0, np.array([0.0, T_END_S]), p, prep.rtol,
                            prep.atol, second_order=True, max_steps=max_steps,
                            newton=choose(p, prep.y0.size, True))  # fmt: skip


def test_default_workspace_enables_the_floor_test():
    assert radau5.radau5_workspace(4, 2)[radau5.WS_FLOATS][radau5._F_FLOOR] == radau5.FLOOR_GAIN > 0.0


def test_stalled_newton_at_round_off_is_not_a_failure(prepared, monkeypatch):
    res = _run(prepared, radau5.FLOOR_GAIN, monkeypatch)
    assert res.status == 0, res.message
    # 83 steps measured; an untrapped run needs about one step per 0.8 s of this scene
    assert res.stats["n_accepted"] <= 300
    assert res.stats["n_newton_fail"] <= 5


def test_negative_control_without_the_floor_test_is_trapped(prepared, monkeypatch):
    # 23,478 steps measured over the whole interval; 3000 steps must not get there
    res = _run(prepared, 0.0, monkeypatch, max_steps=3000)
    assert res.status != 0
    assert res.t[-1] < 0.5 * T_END_S
    assert res.stats["n_newton_fail"] > 1000


@pytest.mark.slow
def test_floor_accepted_run_agrees_with_the_trapped_one(prepared, monkeypatch):
    fast = _run(prepared, radau5.FLOOR_GAIN, monkeypatch)
    slow = _run(prepared, 0.0, monkeypatch)
    assert fast.status == 0 and slow.status == 0
    h = prepared.y0.size // 2
    length_m = float(np.linalg.norm(prepared.y0[3:h].reshape(-1, 3), axis=1).sum()) * 2 * np.sqrt(3.0)
    tip = lambda y: 2 * np.sqrt(3.0) * y[3:h].reshape(-1, 3).sum(axis=0)  # noqa: E731  (root to tip)
    budget_m = 10 * RTOL * length_m
    assert np.max(np.abs(tip(fast.y[-1]) - tip(slow.y[-1]))) < budget_m  # measured 1.4e-9 m
    # the root on its orbit: the tolerance relative to its radius
    assert np.max(np.abs(fast.y[-1][:3] - slow.y[-1][:3])) < 10 * RTOL * np.linalg.norm(prepared.y0[:3])
