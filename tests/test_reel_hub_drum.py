"""A drum under a spool law on a rigid hub, and hauling in through a canister (docs/deployment.md 9.7-9.8).

The hub is part H's (studies/deployment_hub.py): spinning at 0.05 rad/s, a free wheel, paying out
from 150 m at 2 m/s, here from a drum of J = 0.5 kg m^2 on R = 0.3 m (axis z, the ring of the turns
on the same radius) under the spool law, against a brake (0.01 N m) or driven by a motor (-0.3 N m),
with a viscous friction of 0.5 N s/m, for 60 s.  In free space the total angular momentum, the
drum's own spin J (L'/R) a included, is an invariant of the flow: its drift is bounded by the
integrator's error, 100 rtol |H(0)| (part H's bound); the energy balance (10.3) with the drum's and
its turns' kinetic energy closes to the Richardson estimate of its two works' quadrature (the bound
of tests/test_reel_spool.py).  The old model (DEFECT_HUB_DRUM_NO_SPIN: the drum's spin out of the
hub's balance and the hub's alpha out of the spool's) fails both by orders of magnitude.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tetherlab import mutants
from tetherlab.deployment import simulate_reel
from tetherlab.errors import SceneError
from tetherlab.scene import Scene

from .helpers import import_study

_HUB = import_study("deployment_hub")
_LAWS = import_study("reel_laws")
RTOL = _HUB.HUB_RTOL


def drum_data(torque="0.01 N m", duration="60 s", count=121):
    data = _HUB.hub_scene(duration=duration, count=count).to_dict()
    data["tethers"]["main"]["reel"].update({
        "law": "spool", "exit": "drum", "speed": "2 m/s", "drum_radius": "0.3 m", "spool_axis": [0, 0, 1],
        "spool_inertia": "0.5 kg m2", "torque": torque, "viscous_friction": "0.5 N s/m"})  # fmt: skip
    return data


def _measure(run):
    """(|H - H0| max / (100 rtol |H0|), (10.3) drift / (2 est + 100 rtol max|E|))."""
    H = _HUB._vec(run.invariants, "H")
    h_ratio = float(np.abs(H - H[0]).max()) / (100.0 * RTOL * float(np.linalg.norm(H[0])))
    total, est = _LAWS.spool_energy(run)
    scale = float(np.abs(run.invariants["energy_J"]).max())
    e_ratio = float(np.abs(total - total[0]).max()) / (2.0 * est + 100.0 * RTOL * scale)
    return h_ratio, e_ratio


@pytest.mark.slow
@pytest.mark.parametrize("torque", ["0.01 N m", "-0.3 N m"], ids=["brake", "motor"])
def test_drum_spool_law_on_a_rigid_hub_keeps_angular_momentum_and_energy(torque):
    run = simulate_reel(Scene.from_dict(drum_data(torque)), progress=False)
    assert run.ok, run.message
    h_ratio, e_ratio = _measure(run)
    # measured (docs/deployment.md 9.7): H 6.5e-6 (brake) and 2.5e-5 (motor) of the bound; energy ~0.5
    assert h_ratio <= 1.0, h_ratio
    assert e_ratio <= 1.0, e_ratio
    # the drum is really exercised: the spool's balance sets L' (the brake or motor against the line)
    assert abs(float(run.reel["speed_m_s"].iloc[-1]) - 2.0) > 0.2


@pytest.mark.slow
def test_the_old_model_without_the_drums_spin_fails_both():
    with mutants.active("hub_drum_no_spin"):
        run = simulate_reel(Scene.from_dict(drum_data()), progress=False)
    assert run.ok, run.message
    h_ratio, e_ratio = _measure(run)
    # measured: |H - H0| 1.7 kg m^2/s (1.4e5 of the bound), (10.3) 0.71 J (34x)
    assert h_ratio > 1e3, h_ratio
    assert e_ratio > 5.0, e_ratio


def test_a_drum_whose_ring_is_not_at_its_rim_is_refused_naming_the_key():
    data = drum_data()
    data["tethers"]["main"]["reel"]["spool_radius"] = "0.5 m"
    with pytest.raises(SceneError) as err:
        Scene.from_dict(data)
    assert err.value.key == "tethers.main.reel.spool_radius"
    assert "drum_radius" in str(err.value) and "0.3" in str(err.value)


def haul_in_data(torque="30 N m", duration="20 s", count=401):
    """Part H's hub as a point mass (210 kg with its end mass) hauling 150 m of 10 g/m in through a
    canister from 2 m/s under a motor of 30 N m on 0.3 m (100 N against the 10 kg end mass), viscous
    friction 2 N s/m."""
    data = _HUB.hub_scene(duration=duration, count=count).to_dict()
    r = data["tethers"]["main"]["reel"]
    for key in ("point", "exit_direction", "spool_radius"):
        r.pop(key)
    data["tethers"]["main"].pop("from_point", None)
    data["bodies"]["hub"].pop("rigid")
    data["bodies"]["hub"].pop("wheels")
    r.update({"law": "spool", "speed": "-2 m/s", "drum_radius": "0.3 m", "torque": torque, "viscous_friction": "2 N s/m"})
    return data


def test_canister_haul_in_feels_no_jump_on_the_line_and_loses_the_carnot_energy():
    # docs/deployment.md 9.8: hauling in, the heap stops the material, so the spool's balance
    # (m_s = 0) is T = F_b with no rho L'^2 term, and the exit's own loss (10.3) is the impact's,
    # (1/2) rho |L'|^3 (1 + eps)^2 + L' eps (T - EA eps/2) (docs 9.8), not a gain
    run = simulate_reel(Scene.from_dict(haul_in_data()), progress=False)
    assert run.ok, run.message
    r = run.reel
    ld = r["speed_m_s"].to_numpy()
    # hauled in fast: the jump rho L'^2 > 1 N (the elastic line with its end mass also springs
    # back out at times: those rows are paid out and keep the pay-out's balance)
    assert ld.min() < -10.0 and (ld < 0.0).sum() > 100
    fb = r["torque_N_m"].to_numpy() / 0.3 + r["friction_N"].to_numpy() + r["speed_brake_N"].to_numpy()
    T = r["exit_tension_N"].to_numpy()
    j = np.where(ld > 0.0, _HUB.RHO_KG_M * ld * r["exit_speed_m_s"].to_numpy(), 0.0)  # rho L'^2 (1 + eps) paying out
    # the balance to round-off of its largest term (1e3 eps_mach |T|, as part M's balance bound)
    assert np.abs(T - j - fb).max() <= 1e3 * np.finfo(float).eps * np.abs(T).max(), np.abs(T - j - fb).max()
    # the rho L'^2 the old balance put on the line: what the body still feels (section 4)
    jump = r["exit_jump_N"].to_numpy()
    assert jump.max() > 1.0
    assert float(r["exit_loss_J"].iloc[-1]) > 0.0
    total, est = _LAWS.spool_energy(run)
    scale = float(np.abs(run.invariants["energy_J"]).max())
    assert float(np.abs(total - total[0]).max()) <= 2.0 * est + 100.0 * RTOL * scale
