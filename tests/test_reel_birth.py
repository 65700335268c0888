"""The quasi-static birth (scene key ``tethers.NAME.reel.birth = "quasi-static"``; docs/deployment.md 6.4).

* the new joint's offset is the quadratic's through the exit and the next two joints: on a line
  that is a parabola it lands on the parabola (perpendicular to the chord);
* a birth on a bent, spinning free-space line keeps the mass, momentum and angular momentum to
  round-off and changes the energy by less than the budget of docs/deployment.md 6.4; the same
  birth without the restore misses the momentum by far more than round-off;
* a run with quasi-static births keeps the free-space momentum across them to round-off.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tetherlab import diagnostics as D
from tetherlab.deployment import _rows, quasi_static_birth_state, quasi_static_offset, simulate_reel
from tetherlab.errors import SceneError
from tetherlab.pipeline import prepare
from tetherlab.scene import Scene

from .helpers import import_study

EPS = np.finfo(float).eps
SQ3 = math.sqrt(3.0)
_STUDY = import_study("deployment")
RHO = 0.01  # kg/m, free_scene's line
EA = 2e3  # N, free_scene's line


def _quasi_scene(**kw):
    """The verify study's free-space deployment (studies/deployment.py free_scene) with quasi-static births."""
    d = _STUDY.free_scene(**kw).to_dict()
    d["tethers"]["main"]["reel"]["birth"] = "quasi-static"
    return Scene.from_dict(d)


def _invariants(model, t, y):
    """(P, H, E, K, V_elastic) of one state: the columns the deployment reports (tetherlab/deployment.py)."""
    out, d, _ = _rows(model, np.array([t]), y[None, :])
    g = d["global"][0]
    P = g[D.G_PX : D.G_PZ + 1] + out[0, 0, 9:12]
    H = g[D.G_HX : D.G_HZ + 1] + out[0, 0, 12:15]
    K = g[D.G_KE] + out[0, 0, 15]
    return P, H, g[D.G_E] + out[0, 0, 15], K, g[D.G_VE]


@pytest.fixture(scope="module")
def bent_birth():
    """A birth at t = 25 s (first rod at its bound, 100 m = 50 m new first rod + 50 m full rod),
    the line bent (rods 0 and 1 rotated sideways) and moving (the first rod bending and stretching)."""
    scene = _quasi_scene()
    first = prepare(scene)
    old = prepare(scene, reel_phase={"first": first, "rods": {"main": (3, 200.0)}})
    new = prepare(scene, reel_phase={"first": first, "rods": {"main": (4, 200.0)}})
    lo = old.model.state
    y = np.zeros(lo.size)  # the station at rest at the origin
    # the chords of 100, 50, 50 m (strain 1e-3) bent by 0.1 rad and -0.05 rad in the x-y plane
    for g, (l, ang) in enumerate(((100.0, 0.1), (50.0, -0.05), (50.0, 0.0))):
        y[lo.rod(g)] = l * 1.001 * np.array([math.cos(ang), math.sin(ang), 0.0]) / (2 * SQ3)
    y[lo.rod_rate(0)] = np.array([2.0, 0.6, 0.05]) / (2 * SQ3)  # pay-out and a sideways swing
    y[lo.rod_rate(1)] = np.array([0.0, 0.3, -0.02]) / (2 * SQ3)
    y[lo.rod_rate(2)] = np.array([0.0, 0.5, 0.0]) / (2 * SQ3)
    return old, new, y


def test_offset_lands_on_a_parabola():
    # joints on r(s) = (s, c s^2, 0) at s = 0 (exit), l = 100 m (B) and l + l2 = 150 m (C): the
    # quadratic through them is the parabola itself (an exact interpolation), so the new joint at
    # s = la = 50 m goes to the parabola's point, less its component along the chord AB
    c = 1e-3
    r = lambda s: np.array([s, c * s * s, 0.0])  # noqa: E731
    scene = _quasi_scene()
    first = prepare(scene)
    old = prepare(scene, reel_phase={"first": first, "rods": {"main": (3, 200.0)}})
    lo = old.model.state
    y = np.zeros(lo.size)
    y[lo.rod(0)] = (r(100.0) - r(0.0)) / (2 * SQ3)
    y[lo.rod(1)] = (r(150.0) - r(100.0)) / (2 * SQ3)
    delta, ddelta = quasi_static_offset(y, lo, 0, 100.0, 50.0, 50.0, 0.0)
    u = (r(100.0) - r(0.0)) / np.linalg.norm(r(100.0) - r(0.0))
    want = r(50.0) - (r(0.0) + 0.5 * (r(100.0) - r(0.0)))  # the parabola's sag at the middle: c l^2/4 = 2.5 m
    want = want - (want @ u) * u
    assert np.abs(delta - want).max() <= 1e-12 * np.linalg.norm(want)
    assert np.linalg.norm(want) > 2.0
    assert np.abs(ddelta).max() == 0.0  # a line at rest


def _roundoff(K, M, R):
    """Round-off bounds of P and H (docs/deployment.md 6.3): 100 eps sqrt(2 M K), times R for H."""
    return 100 * EPS * math.sqrt(2 * M * K), 100 * EPS * R * math.sqrt(2 * M * K)


def test_quasi_static_birth_keeps_momenta_and_its_energy_budget(bent_birth):
    old, new, y = bent_birth
    t = 25.0
    z, info = quasi_static_birth_state(old.model, new.model, y, 0, 100.0, 50.0, 50.0, 2.0, t, RHO)
    P0, H0, E0, K0, V0 = _invariants(old.model, t, y)
    P1, H1, E1, K1, V1 = _invariants(new.model, t, z)
    M = 110.0 + RHO * (200.0 + 2000.0 - 200.0)  # bodies, deployed and stored line (free_scene)
    R = 200.0
    bp, bh = _roundoff(max(K0, K1), M, R)
    assert np.abs(P1 - P0).max() <= bp, (P1 - P0, bp)
    assert np.abs(H1 - H0).max() <= bh, (H1 - H0, bh)
    assert new.model.rod_lengths().tolist() == [50.0, 50.0, 50.0, 50.0]  # the mass is where it was
    # the joint moved: a bent line's quasi-static place is off the chord
    delta, dv = info["delta_m"], info["delta_rate_m_s"]
    assert np.linalg.norm(delta) > 0.1
    # the budget of docs/deployment.md 6.4 (6.4c): elastic, second order in delta (delta is
    # perpendicular to the chord), and kinetic, first order against the motion relative to the
    # rigid motion (bounded by the kinetic energy in the centre-of-mass frame)
    k2 = 2 * SQ3
    D = k2 * y[old.model.state.rod(0)]
    eps = np.linalg.norm(D) / 100.0 - 1.0
    Da, Db = 0.5 * np.linalg.norm(D), 0.5 * np.linalg.norm(D)
    d2 = float(delta @ delta)
    elastic = sum(EA * eps * d2 / (2 * Di) + EA * d2 * d2 / (8 * Di * Di * li) for Di, li in ((Da, 50.0), (Db, 50.0)))
    dv_max = float(np.linalg.norm(dv)) + (2.0 / 50.0) * math.sqrt(d2)  # joint, and the exit's w = l'/la D_a
    m_r = RHO * 100.0
    k_cm = K0 - float(P0 @ P0) / (2 * M)
    kinetic = math.sqrt(2 * k_cm * m_r) * dv_max + 0.5 * m_r * dv_max**2
    budget = elastic + kinetic + 100 * EPS * (K0 + abs(V0))
    dE = E1 - E0
    assert abs(dE) <= budget, (dE, elastic, kinetic)
    assert abs(dE) > 1e3 * 100 * EPS * K0  # the change is real, not round-off: the budget is not idle


def test_quasi_static_birth_without_the_restore_misses_the_momenta(bent_birth):
    old, new, y = bent_birth
    t = 25.0
    z, _ = quasi_static_birth_state(old.model, new.model, y, 0, 100.0, 50.0, 50.0, 2.0, t, RHO, restore_momenta=False)
    P0, H0, _, K0, _ = _invariants(old.model, t, y)
    P1, H1, _, _, _ = _invariants(new.model, t, z)
    bp, bh = _roundoff(K0, 110.0 + RHO * 2000.0, 200.0)
    assert np.abs(P1 - P0).max() > 1e6 * bp
    assert np.abs(H1 - H0).max() > 1e6 * bh


def test_run_with_quasi_static_births_keeps_momentum():
    run = simulate_reel(_quasi_scene())
    assert [c["change"] for c in run.changes] == ["birth"] * 5
    P = _STUDY.vectors(run.invariants, "momentum")
    steps = sum(ph.stats["n_accepted"] for ph in run.phases)
    budget = 10.0 * steps * EPS * (110.0 * 3.0 + 10.0 * 2.5)  # tests/test_reel.py's linear-invariant budget
    assert float(np.abs(P - P[0]).max()) <= budget


def test_bad_birth_kind_names_the_key():
    d = _STUDY.free_scene().to_dict()
    d["tethers"]["main"]["reel"]["birth"] = "curved"
    with pytest.raises(SceneError, match=r"tethers\.main\.reel\.birth"):
        Scene.from_dict(d)
